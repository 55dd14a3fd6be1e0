"""The traced wavefront of a schematic eye: one field point, one wavelength, over the entrance pupil.

Steps (`trace_eye_wavefront`):

1. A collimated beam from the field point (x, y) degrees -- the object's direction seen from the
   eye, at (tan x, tan y) in OSA's frame, so the beam travels along (−tan x, −tan y, 1) -- is
   aimed with `aim_collimated` through the cornea onto a regular square grid on the iris (the
   stop; centred on the iris centre, ``stop_decentre_nasal_mm`` towards +x: a right eye), and
   traced on through the lens (the GRIN lens by the ray equation) to the retina
   (`vissim.optics.eyes.surfaces`). Field angles are from the **visual axis** for a model that has
   one (``visual_axis_deg`` > 0: Liou–Brennan's 5°), so that field (0, 0) is the fixation
   direction, and from the optical axis otherwise (`field_from_optical_axis_deg`, `FIELD_AXIS`).
2. The chief ray (through the iris centre) meets the retina at the image point; each ray's OPD is
   taken on the reference sphere about that point through the chief ray's crossing of the
   paraxial exit-pupil plane (`wavefront_on_reference_sphere_um`; OSA sign, W > 0 leads).
3. Each ray is placed at its **entrance-pupil** coordinates: where its incoming line crosses the
   plane of the paraxial entrance pupil (the traced pupil imaging, pupil aberration included).
4. The OSA Zernike fit (`fit_zernike_um`, up to radial order 8 by default) is over the disc of the
   entrance-pupil diameter centred on the chief ray's entrance-pupil point; the grid reaches
   `GRID_MARGIN` times the iris radius so that the disc is covered off axis too, where the
   iris's image grows and shifts (at 40° in ES1999, by up to 13 %). Off axis this disc, in the
   plane normal to the optical axis, is the on-axis pupil's size, not the iris's oblique image.
5. **Slopes to visual angle** (`field_map`): the coefficients' pupil coordinates lie in that plane,
   not in the plane normal to the oblique beam, so a slope of the front is not yet the visual angle it
   sends a ray to. A beam turned by δ from the field point adds the OPD (o(f + δ) − o(f)) · (x, y) over
   the plane (o: `field_direction`), so a slope g is seen at δ = J⁻¹ g, J = ∂(o_x, o_y)/∂(field)
   (1/cos θ tangentially at θ off the axis the pupil plane is normal to; 1.064 at 20°). A PSF of the
   front is in the slopes' angles; `field_map` (J⁻¹) takes it to visual angle
   (`vissim.optics.pupil.spectral_wavefront.SpectralWavefront.field_map`, applied by `vissim.compute_psf`).

Pupils: the entrance pupil (clinicians') or the iris (optical design's) may be given; the other
follows from the real-ray pupil imaging on axis at the trace's wavelength
(`entrance_pupil_from_iris_mm`, `iris_from_entrance_pupil_mm`), and `EyeWavefront.pupil_given`
records which one was. Coefficients are always over the entrance pupil.

A toric cornea (an astigmatic eye, `vissim.optics.eyes.ametropia`) is traced as the biconic it is;
only the paraxial planes the trace is referred to (the entrance and exit pupils, the paraxial
iris that starts the pupil search) are those of its mean meridian (`paraxial.mean_meridian_eye`).

Lenses in front (``lenses``, a `TrialLensSetup` of thick lenses): their surfaces
(`spectacles.lens_surfaces`) are traced before the cornea, the beam starting in front of them.
The iris is the eye's own (a given entrance pupil is the eye's, measured without lenses); the
Zernikes are over the iris's image through the cornea **and** the lenses (real rays on axis, as
without them), at the paraxial entrance pupil of the whole system
(`spectacles.system_entrance_pupil_mm`). For an object at infinity every ray's incoming line is
parallel, so that plane's position moves no ray relative to the chief ray; it only names the
plane the refraction is read at.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vissim.checks import EYE_PUPIL_RANGE_MM, MAX_TRACE_FIELD_DEG, eye_wavelength_nm, positive_number
from vissim.errors import VissimInputError
from vissim.optics.eyes.models import SchematicEye
from vissim.optics.eyes.refraction import ENTRANCE_PUPIL_PLANE
from vissim.optics.eyes.paraxial import (entrance_pupil_position_mm, iris_diameter_mm, matrix_to_surface,
                                         mean_meridian_eye)
from vissim.optics.eyes.spectacles import lens_surfaces, system_entrance_pupil_mm
from vissim.optics.eyes.surfaces import split_at_stop
from vissim.optics.raytrace import RayBundle, aim_collimated, aim_rays, trace_rays, wavefront_on_reference_sphere_um
from vissim.optics.pupil.zernike import fit_zernike_um
from vissim.optics.runtime.threads import map_on_threads, map_shares
from vissim.units import ARCMIN_PER_DEG, image_colrow_to_osa_xy

__all__ = ["EyeWavefront", "trace_eye_wavefront", "field_map", "trace_to_retina", "field_direction", "image_reach_deg", "node_field_deg", "field_of_direction", "field_from_optical_axis_deg", "field_axis",
           "exit_pupil_position_mm", "entrance_pupil_from_iris_mm", "iris_from_entrance_pupil_mm", "max_iris_mm", "pupils_mm",
           "trace_eye_wavefronts", "entrance_pupils_from_irises_mm", "irises_from_entrance_pupil_mm",
           "DEFAULT_SAMPLES", "CHIEF_RAY_SAMPLES", "GRID_MARGIN"]

#: Samples across the iris (odd: the chief ray is the grid's centre) and the grid's reach, in iris radii.
DEFAULT_SAMPLES = 65
GRID_MARGIN = 1.05
#: The iris grid (samples across) of a trace made only for its chief ray and pupil.
CHIEF_RAY_SAMPLES = 17
#: The plane the collimated beam starts on, mm in front of the first surface's vertex.
_START_BEFORE_MM = 5.0
_PUPIL_TOL_MM = 1e-12


def exit_pupil_position_mm(eye: SchematicEye, wavelength_nm: float) -> float:
    """The paraxial exit pupil (the iris imaged by the lens into the vitreous), mm behind the corneal vertex."""
    eye = mean_meridian_eye(eye)
    retina = len(eye.surfaces) - 1
    rest = matrix_to_surface(eye, retina, wavelength_nm) @ np.linalg.inv(matrix_to_surface(eye, eye.stop_index,
                                                                                            wavelength_nm))
    y, nu = rest @ np.array([0.0, 1.0])  # a ray from the iris centre, at the retina's vertex plane
    n_vitreous = eye.surfaces[-2].medium_after.index(wavelength_nm)
    return eye.axial_length_mm - n_vitreous * y / nu


def field_axis(eye: SchematicEye) -> str:
    """The axis field angles are measured from: ``"visual axis"`` for a model with one, else ``"optical axis"``."""
    return "visual axis" if eye.visual_axis_deg != 0.0 else "optical axis"


def node_field_deg(row_px: float, col_px: float, shape: tuple[int, int], arcmin_per_px: float,
                   field_deg=(0.0, 0.0)) -> tuple[float, float]:
    """The field angle (x, y) in degrees, OSA's frame, of image point ``[row_px, col_px]`` of an image of ``shape``
    centred on ``field_deg`` (`vissim.optics.eyes.field_blur`'s module doc): the one map from image pixels to field
    angles (the renderer's sensor draws its film by it too). Numbers give floats; arrays (broadcast) give arrays."""
    centre_row, centre_col = (shape[0] - 1) / 2.0, (shape[1] - 1) / 2.0
    to_deg = arcmin_per_px / ARCMIN_PER_DEG
    dx, dy = image_colrow_to_osa_xy((np.asarray(col_px) - centre_col) * to_deg, (np.asarray(row_px) - centre_row) * to_deg)
    x, y = field_deg[0] + dx, field_deg[1] + dy
    return (float(x), float(y)) if np.ndim(x) == 0 and np.ndim(y) == 0 else (x, y)


def image_reach_deg(eye: SchematicEye, shape: tuple[int, int], arcmin_per_px: float, field_deg) -> float:
    """How far from ``eye``'s optical axis an image of ``shape`` (rows, cols) reaches, deg: the one rule for how wide
    an eye's image may be (`vissim blur`'s check and the renderer's refusal, both against `EYE_RENDER_MAX_THETA_DEG`).

    The widest of the frame's corners (its pixels' outer edges: the film covers them) about the image's field angle
    ``field_deg`` (OSA's x, y), each corner turned to the optical axis by `field_direction`; a corner beyond 89 deg
    along an axis is taken at 89 (the image is refused either way). A frame's widest point is a corner: the
    directions within an angle of an axis project onto the tangent plane as a convex region.
    """
    edges_row, edges_col = np.meshgrid([-0.5, shape[0] - 0.5], [-0.5, shape[1] - 0.5], indexing="ij")
    xs, ys = node_field_deg(edges_row, edges_col, shape, arcmin_per_px, field_deg)
    corners = field_direction(eye, np.clip([xs, ys], -MAX_TRACE_FIELD_DEG, MAX_TRACE_FIELD_DEG))
    return float(np.degrees(np.arccos(np.clip(corners[..., 2].min(), -1.0, 1.0))))


def field_direction(eye: SchematicEye, field_deg) -> np.ndarray:
    """The unit vector from the eye towards the field point, in the eye's (optical-axis) frame: x, y
    OSA's (x the examiner's right, y up), z the axis towards the object.

    The rule, written once: a field angle (x, y) is the direction (tan x, tan y, 1) in the frame of
    the axis `field_axis` names. The visual axis is the optical axis turned by ``visual_axis_deg``
    about y towards +x: the object-space angle alpha with the fixation point **nasal** of the optical
    axis (the fovea temporal of the posterior pole). +x is nasal for a **right eye** in OSA's frame
    (x to the examiner's right), the eye the models' nasal iris decentre already assumes; so the
    fixation direction, field (0, 0), is (+alpha, 0) from the optical axis.

    Vectorised: ``field_deg`` = (x, y) of numbers or of equal-shape arrays; the result has shape (..., 3).
    """
    try:
        fx, fy = (np.asarray(v, dtype=float) for v in field_deg)
    except (TypeError, ValueError):
        raise VissimInputError(f"a field angle must be two numbers (x, y) in deg, got {field_deg!r}") from None
    for value in (fx, fy):
        bad = ~np.isfinite(value) | (np.abs(value) > MAX_TRACE_FIELD_DEG)
        if np.any(bad):
            first = float(np.ravel(value)[np.argmax(np.ravel(bad))])
            raise VissimInputError(f"field angle {first:g} deg is beyond +-{MAX_TRACE_FIELD_DEG:g} deg (90 is grazing)"
                                   if math.isfinite(first) else f"field angle must be finite deg, got {first}")
    tx, ty = np.broadcast_arrays(np.tan(np.radians(fx)), np.tan(np.radians(fy)))
    o = np.stack([tx, ty, np.ones_like(tx)], axis=-1)
    o /= np.linalg.norm(o, axis=-1, keepdims=True)
    alpha = math.radians(eye.visual_axis_deg)
    return np.stack([o[..., 0] * math.cos(alpha) + o[..., 2] * math.sin(alpha), o[..., 1],
                     -o[..., 0] * math.sin(alpha) + o[..., 2] * math.cos(alpha)], axis=-1)


def field_of_direction(eye: SchematicEye, direction) -> np.ndarray:
    """The field angle (x, y) in degrees of the unit vector(s) ``direction`` (..., 3) towards the object, in the
    eye's optical-axis frame with z towards the object: the inverse of
    `field_direction` (the visual axis's turn undone, then (atan x/z, atan y/z))."""
    o = np.asarray(direction, dtype=float)
    alpha = math.radians(eye.visual_axis_deg)
    vx = o[..., 0] * math.cos(alpha) - o[..., 2] * math.sin(alpha)
    vz = o[..., 0] * math.sin(alpha) + o[..., 2] * math.cos(alpha)
    return np.degrees(np.stack([np.arctan2(vx, vz), np.arctan2(o[..., 1], vz)], axis=-1))


def field_from_optical_axis_deg(eye: SchematicEye, field_deg) -> tuple[float, float]:
    """The field angle (x, y), degrees, given from `field_axis`, as angles from the optical axis
    (each the arctangent of its direction's x or y over z); the same angles for a model with no visual axis."""
    o = field_direction(eye, field_deg)
    return math.degrees(math.atan2(o[0], o[2])), math.degrees(math.atan2(o[1], o[2]))


def field_map(eye: SchematicEye, field_deg) -> np.ndarray:
    """The 2 x 2 matrix that takes a wavefront slope over the entrance-pupil plane (x, y; OSA) to the visual
    angle (x, y) it is seen at, both in the same angular unit (module doc, step 5): the inverse of
    ∂(o_x, o_y)/∂(field x, y), o = `field_direction`, differentiated analytically."""
    fx, fy = (math.radians(float(v)) for v in field_deg)
    field_direction(eye, field_deg)  # the same checks
    t = np.array([math.tan(fx), math.tan(fy), 1.0])
    norm = float(np.linalg.norm(t))
    alpha = math.radians(eye.visual_axis_deg)
    columns = []
    for axis, angle in ((0, fx), (1, fy)):
        dt = np.zeros(3)
        dt[axis] = 1.0 / math.cos(angle) ** 2
        du = dt / norm - t * float(t @ dt) / norm ** 3
        columns.append([du[0] * math.cos(alpha) + du[2] * math.sin(alpha), du[1]])
    return np.linalg.inv(np.array(columns).T)


def _beam_direction(eye: SchematicEye, field_deg) -> np.ndarray:
    """The collimated beam's direction of travel (towards +z) from the field point ``field_deg``."""
    o = field_direction(eye, field_deg)
    return np.array([-o[0], -o[1], o[2]])


def _front(eye: SchematicEye, lenses, phase=None) -> tuple[tuple, float, tuple, float]:
    """(surfaces before the iris, lenses first, then the `PhasePlane` ``phase`` if any; the iris z; those after
    it; the beam's start z), mm."""
    front, stop_z, back = split_at_stop(eye)
    lens_part = lens_surfaces(lenses) if lenses is not None and lenses.lenses else ()
    start_z = (lens_part + tuple(front))[0].vertex_z_mm
    return lens_part + (() if phase is None else (phase,)) + tuple(front), stop_z, back, start_z - _START_BEFORE_MM


def _axial_starts(eye: SchematicEye, iris_x_mm, wavelength_nm: float, lenses=None) -> np.ndarray:
    """x (mm) where axial rays that land on the iris at ``iris_x_mm`` (y = 0) enter: their entrance-pupil heights."""
    front, stop_z, _, start_z = _front(eye, lenses)
    targets = np.stack([np.asarray(iris_x_mm, dtype=float), np.zeros(len(iris_x_mm))], axis=1)
    _, starts = aim_collimated(front, [0.0, 0.0, 1.0], targets, stop_z, start_z, wavelength_nm=wavelength_nm)
    return starts[:, 0]


def entrance_pupils_from_irises_mm(eye: SchematicEye, irises_mm, wavelengths_nm, lenses=None) -> np.ndarray:
    """The entrance-pupil diameters (mm) of irises ``irises_mm`` across at ``wavelengths_nm`` (one each, or one for
    all), by real rays on axis (their x extent) through the cornea and, if given, the lenses of the
    `TrialLensSetup` ``lenses``: every rim ray in one trace."""
    irises, waves = np.broadcast_arrays(np.asarray(irises_mm, dtype=float).ravel(),
                                        np.asarray(wavelengths_nm, dtype=float).ravel())
    centre, radius = eye.stop_decentre_nasal_mm, 0.5 * irises
    rim = _axial_starts(eye, np.concatenate([centre + radius, centre - radius]), np.concatenate([waves, waves]),
                        lenses)
    return rim[: len(irises)] - rim[len(irises):]


def entrance_pupil_from_iris_mm(eye: SchematicEye, iris_mm: float, wavelength_nm: float, lenses=None) -> float:
    """The entrance-pupil diameter (mm) of an iris ``iris_mm`` across (`entrance_pupils_from_irises_mm`)."""
    return float(entrance_pupils_from_irises_mm(eye, [iris_mm], [wavelength_nm], lenses)[0])


def irises_from_entrance_pupil_mm(eye: SchematicEye, entrance_pupil_mm: float, wavelengths_nm) -> np.ndarray:
    """The iris diameters (mm) whose real-ray entrance pupil is ``entrance_pupil_mm`` at each of
    ``wavelengths_nm``: the secant method from the paraxial iris, every wavelength's search in one trace a step."""
    waves = np.asarray(wavelengths_nm, dtype=float).ravel()
    d0 = np.array([iris_diameter_mm(mean_meridian_eye(eye), entrance_pupil_mm, w) for w in waves])
    d1 = 1.01 * d0
    f0 = entrance_pupils_from_irises_mm(eye, d0, waves) - entrance_pupil_mm
    irises, active = np.empty(len(waves)), np.arange(len(waves))
    for _ in range(30):
        f1 = entrance_pupils_from_irises_mm(eye, d1, waves[active]) - entrance_pupil_mm
        done = (np.abs(f1) < _PUPIL_TOL_MM) | (f1 == f0)
        irises[active[done]] = d1[done]
        if done.all():
            return irises
        going = ~done
        d0, d1, f0 = d1[going], d1[going] - f1[going] * (d1[going] - d0[going]) / (f1[going] - f0[going]), f1[going]
        active = active[going]
    raise VissimInputError(f"no iris gives a {entrance_pupil_mm:g} mm entrance pupil")  # pragma: no cover


def iris_from_entrance_pupil_mm(eye: SchematicEye, entrance_pupil_mm: float, wavelength_nm: float) -> float:
    """The iris diameter (mm) whose real-ray entrance pupil is ``entrance_pupil_mm`` (`irises_from_entrance_pupil_mm`)."""
    return float(irises_from_entrance_pupil_mm(eye, entrance_pupil_mm, [wavelength_nm])[0])


def max_iris_mm(eye: SchematicEye) -> float:
    """The widest iris the eye holds, mm: twice the radius where the iris plane meets the surface in
    front of it (the anterior chamber's angle, at the cornea's back), by bisection on its sag."""
    front, stop_z, _ = split_at_stop(eye)
    wall = front[-1]
    depth = stop_z - wall.vertex_z_mm
    low, high = 0.0, 1.0
    while high < 1e3 and wall.shape.sag_mm(np.array([high, 0.0])) < depth:
        high *= 2.0
    for _ in range(80):
        mid = 0.5 * (low + high)
        sag = wall.shape.sag_mm(np.array([mid, 0.0]))
        low, high = (mid, high) if sag < depth else (low, mid)  # NaN (beyond the conic's domain): the rim
    return 2.0 * low


def _pupils(eye: SchematicEye, wavelengths_nm: np.ndarray, pupil_mm, iris_mm) -> tuple[np.ndarray, np.ndarray, str]:
    """(entrance pupils, irises, which was given), mm, one each of ``wavelengths_nm``. The iris may open to the top
    of a human eye's `EYE_PUPIL_RANGE_MM` and to `max_iris_mm` of this eye; an entrance pupil is held to the iris it
    needs."""
    if (pupil_mm is None) == (iris_mm is None):
        raise VissimInputError("give either the entrance-pupil diameter (pupil_mm) or the iris diameter (iris_mm), "
                               "not both or neither")
    human = EYE_PUPIL_RANGE_MM[1]
    widest = min(human, max_iris_mm(eye))
    if pupil_mm is not None:
        pupil, given = positive_number(pupil_mm, "entrance pupil diameter", "mm"), "entrance pupil"
        widest_pupil = float(np.min(entrance_pupils_from_irises_mm(eye, widest, wavelengths_nm)))
        if pupil > widest_pupil:  # checked before the search, which a huge pupil would send out of range
            raise VissimInputError(f"entrance pupil {pupil:g} mm, wider than the {widest_pupil:.3g} mm that the "
                                   f"{eye.name} eye's widest iris, {widest:.3g} mm, gives (a human iris opens to "
                                   f"{human:g} mm at most, and to no wider than where the iris plane meets the "
                                   "cornea's back)")
        try:
            irises = irises_from_entrance_pupil_mm(eye, pupil, wavelengths_nm)
        except VissimInputError as error:
            raise VissimInputError(f"entrance pupil {pupil:g} mm: {error}") from None
        asked = f"entrance pupil {pupil:g} mm needs an iris of {float(np.max(irises)):.3f} mm"
        pupils = np.full(len(irises), float(pupil))
    else:
        iris, given = positive_number(iris_mm, "iris diameter", "mm"), "iris"
        irises, asked = np.full(len(wavelengths_nm), float(iris)), f"iris {iris:g} mm"
    if np.max(irises) > widest:
        raise VissimInputError(f"{asked}, wider than the {widest:.3g} mm the {eye.name} eye's iris allows (a human "
                               f"iris opens to {human:g} mm at most, and to no wider than where the iris plane meets "
                               "the cornea's back)")
    if given == "iris":
        pupils = entrance_pupils_from_irises_mm(eye, irises, wavelengths_nm)
        if np.max(pupils) > human:  # the range is the pupil one sees; the cornea magnifies the iris (about 1.13)
            raise VissimInputError(f"{asked} gives a {float(np.max(pupils)):.3g} mm entrance pupil, wider than a human "
                                   f"eye's {human:g} mm: give a smaller iris")
    return pupils, irises, given


def pupils_mm(eye: SchematicEye, wavelength_nm: float, pupil_mm=None, iris_mm=None) -> tuple[float, float]:
    """(entrance pupil, iris), mm, at ``wavelength_nm`` from the one given, within the limits every trace of
    ``eye`` keeps (`_pupils`: the widest iris, a human eye's widest pupil)."""
    pupils, irises, _ = _pupils(eye, np.array([eye_wavelength_nm(wavelength_nm)]), pupil_mm, iris_mm)
    return float(pupils[0]), float(irises[0])


@dataclass(frozen=True, eq=False)
class EyeWavefront:
    """The traced wavefront of ``model`` at ``field_deg`` and ``wavelength_nm`` (module doc).

    ``entrance_pupil_mm`` / ``iris_mm``: the pupil the coefficients are over and the iris that gives
    it; ``pupil_given``: ``"entrance pupil"`` or ``"iris"``. ``x_mm``, ``y_mm``, ``opd_um``: every
    traced ray's entrance-pupil coordinates (relative to the chief ray's) and OPD (µm, OSA sign),
    inside the disc or not. ``zernike_um``: OSA (n, m) -> µm over the entrance pupil, piston and tilt
    included; ``rms_um``: without piston and tilt; ``image_point_mm``: the chief ray on the retina;
    ``chief_entrance_pupil_mm``: where the chief ray crosses the entrance-pupil plane (x, y), the
    disc's centre (on the axis for a centred iris on axis; −0.097 mm in x at 40° in ES1999).
    ``lenses``: the `TrialLensSetup` in front (None: none); with lenses ``entrance_pupil_mm`` and
    ``entrance_pupil_position_mm`` are the whole system's and ``eye_entrance_pupil_mm`` the eye's own.
    ``field_axis``: the axis ``field_deg`` is measured from (`field_axis`). ``field_map``: the 2 x 2 map from
    the front's slopes to visual angle (`field_map`; the identity on the axis of a model without a visual axis).
    ``chief_direction``: the unit vector towards the field point, the chief ray's in object space, in the
    optical-axis frame (`field_direction`; the refraction's pupil is seen along it, `refraction` module doc).
    ``pupil_plane``: the plane the coefficients' pupil lies in: the entrance pupil's (normal to the optical
    axis), or `refraction.BEAM_PLANE` (normal to the chief ray: a measured eye's data).
    """

    model: str
    field_deg: tuple[float, float]
    wavelength_nm: float
    entrance_pupil_mm: float
    iris_mm: float
    pupil_given: str
    entrance_pupil_position_mm: float
    exit_pupil_position_mm: float
    image_point_mm: tuple[float, float, float]
    chief_entrance_pupil_mm: tuple[float, float]
    x_mm: np.ndarray
    y_mm: np.ndarray
    opd_um: np.ndarray
    zernike_um: dict
    fit_residual_rms_um: float
    lenses: object = None
    eye_entrance_pupil_mm: float | None = None
    field_axis: str = "optical axis"
    field_map: tuple = ((1.0, 0.0), (0.0, 1.0))
    chief_direction: tuple = (0.0, 0.0, 1.0)
    pupil_plane: str = ENTRANCE_PUPIL_PLANE

    @property
    def rms_um(self) -> float:
        """RMS wavefront error over the entrance pupil, piston and tilt removed (unit-RMS Zernikes)."""
        return math.sqrt(sum(v * v for (n, _), v in self.zernike_um.items() if n >= 2))

    def inside(self) -> np.ndarray:
        """The rays inside the entrance-pupil disc (those the fit used)."""
        return np.hypot(self.x_mm, self.y_mm) <= 0.5 * self.entrance_pupil_mm * (1.0 + 1e-12)


def _iris_grid(eye: SchematicEye, iris_mm: float, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """The (N, 2) iris targets -- a square grid of step iris / (samples − 1), its points within
    `GRID_MARGIN` iris radii plus two steps, the chief ray (the iris centre) first -- and which of
    them are on the grid's edge (a 4-neighbour missing)."""
    step = iris_mm / (samples - 1)
    # two steps beyond GRID_MARGIN, but never farther (in iris diameters) than the default grid's: a coarse grid's
    # two steps would otherwise reach rays far beyond the iris that miss the cornea of a wide pupil
    reach = GRID_MARGIN / 2 + 2 / (DEFAULT_SAMPLES - 1)
    half = min(math.ceil(GRID_MARGIN * (samples - 1) / 2) + 2, math.ceil(reach * (samples - 1) - 1e-9))
    axis = step * np.arange(-half, half + 1)
    x, y = np.meshgrid(axis, axis[::-1])
    keep = np.hypot(x, y) <= step * (half + 1e-9)
    padded = np.pad(keep, 1)
    edge = keep & ~(padded[:-2, 1:-1] & padded[2:, 1:-1] & padded[1:-1, :-2] & padded[1:-1, 2:])
    keep[half, half] = False
    points = np.concatenate([[[0.0, 0.0]], np.stack([x[keep], y[keep]], axis=1)])
    return points + np.array([eye.stop_decentre_nasal_mm, 0.0]), np.concatenate([[False], edge[keep]])


def trace_to_retina(eye: SchematicEye, targets, wavelength_nm: float, *, field_deg=None, object_point_mm=None,
                    lenses=None, phase=None) -> tuple[RayBundle, np.ndarray]:
    """Rays through ``lenses`` (a `TrialLensSetup`, or None) and ``eye`` aimed at the iris points ``targets``
    (N, 2, mm) at ``wavelength_nm`` (one, or one per target) and traced to the retina: a collimated beam from
    ``field_deg`` (the models' rule, `field_direction`) or the rays of one ``object_point_mm`` (eye frame, z
    towards the retina). Returns the
    bundle on the retina (path lengths from the start) and the rays' starts (collimated) or launch directions.
    ``phase``: a `vissim.optics.raytrace.PhasePlane` between the lenses and the cornea (a measured eye's)."""
    front, stop_z, back, start_z = _front(eye, lenses, phase)
    if (field_deg is None) == (object_point_mm is None):
        raise VissimInputError("trace to the retina from a field angle or from an object point, not both or neither")
    if object_point_mm is None:
        at_iris, starts = aim_collimated(front, _beam_direction(eye, field_deg), targets, stop_z, start_z,
                                         wavelength_nm=wavelength_nm)
    else:
        at_iris, starts = aim_rays(front, object_point_mm, targets, stop_z, wavelength_nm=wavelength_nm)
    on_retina = trace_rays(back, at_iris.points_mm, at_iris.directions, None, wavelength_nm=wavelength_nm,
                           index_before=at_iris.final_index)
    bundle = RayBundle(on_retina.points_mm, on_retina.directions, at_iris.opl_mm + on_retina.opl_mm,
                       on_retina.final_index)
    return bundle, starts


def _checked_samples(samples) -> int:
    if int(samples) != samples or not 9 <= samples <= 1025 or samples % 2 == 0:
        raise VissimInputError(f"iris grid samples must be an odd whole number within 9-1025, got {samples!r}")
    return int(samples)


def _system_pupils(eye: SchematicEye, lenses, irises, pupils, wavelengths) -> tuple[np.ndarray, list[float]]:
    """(entrance-pupil diameters, their positions behind the corneal vertex), mm, one each of ``wavelengths``: the
    eye's, or with lenses the system's."""
    if lenses is None or not lenses.lenses:
        return pupils, [entrance_pupil_position_mm(mean_meridian_eye(eye), w) for w in wavelengths]
    return (entrance_pupils_from_irises_mm(eye, irises, wavelengths, lenses),
            [system_entrance_pupil_mm(eye, lenses, w)[0] for w in wavelengths])


def trace_eye_wavefront(eye: SchematicEye, wavelength_nm: float, field_deg=(0.0, 0.0), *, pupil_mm=None,
                        iris_mm=None, samples: int = DEFAULT_SAMPLES, max_order: int = 8,
                        lenses=None, phase=None) -> EyeWavefront:
    """The traced wavefront of ``eye`` (module doc) at one wavelength; give ``pupil_mm`` (entrance pupil) or
    ``iris_mm``; ``lenses``: a `TrialLensSetup` of thick lenses in front (module doc); ``phase``: a `PhasePlane`
    before the cornea (`trace_to_retina`).

    A field angle where rays miss a surface, meet total internal reflection or leave the GRIN lens
    raises one `VissimInputError` naming the field angle in degrees and what happened.
    """
    return trace_eye_wavefronts(eye, [wavelength_nm], field_deg, pupil_mm=pupil_mm, iris_mm=iris_mm,
                                samples=samples, max_order=max_order, lenses=lenses, phase=phase)[0]


def trace_eye_wavefronts(eye: SchematicEye, wavelengths_nm, field_deg=(0.0, 0.0), *, pupil_mm=None,
                         iris_mm=None, samples: int = DEFAULT_SAMPLES, max_order: int = 8,
                         lenses=None, phase=None) -> list[EyeWavefront]:
    """`trace_eye_wavefront` at each of ``wavelengths_nm``, in one trace per core: the rays of several wavelengths
    travel together, their paths differing only through the media's indices (one per ray, `trace_rays`), and each
    wavelength's pupil search runs in the same traces. Equal to tracing each wavelength alone (to round-off;
    tests/test_eye_multi_wavelength.py). ``pupil_mm``: the entrance pupil at every wavelength; ``iris_mm``: one iris,
    its entrance pupil each wavelength's."""
    try:
        wavelengths = [eye_wavelength_nm(w) for w in wavelengths_nm]
    except TypeError:
        raise VissimInputError(f"wavelengths must be a list of nm, got {wavelengths_nm!r}") from None
    if not wavelengths:
        raise VissimInputError("trace at least one wavelength, got none")
    _beam_direction(eye, field_deg)  # the field's checks first
    samples = _checked_samples(samples)
    pupils, irises, given = _pupils(eye, np.array(wavelengths), pupil_mm, iris_mm)
    field = tuple(float(v) for v in field_deg)
    try:
        system, entrance_z = _system_pupils(eye, lenses, irises, pupils, wavelengths)
        grids = [_iris_grid(eye, iris, samples) for iris in irises]

        def trace_share(share):  # the rays of several wavelengths, traced together
            targets = np.concatenate([grids[k][0] for k in share])
            waves = np.repeat([wavelengths[k] for k in share], [len(grids[k][1]) for k in share])
            return share, trace_to_retina(eye, targets, waves, field_deg=field, lenses=lenses, phase=phase)

        traced = map_shares(trace_share, range(len(grids)))
    except VissimInputError as error:
        raise VissimInputError(f"field angle ({field[0]:g}, {field[1]:g}) deg, {given} {_widest(pupils, irises, given)} "
                               f"mm: {error}; the {eye.name} eye traces a smaller pupil or field angle") from None

    def fit_share(share_traced):
        share, (bundle, starts) = share_traced
        fronts, first = [], 0
        for k in share:
            edge = grids[k][1]
            rays = slice(first, first + len(edge))
            first += len(edge)
            fronts.append(_fitted_front(eye, field, wavelengths[k], bundle.rows(rays), starts[rays], edge, max_order,
                                        (float(system[k]), float(irises[k]), given, entrance_z[k], float(pupils[k])),
                                        lenses))
        return fronts

    return [front for fronts in map_on_threads(fit_share, traced) for front in fronts]


def _widest(pupils, irises, given: str) -> str:
    """The widest pupil (or iris) of a trace, as its refusal names it."""
    return f"{float(np.max(pupils if given == 'entrance pupil' else irises)):.3g}"


def _fitted_front(eye, field, wavelength, bundle, starts, edge, max_order, pupil, lenses) -> EyeWavefront:
    """One wavelength's rays on the retina, their OPD on the reference sphere fitted over the entrance pupil."""
    diameter, iris, given, entrance_z, eye_pupil = pupil
    direction = _beam_direction(eye, field)
    exit_z = exit_pupil_position_mm(eye, wavelength)
    opd_um = wavefront_on_reference_sphere_um(bundle, 0, exit_z)
    xy = starts[:, :2] + direction[:2] / direction[2] * (entrance_z - starts[:, 2:3])
    chief = tuple(float(v) for v in xy[0])
    xy = xy - xy[0]
    if np.any(np.hypot(xy[edge, 0], xy[edge, 1]) <= 0.5 * diameter):
        raise VissimInputError(f"field angle ({field[0]:g}, {field[1]:g}) deg: the traced rays do not cover the "
                               f"{diameter:g} mm entrance pupil; the {eye.name} eye traces a smaller pupil or field angle")
    coefficients, residual = fit_zernike_um(xy[:, 0], xy[:, 1], opd_um, diameter, max_order)
    return EyeWavefront(eye.name, field, wavelength, diameter, iris, given, entrance_z, exit_z,
                        tuple(float(v) for v in bundle.points_mm[0]), chief, xy[:, 0].copy(), xy[:, 1].copy(), opd_um,
                        coefficients, residual, lenses, eye_pupil, field_axis(eye),
                        tuple(tuple(float(v) for v in row) for row in field_map(eye, field)),
                        tuple(float(v) for v in field_direction(eye, field)))
