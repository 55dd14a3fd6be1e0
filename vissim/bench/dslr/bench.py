"""The DSLR bench of thesis section 4.4 as a Mitsuba scene dict: camera, trial lenses, chart.

World frame (millimetres): the camera's principal plane (and entrance pupil) at z = 0, looking
along +z with +y up; the chart at z = ``chart_distance_mm``.  World x is the examiner's right
(TABO frame of `vissim.optics.rx.trial_lens`), so the camera's image right is world -x.  Light
travels towards -z: chart, trial lenses (the last lens's back vertex at ``vertex_distance_mm``,
the others stacked towards the chart with ``lens_gap_mm`` of air), camera.

Choices, and why:

* **Camera**: Mitsuba's ``thinlens`` -- an ideal lens whose aperture disc of diameter f/N is the
  entrance pupil (3.6 mm at f/5 and 18 mm) -- focused on ``focus_distance_mm``; a ``box``
  pixel filter so each output pixel is the integral over its solid angle, like vissim's PSFs.
  ``near_clip`` is 1 mm: Mitsuba's default 0.01 scene units would be 10 mm in a metre scene
  and silently skip a lens at 10 mm.
* **Chart**: a self-emitting rectangle whose radiance is the chart's linear reflectance (times
  ``radiance_scale``).  Emission is deterministic along every path, so the only noise is the
  camera's pixel and aperture sampling, and with no lens a pixel's expected value is exactly
  the chart's mean reflectance over it: a clean ground truth.  A diffuse chart lit by lamps
  would add light-sampling noise and an illumination falloff that tells nothing about blur.
* **Texture**: the print raster, ``nearest`` filtered, at >= 4 texels per camera pixel
  (`chart_mm_per_texel`).  Nearest reproduces the printed raster exactly (piecewise
  constant, like ink dots); bilinear would add a one-texel triangle blur.  The raster is
  cropped around the axis, or padded with its edge values, to cover the field plus blur and
  magnification margins.
* **Lenses**: the holder's rules, shared with the eye bench (`vissim.bench.lenses.holder`): PLY
  meshes with exact normals (`vissim.bench.lenses.mesh`), made of the refraction-only
  ``vissim_refract`` BSDF (`vissim.render.plugins`).  Thin lenses (``refractive_index`` None)
  become crown-glass lenses of realistic centre thickness for the clear aperture, and the theory
  (`DslrBench.viewing_setup`, a `ViewingSetup`) uses those same lenses and gives the aperture.
  The chart, its texture, the film and the integrator are `vissim.bench.scene_parts`'s.

The dict is Mitsuba's scene-dict format with plain values only: transforms are 4 x 4 row-major
nested lists under ``to_world`` and bitmap textures carry a float32 numpy array under
``data``; `vissim.render.run.to_mitsuba_dict` converts them.  Nothing here imports Mitsuba.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from vissim.bench.lenses.holder import (LENS_GAP_MM, MESH_RINGS, MESH_SEGMENTS, lens_back_vertex_z_mm,
                                        lens_clear_aperture_mm, lens_shapes, physical_lens)
from vissim.bench.scene_parts import chart_emitter, chart_texture, checked_chart_pixels, hdr_film, path_integrator
from vissim.bench.scene_parts import chart_texture_shape as texture_shape
from vissim.checks import (LENS_GAP_RANGE_MM, REFRACTIVE_INDEX_RANGE, TEXELS_PER_PX_RANGE, check_allocation,
                           number_within, sampler_seed, size_text)
from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.checks import samples_per_pixel
from vissim.checks import size_px as check_size_px
from vissim.checks import DEFAULT_WAVELENGTH_NM
from vissim.checks import vertex_distance_mm as check_vertex_mm
from vissim.errors import VissimInputError
from vissim.optics.rx.trial_lens import (CROWN_GLASS_INDEX, MAX_LENSES_IN_HOLDER, TrialLens, TrialLensSetup,
                                      entrance_pupil_diameter_mm)
from vissim.optics.rx.viewing_setup import ViewingSetup
from vissim.thesis import THESIS_CHART_DISTANCE_MM, THESIS_F_NUMBER, THESIS_FOCAL_LENGTH_MM, THESIS_VERTEX_DISTANCE_MM
from vissim.units import arcmin_to_rad, mm_to_m

__all__ = ["SAMPLERS", "RENDER_KINDS", "SPECTRAL_MODE", "DslrBench", "chart_mm_per_texel", "chart_texture_shape",
           "dslr_scene"]

SAMPLERS = ("independent", "stratified", "multijitter", "ldsampler")
#: Near clipping plane of the camera, mm (well below any vertex distance).
NEAR_CLIP_MM = 1.0


def _positive(value: Any, name: str, unit: str, *, allow_zero: bool = False) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise VissimInputError(f"{name} must be a number in {unit}, got {value!r}") from None
    if not math.isfinite(number) or number < 0.0 or (number == 0.0 and not allow_zero):
        raise VissimInputError(f"{name} must be {'>= 0' if allow_zero else '> 0'} {unit}, got {value!r}")
    return number


#: The least a render holds per pixel, bytes (a float32 value and its weight): a size beyond memory at this is refused
#: before anything is sized for it (the renderer's own estimate, `vissim.render.run`, is larger and checked again).
RENDER_BYTES_PER_PX = 8


@dataclass(frozen=True)
class DslrBench:
    """Camera, trial-lens holder and sampling of the DSLR bench (defaults: the thesis's bench).

    Parameters
    ----------
    focal_length_mm : float
        The camera lens (an ideal thin lens): focal length, mm.
    f_number : float
        Its f-number (the entrance pupil is ``focal_length_mm / f_number`` across).
    focus_distance_mm : float
        Where the camera is focused, mm from the camera lens.
    chart_distance_mm : float
        Where the chart stands, mm from the camera lens.
    vertex_distance_mm : float
        From the camera lens to the nearest trial lens, mm.
    lens_gap_mm : float
        Between lenses in the holder, mm.
    lenses : tuple of TrialLens
        Trial lenses, ordered from the chart to the camera, as in
        `TrialLensSetup` (at most the holder's slots).
    refractive_index : float
        The lenses' glass at the design wavelength (crown glass by default).
    clear_aperture_mm : float or None
        The lens meshes' diameter, mm; None sizes them to the beam (`clear_aperture`).
    arcmin_per_px : float
        The sensor's sampling, arcmin per pixel.
    size_px : (int, int)
        The sensor's size ``(rows, cols)``.
    spp : int
        Samples per pixel of the render.
    seed : int
        The render's seed.
    sampler : str
        The render's Mitsuba sampler.
    fresnel_loss : bool
        Whether the lens surfaces reflect (Fresnel) or transmit everything.
    texels_per_px : float
        The chart texture's resolution per camera pixel.
    radiance_scale : float
        The chart's radiance scale (relative).
    mesh_rings : int
        Tessellation of each lens surface: rings.
    mesh_segments : int
        Tessellation of each lens surface: segments per ring.

    Examples
    --------
    >>> import vissim
    >>> from vissim.optics.rx.trial_lens import TrialLens
    >>> bench = vissim.DslrBench(lenses=(TrialLens(2.0),), size_px=(64, 64))
    >>> bench.focal_length_mm, bench.f_number  # the thesis's camera: an 18 mm lens at f/5
    (18.0, 5.0)
    """

    focal_length_mm: float = THESIS_FOCAL_LENGTH_MM
    f_number: float = THESIS_F_NUMBER
    focus_distance_mm: float = THESIS_CHART_DISTANCE_MM
    chart_distance_mm: float = THESIS_CHART_DISTANCE_MM
    vertex_distance_mm: float = THESIS_VERTEX_DISTANCE_MM
    lens_gap_mm: float = LENS_GAP_MM
    lenses: tuple[TrialLens, ...] = ()
    refractive_index: float = CROWN_GLASS_INDEX
    clear_aperture_mm: float | None = None
    arcmin_per_px: float = 1.0
    size_px: tuple[int, int] = (133, 113)
    spp: int = 256
    seed: int = 0
    sampler: str = "multijitter"
    fresnel_loss: bool = False
    texels_per_px: float = 4.0
    radiance_scale: float = 1.0
    mesh_rings: int = MESH_RINGS
    mesh_segments: int = MESH_SEGMENTS

    def __post_init__(self) -> None:
        for name, unit in (("focal_length_mm", "mm"), ("f_number", "(f-number)"), ("focus_distance_mm", "mm"),
                           ("chart_distance_mm", "mm"), ("arcmin_per_px", "arcmin/px"), ("radiance_scale", "(relative)")):
            object.__setattr__(self, name, _positive(getattr(self, name), name.replace("_", " "), unit))
        for name, unit, bounds in (("refractive_index", "(dimensionless)", REFRACTIVE_INDEX_RANGE),
                                   ("texels_per_px", "texels per camera pixel", TEXELS_PER_PX_RANGE)):
            object.__setattr__(self, name, number_within(getattr(self, name), name.replace("_", " "), unit, bounds))
        object.__setattr__(self, "seed", sampler_seed(self.seed))
        object.__setattr__(self, "vertex_distance_mm", check_vertex_mm(self.vertex_distance_mm))
        object.__setattr__(self, "lens_gap_mm", number_within(self.lens_gap_mm, "lens gap", "mm", LENS_GAP_RANGE_MM))
        lenses = (self.lenses,) if isinstance(self.lenses, TrialLens) else tuple(self.lenses)
        if len(lenses) > MAX_LENSES_IN_HOLDER or not all(isinstance(lens, TrialLens) for lens in lenses):
            raise VissimInputError(
                f"the holder takes up to {MAX_LENSES_IN_HOLDER} TrialLens objects, got {self.lenses!r}")
        object.__setattr__(self, "lenses", lenses)
        object.__setattr__(self, "size_px", check_size_px(self.size_px))
        check_allocation(RENDER_BYTES_PER_PX * self.size_px[0] * self.size_px[1],
                         f"a {size_text(self.size_px)} render")  # before the lenses are sized for its field
        object.__setattr__(self, "spp", samples_per_pixel(self.spp))
        if self.sampler not in SAMPLERS:
            raise VissimInputError(f"sampler must be one of {', '.join(SAMPLERS)}, got {self.sampler!r}")
        check_arcmin_per_px(self.arcmin_per_px, "camera pixel")
        if self.clear_aperture_mm is not None:
            object.__setattr__(self, "clear_aperture_mm", _positive(self.clear_aperture_mm, "clear aperture", "mm"))
        self.trial_lens_setup()  # validates the stack against the chart distance

    # -- geometry -------------------------------------------------------------------------
    @property
    def entrance_pupil_diameter_mm(self) -> float:
        return entrance_pupil_diameter_mm(self.focal_length_mm, self.f_number)

    @property
    def field_half_diagonal_rad(self) -> float:
        """Angle from the axis to a corner of the frame (pixels are uniform in tan(angle))."""
        rows, cols = self.size_px
        return math.atan(0.5 * math.hypot(rows, cols) * math.tan(arcmin_to_rad(self.arcmin_per_px)))

    def clear_aperture(self) -> float:
        """Lens clear aperture, mm: given, or the beam at the farthest lens surface x 1.25 + 2 mm.

        Beam = pupil + 2 z tan(half-diagonal field) at z = vertex distance + the holder's depth
        (3 lenses of <= 4 mm and the gaps), rounded up to 0.5 mm.
        """
        if self.clear_aperture_mm is not None:
            return self.clear_aperture_mm
        return lens_clear_aperture_mm(self.entrance_pupil_diameter_mm, self.field_half_diagonal_rad,
                                      self.vertex_distance_mm, self.lens_gap_mm)

    @functools.cached_property
    def physical_lenses(self) -> tuple[TrialLens, ...]:
        """The lenses as rendered: thick, with an index (thin ones made realistic: `physical_lens`)."""
        return tuple(physical_lens(lens, self.clear_aperture(), self.refractive_index) for lens in self.lenses)

    def trial_lens_setup(self) -> TrialLensSetup:
        """The rendered lenses as a `TrialLensSetup` (object distance = chart distance)."""
        distance_m = mm_to_m(self.chart_distance_mm)
        return TrialLensSetup(self.physical_lenses, self.vertex_distance_mm, distance_m, self.lens_gap_mm)

    def lens_back_vertex_z_mm(self) -> tuple[float, ...]:
        """World z of each lens's back vertex, in the order of ``lenses`` (chart to camera)."""
        return lens_back_vertex_z_mm(self.physical_lenses, self.vertex_distance_mm, self.lens_gap_mm)

    @property
    def pitch_mm(self) -> float:
        """Size on the chart of the central camera pixel, mm (pixels are uniform in tan(angle))."""
        return self.chart_distance_mm * math.tan(arcmin_to_rad(self.arcmin_per_px))

    def viewing_setup(self, wavelength_nm: float = DEFAULT_WAVELENGTH_NM) -> ViewingSetup:
        """What this camera sees through its rendered lenses: pupil, defocus, magnification."""
        return ViewingSetup.dslr(self.focal_length_mm, self.f_number, mm_to_m(self.focus_distance_mm),
                                 self.trial_lens_setup(), wavelength_nm=wavelength_nm)

    def fov_x_deg(self) -> float:
        cols = self.size_px[1]
        return math.degrees(2.0 * math.atan(0.5 * cols * math.tan(arcmin_to_rad(self.arcmin_per_px))))


def chart_mm_per_texel(bench: DslrBench) -> float:
    """Texel size for the chart raster: ``texels_per_px`` texels per camera pixel on the chart."""
    return bench.pitch_mm / bench.texels_per_px


def chart_texture_shape(bench: DslrBench, setup: ViewingSetup, mm_per_px: float) -> tuple[int, int]:
    """(rows, cols) texels the chart texture needs: the magnified field, the blur and a margin
    (`vissim.bench.scene_parts.chart_texture_shape` of the camera's blur and magnification through its lenses)."""
    blur_px = max(d for d, _ in setup.blur_diameter_arcmin) / bench.arcmin_per_px
    mag = max(abs(m) for m, _ in setup.magnification_principal)
    return texture_shape(bench.size_px, bench.pitch_mm, blur_px, mag, mm_per_px)


def _chart_texture(bench: DslrBench, setup: ViewingSetup, pixels: np.ndarray, mm_per_px: float) -> tuple[np.ndarray, float, float]:
    """Crop/pad ``pixels`` (centred on the axis) to cover the field with margins; (texture, height_mm, width_mm)."""
    what = f"{size_text(bench.size_px)} frame, blur {max(d for d, _ in setup.blur_diameter_arcmin):.3g} arcmin"
    return chart_texture(pixels, chart_texture_shape(bench, setup, mm_per_px), mm_per_px, what)


#: Render kinds of the bench: one channel, three, or spectral (luminance of a spectral render).
RENDER_KINDS = ("mono", "rgb", "spectral")
#: What a spectral bench render is (recorded in its provenance): the chart's light, the lenses' glass, the response.
SPECTRAL_MODE = {
    "emitter_spectrum": "equal-energy (CIE illuminant E): the chart's linear reflectance at every wavelength",
    "glass": "spectacle crown dispersion: Cauchy fit to the lens index at the d line and Abbe number 58.6 "
             "(vissim.optics.rx.glass.glass_like_crown)",
    "response": "CIE 1931 luminance Y (Mitsuba's film: XYZ from the sampled wavelengths, stored as Y)",
    "wavelengths": "Mitsuba's sampling of the visible range, 4 per path; at a path's first lens surface only the "
                   "hero wavelength continues, weighted by 4 (pbrt-v4's TerminateSecondary)",
}


def dslr_scene(
    bench: DslrBench,
    chart_pixels: np.ndarray,
    chart_mm_per_px: float,
    *,
    kind: str = "mono",
    mesh_cache_dir=None,
    lens_wavelength_nm: float | None = None,
    sensor_terminates_secondary: bool = False,
) -> dict[str, Any]:
    """The Mitsuba scene dict of ``bench`` with the chart raster ``chart_pixels`` (module doc).

    The lenses' glass, decided here: spectacle crown, dispersive, in a ``"spectral"`` render (each path's
    hero wavelength; ``sensor_terminates_secondary`` when the camera ends the other wavelengths itself) and
    when ``lens_wavelength_nm`` is given (a one-wavelength render: crown's index there); otherwise the
    lenses' index at every wavelength (the bench's default).

    ``chart_pixels``: linear reflectance, (H, W) or (H, W, 3), row 0 the top of the chart as
    the camera sees it, columns to the camera's right; its centre lies on the optical axis.
    """
    pixels = checked_chart_pixels(chart_pixels)
    mm_per_px = _positive(chart_mm_per_px, "chart pixel size", "mm")
    if kind not in RENDER_KINDS:
        raise VissimInputError(f"render kind must be one of {', '.join(RENDER_KINDS)}, got {kind!r}")
    setup = bench.viewing_setup()
    texture, height_mm, width_mm = _chart_texture(bench, setup, pixels, mm_per_px)
    scene: dict[str, Any] = {
        "type": "scene",
        "integrator": path_integrator(),
        "camera": {
            "type": "thinlens",
            "fov": bench.fov_x_deg(),
            "fov_axis": "x",
            "aperture_radius": 0.5 * setup.pupil_diameter_mm,
            "focus_distance": bench.focus_distance_mm,
            "near_clip": NEAR_CLIP_MM,
            "far_clip": 10.0 * bench.chart_distance_mm,
            # look_at((0,0,0), (0,0,1), up (0,1,0)): Mitsuba's camera frame is +x left, +y up, +z forward.
            "to_world": [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]],
            "sampler": {"type": bench.sampler, "sample_count": int(bench.spp), "seed": int(bench.seed)},
            "film": hdr_film(bench.size_px, kind),
        },
        "chart": chart_emitter(texture, height_mm, width_mm, bench.chart_distance_mm, kind=kind,
                               radiance_scale=bench.radiance_scale),
    }
    scene.update(lens_shapes(bench.physical_lenses, bench.lens_back_vertex_z_mm(), bench.clear_aperture(), kind=kind,
                             lens_wavelength_nm=lens_wavelength_nm,
                             sensor_terminates_secondary=sensor_terminates_secondary,
                             fresnel_loss=bench.fresnel_loss, rings=bench.mesh_rings, segments=bench.mesh_segments,
                             mesh_cache_dir=mesh_cache_dir))
    return scene
