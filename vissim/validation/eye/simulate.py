"""The simulations the eye bench compares with its renders (pure numpy, no Mitsuba).

Every simulation blurs the same chart: the rendered letter as the eye's pixels see it
(`vissim.bench.eye.bench.EyeBench.seen_chart`), ``oversample`` times finer than the image and wider by a
margin that holds the blur; the result is integrated onto the image's pixels.  ``reference`` says what
each is scored against: the render itself (ray optics: the render has no diffraction) or the render
convolved with the pupil's in-focus diffraction PSF (wave optics).

``traced_rays``
    The geometric self-check: the numpy trace's ray PSF and spectacle magnification
    (`vissim.optics.eyes.retina_map.ray_psf`).
The others are the eye models' simulations of the rendered bench's view (`EyeBench.view`), made by the
library (`vissim.optics.eyes.simulations.simulate_view`, whose doc says what each is): the reduced eye
(``reduced_wave``, ``reduced_geometric``), the thesis (``thesis``), the schematic eye (``schematic_wave``;
``schematic``, the same wavefront in ray optics, scored against the render itself: the schematic eye's check
free of the wave reference's own error near focus, `vissim.validation.eye.report`; made for one-wavelength
light only: the ray PSFs of 13 photopic wavelengths take about a minute per item), and each reduced-eye
assumption put into ``schematic_wave`` one at a time (`COSTS`). Photopic light is `Light.photopic`.
"""

from __future__ import annotations

import numpy as np

from vissim.lazy_import import lazy_module
from vissim.optics.eyes.simulations import WAVE_OPTICS, simulate_view
from vissim.optics.psf.compute import PSF, compute_psf
from vissim.optics.blur.resample import block_mean, magnify
from vissim.optics.pupil.wavefront import Wavefront
from vissim.optics.eyes.retina_map import RAYS_ACROSS_IRIS

ndimage = lazy_module("scipy.ndimage")
signal = lazy_module("scipy.signal")

__all__ = ["SIMULATIONS", "COSTS", "EyeScene", "simulate", "reference_of", "diffraction_psf", "margin_px"]

#: The simulations compared with every render (module doc).
SIMULATIONS = ("traced_rays", "reduced_geometric", "reduced_wave", "thesis", "schematic", "schematic_wave")
#: Reduced-eye assumption -> the simulation that puts it into the schematic wave-optics one, and where it applies.
COSTS = {"spherical aberration": ("no_higher_orders", "always"),
         "chromatic model": ("thibos_lca", "photopic"),
         "field dependence": ("on_axis_psf", "off axis"),
         "pupil definition": ("iris_as_pupil", "always"),
         "spectacle magnification": ("no_magnification", "lens")}


def reference_of(simulation: str) -> str:
    """``"render"`` or ``"render + diffraction"``: what ``simulation`` is scored against."""
    return "render + diffraction" if simulation in WAVE_OPTICS else "render"


class EyeScene:
    """A rendered bench (`vissim.bench.eye.bench.EyeBench`), its view (`EyeBench.view`: its `Eye` through its lens at
    its chart) and its light (`EyeBench.light`), simulated on a grid ``oversample`` times finer than its image;
    ``rays_across``: the ray PSF's rays across the iris."""

    def __init__(self, bench, oversample: int, rays_across: int = RAYS_ACROSS_IRIS):
        self.bench, self.view, self.light = bench, bench.view, bench.light
        self.oversample, self.rays_across = int(oversample), int(rays_across)


def simulate(simulation: str, scene: EyeScene, ray, margin: int, offset_px=(0.0, 0.0)) -> np.ndarray:
    """``simulation`` (module doc) of ``scene``'s chart, on the image's pixels; ``ray``: its `RayPsf`;
    ``offset_px``: the chart's placement in the render (rows down, columns right; image pixels)."""
    ov = scene.oversample
    step = scene.bench.arcmin_per_px / ov
    rows, cols = scene.bench.size_px
    image = scene.bench.seen_chart(step, (rows * ov + 2 * margin, cols * ov + 2 * margin))
    if tuple(offset_px) != (0.0, 0.0):
        image = ndimage.shift(image, (offset_px[0] * ov, offset_px[1] * ov), order=3, mode="nearest")
    if simulation == "traced_rays":
        image = np.asarray(magnify(image, ray.magnification), np.float64)
        half = ray.psf.shape[0] // 2
        blurred = signal.fftconvolve(np.pad(image, half, mode="edge"), ray.psf, mode="valid")
    else:
        size = ray.psf.shape[0] + 16 if simulation not in WAVE_OPTICS else "auto"
        blurred = simulate_view(scene.view, scene.light, simulation, np.asarray(image, np.float64), step, size_px=size)
    inner = blurred[margin:blurred.shape[0] - margin, margin:blurred.shape[1] - margin]
    return block_mean(inner, ov)


def diffraction_psf(scene: EyeScene) -> PSF:
    """The in-focus diffraction PSF of the entrance pupil at the image's sampling (photopic: its focus, 555 nm)."""
    front = Wavefront({}, scene.view.entrance_pupil_mm)
    return compute_psf(front, wavelength_nm=scene.light.focus_nm, arcmin_per_px=scene.bench.arcmin_per_px, size_px="auto",
                       mode="wave", pixel="integrate")


def margin_px(ray, oversample: int) -> int:
    """The chart's margin (fine pixels): the ray PSF's half-width and 4 image pixels."""
    return ray.psf.shape[0] // 2 + 4 * oversample
