"""A chart as an eye sees it through a lens, simulated by each of vissim's eye models (pure numpy).

``simulate_view(view, light, simulation, image, arcmin_per_px)`` blurs ``image`` (the chart drawn in
visual angle as the eye's pixels see it, centred on the chart: `vissim.bench.eye.bench.EyeBench.seen_chart`)
for the `EyeView` ``view`` in the `Light` ``light``: the lens's spectacle magnification first, then the
model's PSF. The simulations:

``reduced_wave`` / ``reduced_geometric``
    The reduced eye (`EyeView.reduced_setup`, `vissim.ViewingSetup.eye`): the eye's prescription carried to
    the corneal vertex, the lens's added power and spectacle magnification there, the chart's vergence, the
    accommodation; photopic light by Thibos's chromatic eye (in focus at the light's focus wavelength).
``thesis``
    The thesis's setup (`EyeView.thesis_setup`): the lens's P / (1 - dP) at the vertex distance, the chart at
    infinity, no magnification, one wavelength (the light's focus wavelength), wave optics.
``schematic_wave`` / ``schematic``
    The schematic eye itself (`EyeView.blur`, `vissim.blur_eye`): its traced wavefront at the chart's field and
    every wavelength (each with its own focus and transverse shift), the lens and the chart's vergence added at
    its entrance pupil, the lens's spectacle magnification. An ametropic eye (one with a prescription) is traced
    as itself: its longer vitreous, toric cornea and the higher orders they bring.

Each reduced-eye assumption put into the schematic eye one at a time:
``no_higher_orders`` (its Zernike orders above 2 dropped), ``thibos_lca`` (traced at the focus wavelength only,
Thibos's formula for the others), ``on_axis_psf`` (the on-axis PSF at an off-axis field), ``iris_as_pupil`` (the
iris's diameter taken as the entrance pupil's), ``no_magnification`` (the lens's spectacle magnification left out).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vissim.errors import FieldTooSmallError, VissimInputError
from vissim.optics.blur.convolve import blur_image
from vissim.optics.eyes.defaults import PHOTOPIC_FOCUS_NM, PHOTOPIC_STEP_NM
from vissim.optics.eyes.viewing import EyeView
from vissim.optics.eyes.traced_wavefront import iris_from_entrance_pupil_mm
from vissim.optics.psf.compute import PSF, compute_psf
from vissim.optics.blur.resample import magnify
from vissim.optics.pupil.wavefront import Wavefront
from vissim.spectra import named_spectrum

__all__ = ["Light", "simulate_view", "VIEW_SIMULATIONS", "ASSUMPTIONS", "WAVE_OPTICS"]

#: The simulations of the eye models (module doc).
VIEW_SIMULATIONS = ("reduced_geometric", "reduced_wave", "thesis", "schematic", "schematic_wave")
#: The reduced-eye assumptions, each put into the schematic eye (module doc).
ASSUMPTIONS = ("no_higher_orders", "thibos_lca", "on_axis_psf", "iris_as_pupil", "no_magnification")
#: The simulations in wave optics (the others are ray optics).
WAVE_OPTICS = ("reduced_wave", "thesis", "schematic_wave") + ASSUMPTIONS


@dataclass(frozen=True)
class Light:
    """The chart's light: ``wavelengths_nm`` weighted by ``weights``; ``focus_nm`` the wavelength the reduced eye and
    the thesis focus (and the one the entrance pupil's depth is taken at)."""

    wavelengths_nm: tuple[float, ...]
    weights: tuple[float, ...]
    focus_nm: float

    @classmethod
    def monochromatic(cls, wavelength_nm: float) -> "Light":
        return cls((float(wavelength_nm),), (1.0,), float(wavelength_nm))

    @classmethod
    def photopic(cls, step_nm: float = PHOTOPIC_STEP_NM) -> "Light":
        """White light seen as luminance (V(λ) every ``step_nm``), in focus at `PHOTOPIC_FOCUS_NM`."""
        wavelengths, weights = named_spectrum("photopic", step_nm)
        return cls(tuple(wavelengths), tuple(weights), PHOTOPIC_FOCUS_NM)

    @property
    def is_white(self) -> bool:
        return len(self.wavelengths_nm) > 1


def magnification_of(view: EyeView, light: Light, simulation: str) -> np.ndarray:
    """The lens's 2 x 2 spectacle magnification (x, y) that ``simulation`` applies to the chart."""
    if simulation in ("thesis", "no_magnification"):
        return np.eye(2)
    if simulation.startswith("reduced"):
        return view.reduced_setup(light.focus_nm)[1]
    return view.vergence_at_pupil(light.focus_nm)[1]


def simulate_view(view: EyeView, light: Light, simulation: str, image: np.ndarray, arcmin_per_px: float, *,
                  size_px="auto") -> np.ndarray:
    """``image`` (float64, ``arcmin_per_px``, centred on the chart) magnified and blurred by ``simulation`` (module
    doc); ``size_px``: the ray-optics schematic PSF's field (default: the automatic size)."""
    if simulation not in VIEW_SIMULATIONS + ASSUMPTIONS:
        raise VissimInputError(f"unknown simulation {simulation!r}; choose from "
                               + ", ".join(VIEW_SIMULATIONS + ASSUMPTIONS))
    image = np.asarray(magnify(image, magnification_of(view, light, simulation)), np.float64)
    mode = "wave" if simulation in WAVE_OPTICS else "geometric"
    step = arcmin_per_px
    if simulation.startswith("reduced") or simulation == "thesis":
        return _reduced(view, light, image, step, mode, thesis=simulation == "thesis")
    if simulation == "no_higher_orders":
        return _schematic(view, light, image, step, mode, drop_higher=True)
    if simulation == "thibos_lca":
        return _schematic(view, light, image, step, mode, thibos=True)
    if simulation == "on_axis_psf":
        return _schematic(view, light, image, step, mode, field=(0.0, 0.0))
    if simulation == "iris_as_pupil":
        iris = iris_from_entrance_pupil_mm(view.eye.optics, view.entrance_pupil_mm, light.focus_nm)
        return _schematic(view, light, image, step, mode, pupil_mm=iris)
    return _schematic(view, light, image, step, mode, size_px=size_px)


def _blur_psf(image: np.ndarray, psf: PSF, step: float) -> np.ndarray:
    return np.asarray(blur_image(image, psf, arcmin_per_px=step, padding="edge"), np.float64)


def _psf(front, step: float, mode: str, size_px="auto", **extra) -> PSF:
    """The PSF of ``front``; ray optics on ``size_px`` (the automatic size's search is slow for ray optics),
    widened to the automatic size where more than 1 % of the light falls outside."""
    try:
        return compute_psf(front, arcmin_per_px=step, size_px=size_px, mode=mode, pixel="integrate", **extra)
    except FieldTooSmallError:
        return compute_psf(front, arcmin_per_px=step, size_px="auto", mode=mode, pixel="integrate", **extra)


def _schematic(view: EyeView, light: Light, image: np.ndarray, step: float, mode: str, *, field=None,
               pupil_mm=None, drop_higher=False, thibos=False, size_px="auto") -> np.ndarray:
    """The schematic eye's blur of ``image`` with one assumption swapped (module doc). Unswapped, in wave optics, it
    is `blur_eye`; in ray optics the same PSF (the image lies within one of `blur_eye`'s PSF nodes) on ``size_px``."""
    field = view.field_deg if field is None else field
    eye = view.eye if pupil_mm is None else view.eye.with_assumed_pupil(pupil_mm)
    if mode == "wave" and not (drop_higher or thibos or field != view.field_deg or pupil_mm is not None):
        bands = [light.wavelengths_nm] if light.is_white else light.focus_nm
        weights = [light.weights] if light.is_white else None
        return np.asarray(view.blur(image, arcmin_per_px=step, wavelength_nm=bands, focus_nm=light.focus_nm,
                                    weights=weights, mode=mode, padding="edge", dtype=np.float64), np.float64)
    wavelengths = (light.focus_nm,) if thibos else light.wavelengths_nm
    front = view.spectral_wavefront(wavelengths, focus_nm=light.focus_nm, field_deg=field, eye=eye)
    if drop_higher:
        front = front.map(lambda f: Wavefront({k: v for k, v in f.coefficients_um.items() if k[0] <= 2},
                                              f.pupil_diameter_mm, f.wavelength_nm))
    if thibos:
        psf = _psf(front.fronts[0], step, mode, wavelength_nm=light.wavelengths_nm, weights=light.weights,
                   lca_reference_nm=light.focus_nm)
    else:
        psf = _psf(front, step, mode, size_px, weights=light.weights)
    return _blur_psf(image, psf, step)


def _reduced(view: EyeView, light: Light, image: np.ndarray, step: float, mode: str, thesis: bool) -> np.ndarray:
    if thesis:
        setup = view.thesis_setup(light.focus_nm)
        return _blur_psf(image, _psf(setup.wavefront, step, mode, wavelength_nm=light.focus_nm), step)
    setup, _ = view.reduced_setup(light.focus_nm)
    if light.is_white:
        psf = _psf(setup.wavefront, step, mode, wavelength_nm=light.wavelengths_nm, weights=light.weights,
                   lca_reference_nm=light.focus_nm)
    else:
        psf = _psf(setup.wavefront, step, mode, wavelength_nm=light.focus_nm)
    return _blur_psf(image, psf, step)
