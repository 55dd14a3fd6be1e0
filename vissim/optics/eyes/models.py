"""Schematic eyes as plain data: surface tables, media, stop and retina, each with its source.

Sign convention (as Zemax, optiland and visisipy): light travels along +z from the cornea to the
retina; a radius is positive when its centre of curvature lies behind the surface (towards the
retina), so the cornea's front is +7.72 mm and the lens back and the retina are negative. The conic
constant Q is Zemax's k: the sag is c r²/(1 + √(1 − (1 + Q) c² r²)), Q = 0 a sphere, −1 a
paraboloid. Thicknesses are along the axis from a surface's vertex to the next one's.

Builders: `navarro_1985`, `escudero_sanz_1999`, `arizona`, `le_grand`, `liou_brennan_1997`;
`EYE_MODELS` maps each model's command-line name to its builder and `eye_model` builds one by name.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from vissim.checks import (ARIZONA_ACCOMMODATION_RANGE_DIOPTERS, NAVARRO_ACCOMMODATION_RANGE_DIOPTERS,
                           finite_number, number_within)
from vissim.errors import VissimInputError
from vissim.optics.eyes.dispersion import (AIR, GrinMedium, Medium, arizona_medium, le_grand_medium,
                                      liou_brennan_medium, navarro_medium)

__all__ = ["EyeSurface", "SchematicEye", "SURFACE_KINDS", "navarro_1985", "escudero_sanz_1999", "arizona",
           "le_grand", "liou_brennan_1997", "EYE_MODELS", "eye_model", "LE_GRAND_ACCOMMODATED_DIOPTERS",
           "fixed_accommodation_text"]

#: refracting: an index step; stop: the iris, a plane with no power; grin-boundary: a plane inside
#: a GRIN lens where its polynomial changes (the index is continuous); retina: the image surface.
SURFACE_KINDS = ("refracting", "stop", "grin-boundary", "retina")

@dataclass(frozen=True)
class EyeSurface:
    """One surface: its vertex radius (mm; ``math.inf`` for a plane), conic Q, the axial distance
    to the next surface's vertex (mm) and the medium between them, and its kind (`SURFACE_KINDS`).

    A toric (biconic) surface also has ``radius_y_mm``: then ``radius_mm`` is the radius of its
    section along the TABO meridian ``axis_deg`` (its local x', counter-clockwise from +x, the
    examiner's right, as the examiner faces the eye) and ``radius_y_mm`` that along ``axis_deg``
    + 90° (y'); both sections have the conic Q (Zemax's biconic with Qx = Qy). ``radius_y_mm``
    None (every model's table) is a surface of revolution, and ``axis_deg`` is then unused.
    """

    name: str
    radius_mm: float
    conic: float
    thickness_after_mm: float
    medium_after: Medium | GrinMedium
    kind: str = "refracting"
    radius_y_mm: float | None = None
    axis_deg: float = 0.0

    @property
    def radius_x_mm(self) -> float:
        """The radius along x' (the meridian ``axis_deg``), mm: ``radius_mm``."""
        return self.radius_mm

    @property
    def is_toric(self) -> bool:
        """True when the two principal radii differ."""
        return self.radius_y_mm is not None and self.radius_y_mm != self.radius_mm


@dataclass(frozen=True)
class SchematicEye:
    """A schematic eye: ``surfaces`` from the cornea's front to the retina (the last, kind
    ``retina``), the iris at ``surfaces[stop_index]`` (a plane), in air.

    ``stop_decentre_nasal_mm``: the iris centre's offset from the optical axis towards the nose;
    ``visual_axis_deg``: the angle between the visual and the optical axis in object space
    (angle alpha: the visual axis lies nasal of the optical axis). Both are 0 for centred models.
    The models are right eyes (nasal is +x in OSA's frame). A model with a visual axis has its
    field angles measured from it: field (0, 0) is where it fixates (the rule is applied once, by
    the trace: `vissim.optics.eyes.traced_wavefront.field_from_optical_axis_deg`).
    ``accommodation_diopters`` is the model's own accommodation parameter; ``recalled`` marks a
    table not checked against a stored source.
    """

    name: str
    surfaces: tuple[EyeSurface, ...]
    stop_index: int
    reference_wavelength_nm: float
    source: str
    accommodation_diopters: float = 0.0
    stop_decentre_nasal_mm: float = 0.0
    visual_axis_deg: float = 0.0
    recalled: bool = False

    @property
    def object_medium(self) -> Medium:
        """The medium in front of the cornea: air."""
        return AIR

    @property
    def retina(self) -> EyeSurface:
        """The image surface."""
        return self.surfaces[-1]

    @property
    def retina_radius_mm(self) -> float:
        """The retina's vertex radius, mm (negative: concave towards the light)."""
        return self.retina.radius_mm

    @property
    def axial_length_mm(self) -> float:
        """The corneal front vertex to the retina's vertex, mm."""
        return sum(s.thickness_after_mm for s in self.surfaces[:-1])

    @property
    def stop(self) -> EyeSurface:
        """The iris."""
        return self.surfaces[self.stop_index]


def _accommodation(value, model: str, bounds: tuple[float, float]) -> float:
    return number_within(value, f"{model} accommodation", "dioptres", bounds)


_NAVARRO_SOURCE = ("Navarro, Santamaria & Bescos 1985, JOSA A 2:1273, Tables 1 and 4 (accommodation "
                   "formulas in L = ln(A + 1), as ISET3d navarroLensCreate.m and mb.body.Navarro.m); ")


def _navarro_surfaces(accommodation_diopters: float, vitreous_mm: float, retina_radius_mm: float):
    a = accommodation_diopters
    ln_a = math.log(a + 1.0)
    lens = navarro_medium("lens", 9e-5 * (10.0 * a + a * a))
    aqueous = navarro_medium("aqueous")
    vitreous = navarro_medium("vitreous")
    return (
        EyeSurface("cornea front", 7.72, -0.26, 0.55, navarro_medium("cornea")),
        EyeSurface("cornea back", 6.50, 0.0, 3.05 - 0.05 * ln_a, aqueous),
        EyeSurface("iris", math.inf, 0.0, 0.0, aqueous, "stop"),
        EyeSurface("lens front", 10.2 - 1.75 * ln_a, -3.1316 - 0.34 * ln_a, 4.0 + 0.1 * ln_a, lens),
        EyeSurface("lens back", -6.0 + 0.2294 * ln_a, -1.0 - 0.125 * ln_a, vitreous_mm, vitreous),
        EyeSurface("retina", retina_radius_mm, 0.0, 0.0, vitreous, "retina"),
    )


def navarro_1985(accommodation_diopters: float = 0.0) -> SchematicEye:
    """Navarro's 1985 eye, accommodated by A dioptres (0-10 D) by its Table 4 formulas.

    The vitreous (lens back to retina) stays 16.40 mm at every A, as ISET3d and mb.body.Navarro (whose
    author checked it against the paper's Tables 4 and 5) do, so the axial length grows by
    0.05 ln(A + 1) mm; the paper is not in a stored source, so whether it holds the axial length
    instead is unconfirmed (tests/test_eye_models.py records the refraction either way). The 1985 paper gives
    no retinal curvature; the retina here is Escudero-Sanz & Navarro's −12 mm sphere.
    """
    a = _accommodation(accommodation_diopters, "navarro-1985", NAVARRO_ACCOMMODATION_RANGE_DIOPTERS)
    return SchematicEye("navarro-1985", _navarro_surfaces(a, 16.40, -12.0), 2, 589.3,
                        _NAVARRO_SOURCE + "vitreous 16.40 mm; retina radius from Escudero-Sanz 1999",
                        accommodation_diopters=a)


def escudero_sanz_1999(accommodation_diopters: float = 0.0) -> SchematicEye:
    """Escudero-Sanz & Navarro's 1999 wide-angle eye: Navarro 1985 with a 16.3203 mm vitreous and a
    −12 mm spherical retina (JOSA A 16:1881, Table 1; optiland ``NavarroWideAngleEye``).

    The paper's eye is unaccommodated; A > 0 applies Navarro 1985's formulas (0-10 D) with the
    vitreous fixed, as ISET3d does with its 16.32 mm vitreous.
    """
    a = _accommodation(accommodation_diopters, "escudero-sanz-1999", NAVARRO_ACCOMMODATION_RANGE_DIOPTERS)
    return SchematicEye("escudero-sanz-1999", _navarro_surfaces(a, 16.3203, -12.0), 2, 543.0,
                        "Escudero-Sanz & Navarro 1999, JOSA A 16:1881, Table 1; " + _NAVARRO_SOURCE,
                        accommodation_diopters=a)


def arizona(accommodation_diopters: float = 0.0) -> SchematicEye:
    """The Arizona eye (Schwiegerling 2004) accommodated by A dioptres (0-6 D), as ISET3d's
    ``arizonaLensCreate.m`` (FRED's ArizonaEyeModel.pdf); vitreous 16.713 mm, retina −13.4 mm."""
    a = _accommodation(accommodation_diopters, "arizona", ARIZONA_ACCOMMODATION_RANGE_DIOPTERS)
    aqueous = arizona_medium("aqueous")
    lens = arizona_medium("lens", 1.42 + 0.00256 * a - 0.00022 * a * a)
    vitreous = arizona_medium("vitreous")
    surfaces = (
        EyeSurface("cornea front", 7.8, -0.25, 0.55, arizona_medium("cornea")),
        EyeSurface("cornea back", 6.5, -0.25, 2.97 - 0.04 * a, aqueous),
        EyeSurface("iris", math.inf, 0.0, 0.0, aqueous, "stop"),
        EyeSurface("lens front", 12.0 - 0.4 * a, -7.518749 + 1.285720 * a, 3.767 + 0.04 * a, lens),
        EyeSurface("lens back", -5.224557 + 0.2 * a, -1.353971 - 0.431762 * a, 16.713, vitreous),
        EyeSurface("retina", -13.4, 0.0, 0.0, vitreous, "retina"),
    )
    return SchematicEye("arizona", surfaces, 2, 589.3,
                        "Schwiegerling 2004, Field Guide to Visual and Ophthalmic Optics (SPIE); "
                        "ISET3d arizonaLensCreate.m, vitreous 16.713 mm from ISET3d sceneEye",
                        accommodation_diopters=a)


def le_grand(accommodated: bool = False) -> SchematicEye:
    """Gullstrand–Le Grand's full theoretical eye, relaxed or accommodated (visisipy
    ``catalog/gullstrand.py``; accommodated: ``accommodation_diopters`` `LE_GRAND_ACCOMMODATED_DIOPTERS`,
    ``eye_model("le-grand", 7.05)``); indices with ISET3d's n∞ + K/(λ − 130) dispersion. The iris is at
    the lens front, as visisipy puts it (3.6 mm behind the corneal vertex when relaxed)."""
    aqueous, vitreous = le_grand_medium("aqueous"), le_grand_medium("vitreous")
    if accommodated:  # aqueous 2.65, lens 6.0 / -5.5 x 4.5 mm, n 1.427, vitreous 16.49655
        depth, front, back, thickness, vitreous_mm = 2.65, 6.0, -5.5, 4.5, 16.49655
        lens = le_grand_medium("lens", 1.427 - 1.42)
    else:
        depth, front, back, thickness, vitreous_mm = 3.05, 10.2, -6.0, 4.0, 16.59655
        lens = le_grand_medium("lens")
    surfaces = (
        EyeSurface("cornea front", 7.8, 0.0, 0.55, le_grand_medium("cornea")),
        EyeSurface("cornea back", 6.5, 0.0, depth, aqueous),
        EyeSurface("iris", math.inf, 0.0, 0.0, aqueous, "stop"),
        EyeSurface("lens front", front, 0.0, thickness, lens),
        EyeSurface("lens back", back, 0.0, vitreous_mm, vitreous),
        EyeSurface("retina", -13.4, 0.0, 0.0, vitreous, "retina"),
    )
    return SchematicEye("le-grand", surfaces, 2, 589.3,
                        "Le Grand & El Hage 1980 (Gullstrand-Le Grand); visisipy catalog/gullstrand.py; "
                        "dispersion ISET3d",
                        accommodation_diopters=LE_GRAND_ACCOMMODATED_DIOPTERS if accommodated else 0.0)


_LB_SOURCE = ("Liou & Brennan 1997, JOSA A 14:1684 (abstract: 60.35 D, axial length 23.95 mm). Found in "
              "stored sources: the cornea's radii 7.77 and 6.40 mm (their ratio, named for Liou-Brennan, in a "
              "public Castrop IOL-formula code) and the media's indices at 555 nm, cornea 1.376, aqueous and "
              "vitreous 1.336 (SpikeFinder LiouBrennanRefractiveIndices.cs). RECALLED: the conics, the "
              "thicknesses, the lens radii and the GRIN polynomial are recalled from the paper's Table 1, not "
              "read from a stored copy (they reproduce the abstract's power and axial length); confirm them "
              "against the paper before relying on them")


def liou_brennan_1997() -> SchematicEye:
    """Liou & Brennan's 1997 eye: aspheric cornea and lens, a two-part GRIN lens, the iris at the
    lens front decentred 0.5 mm nasally, the visual axis 5° from the optical axis, nasal (field
    angles are measured from it); partly RECALLED table (``_LB_SOURCE`` says which numbers are found).

    Its dispersion adds the same Δn(λ) to every medium (`dispersion.liou_brennan_shift`), so its LCA is
    small: 0.69 D from 450 to 650 nm against 1.23–1.28 D measured (the formula's own result; the media
    module says why).

    GRIN halves, n at 555 nm, z from each half's front plane, r from the axis (mm):
    front 1.368 + 0.049057z − 0.015427z² − 0.001978r² over 1.59 mm; back 1.407 − 0.006605z² −
    0.001978r² over 2.43 mm. Both equal 1.368 at the lens surfaces and 1.407 at the join.
    """
    aqueous = liou_brennan_medium("aqueous", 1.336)
    vitreous = liou_brennan_medium("vitreous", 1.336)
    front = GrinMedium("lens front half", (1.368, 0.049057, -0.015427), -0.001978, 555.0, source=_LB_SOURCE)
    back = GrinMedium("lens back half", (1.407, 0.0, -0.006605), -0.001978, 555.0, source=_LB_SOURCE)
    surfaces = (
        EyeSurface("cornea front", 7.77, -0.18, 0.50, liou_brennan_medium("cornea", 1.376)),
        EyeSurface("cornea back", 6.40, -0.60, 3.16, aqueous),
        EyeSurface("iris", math.inf, 0.0, 0.0, aqueous, "stop"),
        EyeSurface("lens front", 12.40, -0.94, 1.59, front),
        EyeSurface("lens equator", math.inf, 0.0, 2.43, back, "grin-boundary"),
        EyeSurface("lens back", -8.10, 0.96, 16.27, vitreous),
        EyeSurface("retina", -12.0, 0.0, 0.0, vitreous, "retina"),
    )
    return SchematicEye("liou-brennan-1997", surfaces, 2, 555.0, _LB_SOURCE,
                        stop_decentre_nasal_mm=0.5, visual_axis_deg=5.0, recalled=True)


#: The accommodated Gullstrand–Le Grand eye's accommodation, D, to 0.01 D: the relaxed eye's paraxial
#: refraction at the corneal vertex minus the accommodated eye's, with Le Grand's indices (1.3771,
#: 1.3374, lens 1.42 and 1.427, 1.336; visisipy catalog/gullstrand.py): 7.0525 D. vissim's media at
#: 589.3 nm (ISET3d's dispersion, within 4e-5 of those indices) give 7.058 D. tests/test_eye_models.py
#: recomputes both. ``le-grand`` takes this accommodation, or 0 D, and nothing between: the model has
#: two lenses, not a formula in A.
LE_GRAND_ACCOMMODATED_DIOPTERS = 7.05


def _fixed_accommodation(model: str, builders: dict[float, Callable[[], SchematicEye]]):
    """A builder taking ``accommodation_diopters`` for a model that has eyes at the accommodations
    ``builders``'s keys only (D); any other value is refused, the values it takes named."""
    values = sorted(builders)

    def build(accommodation_diopters: float = 0.0) -> SchematicEye:
        a = finite_number(accommodation_diopters, f"{model} accommodation", "dioptres") + 0.0
        if a not in builders:
            raise VissimInputError(f"{model} takes accommodation {fixed_accommodation_text(model)}, got {a:g} D")
        return builders[a]()

    build.__doc__ = f"{model} at accommodation {' or '.join(f'{v:g}' for v in values)} D only."
    build.accommodations_diopters = tuple(values)
    return build


def fixed_accommodation_text(model: str) -> str:
    """The accommodations a fixed-accommodation model takes, as its refusal names them: ``0 D only``, or
    ``0 D (relaxed) or 7.05 D (its accommodated eye) only``."""
    values = EYE_MODELS[model].accommodations_diopters
    if len(values) == 1:
        return f"{values[0]:g} D only"
    return f"{values[0]:g} D (relaxed) or " + " or ".join(f"{v:g} D (its accommodated eye)" for v in values[1:]) + " only"


#: Command-line model name -> builder taking ``accommodation_diopters``.
EYE_MODELS = {
    "navarro-1985": navarro_1985,
    "escudero-sanz-1999": escudero_sanz_1999,
    "arizona": arizona,
    "le-grand": _fixed_accommodation("le-grand", {0.0: le_grand,
                                                  LE_GRAND_ACCOMMODATED_DIOPTERS: lambda: le_grand(accommodated=True)}),
    "liou-brennan-1997": _fixed_accommodation("liou-brennan-1997", {0.0: liou_brennan_1997}),
}


def register_eye_model(name: str, builder) -> None:
    """Add a model: ``builder(accommodation_diopters)`` returns its `SchematicEye` (refusing accommodations it
    cannot take). Every entry point that takes an eye's name then takes ``name``; a name taken is refused."""
    if name in EYE_MODELS:
        raise VissimInputError(f"an eye model named {name!r} is registered already")
    EYE_MODELS[name] = builder


def eye_model(name: str, accommodation_diopters: float = 0.0) -> SchematicEye:
    """The model ``name`` (a key of `EYE_MODELS`) at ``accommodation_diopters``.

    Liou–Brennan takes 0 D only; Le Grand 0 D (relaxed) or `LE_GRAND_ACCOMMODATED_DIOPTERS` (its
    accommodated eye, `le_grand(accommodated=True)`). An unknown name or an accommodation outside the
    model's range (or not one a fixed-accommodation model has) raises `VissimInputError`.
    """
    if name not in EYE_MODELS:
        raise VissimInputError(f"unknown eye model {name!r}; known: {', '.join(EYE_MODELS)}")
    return EYE_MODELS[name](accommodation_diopters)
