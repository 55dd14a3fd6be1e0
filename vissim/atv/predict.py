"""The ATV tube's retinal image from first-order optics.

The tube is equivalent to a source at (or near) infinity of the pixel's angular extent: the
retinal image is the pixel's square, mapped by the paraxial system (spectacle magnification
included), convolved with the eye's blur for the defocus ``K = vergence + E + A`` at the pupil
(`vissim.bench.atv.paraxial.atv_paraxial`).  The blur comes from `vissim.optics.psf.compute.compute_psf` of
the prescription ``-K``: ``mode="geometric"`` (ray optics, comparable with the light tracer)
or ``"wave"`` (diffraction).  Pure numpy; no Mitsuba.

**Image units.**  An image holds the flux reaching the retina per arcmin² of visual field,
``pixel_radiance x m² x sr / arcmin²`` (W / arcmin² for a radiance in W m⁻² sr⁻¹; lm / arcmin²
for a luminance in cd m⁻²), on the vissim grid: row 0 up, columns to the eye's right, the
straight-ahead direction at ``[N//2, N//2]``, each pixel the integral over its square.

The spot metrics every method reports are `vissim.bench.atv.spot.spot_metrics`.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from vissim.checks import DEFAULT_WAVELENGTH_NM
from vissim.bench.atv.tube import AtvConfig
from vissim.bench.atv.paraxial import AtvParaxial, atv_paraxial
from vissim.bench.atv.spot import spot_metrics, suggested_atv_size_px
from vissim.errors import VissimInputError
from vissim.lazy_import import lazy_module
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf
from vissim.optics.pupil.wavefront import Wavefront
from vissim.units import arcmin_to_rad, mm_to_m

scipy_signal = lazy_module("scipy.signal")

__all__ = ["AtvPrediction", "predicted_spot", "fresnel_transmittance"]

log = logging.getLogger(__name__)

#: Fine samples across the pixel's image, at least.
_FINE_PER_PIXEL_ANGLE = 6.0


def fresnel_transmittance(config: AtvConfig) -> float:
    """Product of the normal-incidence Fresnel transmittances of the lens surfaces (1 without loss)."""
    if not config.fresnel_loss:
        return 1.0
    indices = [config.tube.lens_refractive_index] * 2
    if config.trial_lens is not None:
        indices += [config.trial_lens.refractive_index] * 2
    return float(np.prod([1.0 - ((n - 1.0) / (n + 1.0)) ** 2 for n in indices]))


@dataclass(frozen=True, eq=False)
class AtvPrediction:
    """The paraxial retinal image of the pixel and its metrics (units: module doc)."""

    image: np.ndarray
    arcmin_per_px: float
    mode: str
    total_flux: float
    peak: float
    peak_pixel: float
    spot_diameter_arcmin: float
    centroid_arcmin: tuple[float, float]
    blur_diameter_arcmin: float  # pupil x |defocus|, the geometric blur disc
    pixel_angle_arcmin: float  # side of the pixel's image
    defocus_diopters: float  # spherical equivalent of vergence + eye error + accommodation
    paraxial: AtvParaxial


def _overlap_1d(grid: np.ndarray, low: float, high: float) -> np.ndarray:
    """Length of [low, high] inside each unit cell centred on ``grid``."""
    return np.clip(np.minimum(grid + 0.5, high) - np.maximum(grid - 0.5, low), 0.0, None)


def _pixel_kernel(par: AtvParaxial, pitch_mm: float, offset_mm, fine_arcmin: float) -> np.ndarray:
    """Coverage of the pixel's image on the fine grid, unit sum, origin at its centre element.

    Exact (separable box overlaps) when the image is an axis-aligned rectangle; a rotated or
    sheared one (an oblique cylinder) is supersampled 16 x 16 per fine pixel.
    """
    to_rad = float(arcmin_to_rad(fine_arcmin))
    mapping = par.pixel_angle_matrix / to_rad  # screen offset (m) -> visual angle (fine px), world x/y
    half_m = mm_to_m(0.5 * pitch_mm)
    offset_m = mm_to_m(np.asarray(offset_mm, dtype=float))
    corners = np.array([[sx, sy] for sx in (-1.0, 1.0) for sy in (-1.0, 1.0)]) * half_m + offset_m
    half = int(math.ceil(np.abs(corners @ mapping.T).max())) + 1
    grid = np.arange(-half, half + 1, dtype=float)
    if abs(mapping[0, 1]) + abs(mapping[1, 0]) <= 1e-9 * np.abs(mapping).max():
        # image right = -x, up = -row: the column of world x is -x, the row of world y is -y
        x_lo, x_hi = sorted(-mapping[0, 0] * (offset_m[0] + np.array([-half_m, half_m])))
        y_lo, y_hi = sorted(-mapping[1, 1] * (offset_m[1] + np.array([-half_m, half_m])))
        kernel = np.outer(_overlap_1d(grid, y_lo, y_hi), _overlap_1d(grid, x_lo, x_hi))
    else:
        samples = 16
        sub = (np.arange(samples) + 0.5) / samples - 0.5
        axis = (grid[:, None] + sub[None, :]).ravel()
        rows, cols = np.meshgrid(axis, axis, indexing="ij")
        screen = np.stack([-cols, -rows], axis=-1) @ np.linalg.inv(mapping).T - offset_m
        inside = np.all(np.abs(screen) <= half_m, axis=-1)
        kernel = inside.reshape(grid.size, samples, grid.size, samples).mean(axis=(1, 3))
    if kernel.sum() <= 0.0:  # pragma: no cover - the kernel always holds the pixel
        raise VissimInputError(f"the pixel's image misses the {fine_arcmin:g} arcmin grid")
    return kernel / kernel.sum()


def predicted_spot(config: AtvConfig, *, arcmin_per_px: float = 0.5, size_px: int | None = None,
                   mode: str = "geometric", wavelength_nm: float = DEFAULT_WAVELENGTH_NM) -> AtvPrediction:
    """The retinal image of the pixel by first-order optics (module doc).

    ``mode="geometric"`` convolves the pixel's square with the geometric blur of the defocus
    (what the light tracer should find); ``"wave"`` with the diffraction PSF at
    ``wavelength_nm``.  ``size_px`` defaults to `suggested_atv_size_px`.
    """
    if mode not in ("geometric", "wave"):
        raise VissimInputError(f"prediction mode must be 'geometric' or 'wave', got {mode!r}")
    step = float(arcmin_per_px)
    if not math.isfinite(step) or step <= 0.0:
        raise VissimInputError(f"angular sampling must be > 0 arcmin per pixel, got {arcmin_per_px!r}")
    size = suggested_atv_size_px(config, step) if size_px is None else size_px
    if int(size) != size or not 1 <= size <= 4096:
        raise VissimInputError(f"image size must be a whole number of pixels in 1-4096, got {size_px!r}")
    size = int(size)
    par = atv_paraxial(config)
    odd = size | 1  # an odd grid keeps the fine and coarse origins aligned; cropped at the end
    fine_factor = max(1, math.ceil(step * _FINE_PER_PIXEL_ANGLE / par.pixel_angle_arcmin))
    fine_factor += 1 - fine_factor % 2  # odd
    fine = step / fine_factor
    pupil = config.eye.pupil_diameter_mm
    rx = Prescription.from_power_matrix(-par.defocus_matrix_diopters)
    psf = compute_psf(Wavefront.from_prescription(rx, pupil), pupil_diameter_mm=pupil, wavelength_nm=wavelength_nm,
                      arcmin_per_px=fine, size_px=odd * fine_factor, mode=mode)
    kernel = _pixel_kernel(par, config.tube.pixel_pitch_mm, config.tube.pixel_offset_mm, fine)
    fine_image = np.maximum(scipy_signal.fftconvolve(psf.data, kernel, mode="same"), 0.0)
    coarse = fine_image.reshape(odd, fine_factor, odd, fine_factor).sum(axis=(1, 3))[:size, :size]
    flux = config.tube.pixel_radiance * par.etendue_m2_sr * fresnel_transmittance(config)
    image = (flux * coarse / step**2).astype(np.float32)
    metrics = spot_metrics(image, step)
    log.debug("ATV prediction (%s): defocus %s D, blur %.3g', pixel %.3g', flux %.4g", mode,
              rx, par.blur_diameter_arcmin, par.pixel_angle_arcmin, flux)
    return AtvPrediction(image=image, arcmin_per_px=step, mode=mode, total_flux=flux, peak=metrics.peak,
                         peak_pixel=metrics.peak_pixel, spot_diameter_arcmin=metrics.spot_diameter_arcmin,
                         centroid_arcmin=metrics.centroid_arcmin, blur_diameter_arcmin=par.blur_diameter_arcmin,
                         pixel_angle_arcmin=par.pixel_angle_arcmin,
                         defocus_diopters=float(np.trace(par.defocus_matrix_diopters) / 2.0), paraxial=par)
