"""The simulations the eye bench compares with its renders (pure numpy, no Mitsuba).

Every simulation blurs the same chart: the rendered letter drawn in visual angle, ``oversample``
times finer than the image and wider by a margin that holds the blur; the result is integrated
onto the image's pixels.  ``reference`` says what each is scored against: the render itself
(ray optics: the render has no diffraction) or the render convolved with the pupil's in-focus
diffraction PSF (wave optics).

``traced_rays``
    The geometric self-check: the numpy trace's ray PSF and spectacle magnification
    (`vissim.validation.eye.rays`).
``reduced_wave`` / ``reduced_geometric``
    The reduced eye as `vissim.ViewingSetup.eye` builds it: the trial lens's added power and
    spectacle magnification at the cornea (`trial_lens_effect`), the chart's vergence, the
    accommodation; photopic light by Thibos's chromatic eye (in focus at 555 nm).
``thesis``
    The thesis's setup: the lens's P / (1 - dP) at the vertex distance, the chart at infinity, no
    magnification, one wavelength (555 nm for photopic light), wave optics.
``schematic_wave`` / ``schematic``
    The schematic eye (`EyeView.blur`, `vissim.blur_eye`): the traced wavefront at the image's field and every
    wavelength (each with its own focus and transverse shift), the lens and the chart's vergence
    added at the eye's entrance pupil, the lens's spectacle magnification.  ``schematic`` is the same
    wavefront in ray optics, scored against the render itself: the schematic eye's check free of the
    wave reference's own error near focus (the render is ray optics; blurred by the in-focus diffraction
    PSF it is not a wave image of an eye with spherical aberration: `vissim.validation.eye.report`).  Made
    for one-wavelength light only: the ray PSFs of 13 photopic wavelengths take about a minute per item.
An ametropic eye (the configuration's ``rx``: its spectacle prescription at ``vertex_mm``) is one `Eye`
(`schema.EyeConfiguration.eye`): the schematic simulations and the traced self-check trace that ametropic eye
itself (its longer vitreous, toric cornea and the higher orders they bring), with the light's vergence at its
entrance pupil added (`EyeScene.schematic_vergence`); the reduced eye and the thesis take its refraction
carried to the corneal vertex (`EyeScene.eye_refraction`: the prescription of `ViewingSetup.eye`, which the
thesis adds its lens's P / (1 - dP) to).
Each reduced-eye assumption, put into ``schematic_wave`` one at a time (wave optics, scored against the render
with diffraction):
``no_higher_orders`` (the eye's Zernike orders above 2 dropped), ``thibos_lca`` (traced at 555
nm only, Thibos's formula for the other wavelengths; photopic only), ``on_axis_psf`` (the on-axis
PSF for an off-axis image), ``iris_as_pupil`` (the iris's diameter taken as the entrance pupil's),
``no_magnification`` (the lens's spectacle magnification left out).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy import ndimage
from scipy.signal import fftconvolve

from vissim.charts import optotype_tile
from vissim.errors import FieldTooSmallError
from vissim.optics.blur import blur_image
from vissim.optics.eyes.viewing import EyeView
from vissim.optics.eyes.wavefront import iris_from_entrance_pupil_mm
from vissim.optics.psf import PSF, compute_psf
from vissim.optics.resample import block_mean, magnify
from vissim.optics.setup import ViewingSetup
from vissim.optics.wavefront import Wavefront
from vissim.spectra import named_spectrum

__all__ = ["SIMULATIONS", "COSTS", "EyeScene", "simulate", "thesis_setup", "chart", "PHOTOPIC_FOCUS_NM", "reference_of"]

#: The wavelength the reduced eye is in focus at, and the thesis's one wavelength, for photopic light.
PHOTOPIC_FOCUS_NM = 555.0
#: The photopic spectrum's sampling in the simulations and the ray trace, nm (400-700 nm: 13 wavelengths).
PHOTOPIC_STEP_NM = 25.0
#: The simulations compared with every render (module doc).
SIMULATIONS = ("traced_rays", "reduced_geometric", "reduced_wave", "thesis", "schematic", "schematic_wave")
#: Reduced-eye assumption -> the simulation that puts it into the geometric schematic one, and where it applies.
COSTS = {"spherical aberration": ("no_higher_orders", "always"),
         "chromatic model": ("thibos_lca", "photopic"),
         "field dependence": ("on_axis_psf", "off axis"),
         "pupil definition": ("iris_as_pupil", "always"),
         "spectacle magnification": ("no_magnification", "lens")}
WAVE = ("reduced_wave", "thesis", "schematic_wave") + tuple(name for name, _ in COSTS.values())


def reference_of(simulation: str) -> str:
    """``"render"`` or ``"render + diffraction"``: what ``simulation`` is scored against."""
    return "render + diffraction" if simulation in WAVE else "render"


@functools.lru_cache(maxsize=32)
def chart(letter: str, logmar: float, distance_m: float, step_arcmin: float, shape: tuple[int, int],
          half_size_arcmin: tuple[float, float]) -> np.ndarray:
    """The rendered chart's letter (printed for ``distance_m``, `vissim.bench.eye.bench.EyeBench.chart`) in visual angle,
    centred, ``shape`` pixels of ``step_arcmin``; black beyond the chart's half size (rows, columns; arcmin)."""
    pixels = optotype_tile(letter, logmar, arcmin_per_px=step_arcmin, shape_px=shape,
                           viewing_distance_m=distance_m, snap_to_pixels=False).pixels.astype(np.float64)
    for axis, half in enumerate(half_size_arcmin):
        offset = step_arcmin * np.abs(np.arange(shape[axis]) - (shape[axis] - 1) / 2.0)
        outside = offset > half
        if axis == 0:
            pixels[outside, :] = 0.0
        else:
            pixels[:, outside] = 0.0
    return pixels


class EyeScene:
    """One configuration's view and light, as the simulations need them (configuration: `schema.EyeConfiguration`):
    the item's one `Eye` through its lens at its chart (`vissim.optics.eyes.viewing.EyeView`, the viewing physics)."""

    def __init__(self, configuration, settings, built):
        self.c, self.s = configuration, settings
        self.lens, self.chart_half_arcmin = built.lens, built.chart_half_arcmin  # `renders.EyeBuilt`
        bench = built.bench  # the rendered bench: its eye is the one `Eye` of the item, rendered, traced and simulated
        self.view = EyeView(bench.eye, bench.chart_distance_m, bench.field_deg, built.lens, bench.vertex_mm)
        self.the_eye = self.view.eye
        self.eye = self.the_eye.optics
        self._charts: dict = {}  # (step, shape) -> `scene_chart`'s image: every simulation of the item draws it
        self.photopic = configuration.spectrum == "photopic"
        if self.photopic:
            wavelengths, weights = named_spectrum("photopic", PHOTOPIC_STEP_NM)
            self.wavelengths, self.weights = tuple(wavelengths), tuple(weights)
        else:
            self.wavelengths, self.weights = (configuration.wavelength_nm,), (1.0,)
        self.mono_nm = PHOTOPIC_FOCUS_NM if self.photopic else configuration.wavelength_nm

    def reduced_setup(self):
        """The reduced eye's `ViewingSetup` at the item's focus wavelength, and the lens's magnification."""
        return self.view.reduced_setup(self.mono_nm)

    def schematic_vergence(self) -> tuple[np.ndarray, np.ndarray]:
        """The light's vergence at the eye's entrance pupil and the lens's magnification (`EyeView.vergence_at_pupil`)."""
        return self.view.vergence_at_pupil(self.mono_nm)


def scene_chart(scene: EyeScene, step: float, shape: tuple[int, int]) -> np.ndarray:
    """The chart as the eye's pixels see it (`EyeView.chart_points_arcmin`: each pixel's line of sight from the
    entrance pupil to the flat chart), drawn once per item and shape."""
    if (step, shape) not in scene._charts:
        seen = np.array(_seen_chart(scene, step, shape))
        seen.setflags(write=False)
        scene._charts[(step, shape)] = seen
    return scene._charts[(step, shape)]


def _seen_chart(scene: EyeScene, step: float, shape: tuple[int, int]) -> np.ndarray:
    c = scene.c
    points = scene.view.chart_points_arcmin(shape, step)
    if points is None:
        return chart(c.letter, c.logmar, c.chart_distance_m, step, shape, scene.chart_half_arcmin)
    base_shape = tuple(int(math.ceil(1.15 * n)) + 8 for n in shape)
    base = chart(c.letter, c.logmar, c.chart_distance_m, step, base_shape, scene.chart_half_arcmin)
    row_arcmin, col_arcmin = points
    coords = [row_arcmin / step + (base_shape[0] - 1) / 2.0, col_arcmin / step + (base_shape[1] - 1) / 2.0]
    return ndimage.map_coordinates(base, coords, order=1, mode="nearest")


def _finish(blurred: np.ndarray, margin: int, oversample: int) -> np.ndarray:
    inner = blurred[margin:blurred.shape[0] - margin, margin:blurred.shape[1] - margin]
    return block_mean(inner, oversample)


def _blur_psf(image: np.ndarray, psf: PSF, step: float) -> np.ndarray:
    return np.asarray(blur_image(image, psf, arcmin_per_px=step, padding="edge"), np.float64)


def _psf(front, scene: EyeScene, step: float, mode: str, size_px="auto", **extra) -> PSF:
    """The PSF of ``front``; ray optics on ``size_px`` (the ray PSF's field: the automatic size's search is slow
    for ray optics), widened to the automatic size where more than 1 % of the light falls outside."""
    try:
        return compute_psf(front, arcmin_per_px=step, size_px=size_px, mode=mode, pixel="integrate", **extra)
    except FieldTooSmallError:
        return compute_psf(front, arcmin_per_px=step, size_px="auto", mode=mode, pixel="integrate", **extra)


def _schematic(scene: EyeScene, image: np.ndarray, step: float, mode: str, *, field=None, pupil_mm=None,
               drop_higher=False, thibos=False, size_px="auto") -> np.ndarray:
    """The schematic eye's blur of ``image`` with one assumption swapped (module doc).  Unswapped, in wave optics,
    it is `blur_eye`; in ray optics the same PSF (the image lies within one of `blur_eye`'s PSF nodes) on the ray
    PSF's field."""
    view = scene.view
    field = view.field_deg if field is None else field
    eye = view.eye if pupil_mm is None else view.eye.with_pupil(pupil_mm=pupil_mm)
    if mode == "wave" and not (drop_higher or thibos or field != view.field_deg or pupil_mm is not None):
        bands = [scene.wavelengths] if scene.photopic else scene.mono_nm
        weights = [scene.weights] if scene.photopic else None
        return np.asarray(view.blur(image, arcmin_per_px=step, wavelength_nm=bands, focus_nm=scene.mono_nm,
                                    weights=weights, mode=mode, padding="edge", dtype=np.float64), np.float64)
    wavelengths = (scene.mono_nm,) if thibos else scene.wavelengths
    front = view.spectral_wavefront(wavelengths, focus_nm=scene.mono_nm, field_deg=field, eye=eye)
    if drop_higher:
        front = front.map(lambda f: Wavefront({k: v for k, v in f.coefficients_um.items() if k[0] <= 2},
                                              f.pupil_diameter_mm, f.wavelength_nm))
    if thibos:
        psf = _psf(front.fronts[0], scene, step, mode, wavelength_nm=scene.wavelengths, weights=scene.weights,
                   lca_reference_nm=PHOTOPIC_FOCUS_NM)
    else:
        psf = _psf(front, scene, step, mode, size_px, weights=scene.weights)
    return _blur_psf(image, psf, step)


def thesis_setup(scene: EyeScene) -> ViewingSetup:
    """The thesis's setup (`EyeView.thesis_setup`) at the item's focus wavelength."""
    return scene.view.thesis_setup(scene.mono_nm)


def _reduced(scene: EyeScene, image: np.ndarray, step: float, mode: str, thesis: bool = False) -> np.ndarray:
    if thesis:
        setup = thesis_setup(scene)
        return _blur_psf(image, _psf(setup.wavefront, scene, step, mode, wavelength_nm=scene.mono_nm), step)
    setup, _ = scene.reduced_setup()
    if scene.photopic:
        psf = _psf(setup.wavefront, scene, step, mode, wavelength_nm=scene.wavelengths, weights=scene.weights,
                   lca_reference_nm=PHOTOPIC_FOCUS_NM)
    else:
        psf = _psf(setup.wavefront, scene, step, mode, wavelength_nm=scene.mono_nm)
    return _blur_psf(image, psf, step)


def _magnification(scene: EyeScene, simulation: str, ray) -> np.ndarray:
    if simulation in ("thesis", "no_magnification"):
        return np.eye(2)
    if simulation == "traced_rays":
        return ray.magnification
    if simulation.startswith("reduced"):
        return scene.reduced_setup()[1]
    return scene.schematic_vergence()[1]


def simulate(simulation: str, scene: EyeScene, ray, margin: int, offset_px=(0.0, 0.0)) -> np.ndarray:
    """``simulation`` (module doc) of ``scene``'s chart, on the image's pixels; ``ray``: its `rays.RayPsf`;
    ``offset_px``: the chart's placement in the render (rows down, columns right; image pixels)."""
    ov = scene.s.oversample
    step = scene.c.arcmin_per_px / ov
    rows, cols = scene.c.size_px
    image = scene_chart(scene, step, (rows * ov + 2 * margin, cols * ov + 2 * margin))
    if tuple(offset_px) != (0.0, 0.0):
        image = ndimage.shift(image, (offset_px[0] * ov, offset_px[1] * ov), order=3, mode="nearest")
    image = np.asarray(magnify(image, _magnification(scene, simulation, ray)), np.float64)
    mode = "wave" if simulation in WAVE else "geometric"
    if simulation == "traced_rays":
        half = ray.psf.shape[0] // 2
        blurred = fftconvolve(np.pad(image, half, mode="edge"), ray.psf, mode="valid")
    elif simulation.startswith("reduced"):
        blurred = _reduced(scene, image, step, mode)
    elif simulation == "thesis":
        blurred = _reduced(scene, image, step, mode, thesis=True)
    elif simulation in ("schematic", "schematic_wave", "no_magnification"):
        size = ray.psf.shape[0] + 16 if mode == "geometric" else "auto"
        blurred = _schematic(scene, image, step, mode, size_px=size)
    elif simulation == "no_higher_orders":
        blurred = _schematic(scene, image, step, mode, drop_higher=True)
    elif simulation == "thibos_lca":
        blurred = _schematic(scene, image, step, mode, thibos=True)
    elif simulation == "on_axis_psf":
        blurred = _schematic(scene, image, step, mode, field=(0.0, 0.0))
    elif simulation == "iris_as_pupil":
        iris = iris_from_entrance_pupil_mm(scene.eye, scene.c.pupil_mm, scene.mono_nm)
        blurred = _schematic(scene, image, step, mode, pupil_mm=iris)
    else:
        raise ValueError(f"unknown simulation {simulation!r}")
    return _finish(blurred, margin, ov)


def diffraction_psf(scene: EyeScene) -> PSF:
    """The in-focus diffraction PSF of the entrance pupil at the image's sampling (photopic: 555 nm)."""
    front = Wavefront({}, scene.c.pupil_mm)
    return compute_psf(front, wavelength_nm=scene.mono_nm, arcmin_per_px=scene.c.arcmin_per_px, size_px="auto",
                       mode="wave", pixel="integrate")


def margin_px(ray, oversample: int) -> int:
    """The chart's margin (fine pixels): the ray PSF's half-width and 4 image pixels."""
    return ray.psf.shape[0] // 2 + 4 * oversample
