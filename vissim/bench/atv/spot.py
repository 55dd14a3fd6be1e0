"""The spot metrics every ATV method reports (paraxial prediction, light tracer, virtual ATV).

`spot_metrics`: ``total_flux`` is the image's integral;
``spot_diameter_arcmin`` the **full width at half maximum of the azimuthally averaged radial
profile** about the centroid (1-pixel annuli centred on whole radii,
`vissim.optics.psf.metrics.ring_means`; the outermost crossing of half the peak, linearly
interpolated).  For a uniform blur disc of diameter D it is D (the pixel's square blurs the
edge symmetrically); for the in-focus square pixel of side s it is ``s / cos(22.5°) = 1.082 s``
(the radius at which half of a circle lies inside the square).
``peak`` is the largest value of the image smoothed by a Gaussian of sigma = FWHM / 20 (none
below sigma = 0.5 px): it leaves the plateau of a blur disc and the in-focus square exact
(their edges lie > 8 sigma from the maximum), lowers a Gaussian spot's peak by 1.4 %, and cuts
the Monte Carlo noise of a large disc's plateau ~20-fold, where the largest raw pixel is biased
up by ~3 standard deviations of its noise.  ``peak_pixel`` is that largest raw pixel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vissim.bench.atv.tube import AtvConfig
from vissim.bench.atv.paraxial import atv_paraxial
from vissim.errors import VissimInputError
from vissim.lazy_import import lazy_module
from vissim.optics.psf.metrics import ring_means

scipy_ndimage = lazy_module("scipy.ndimage")

__all__ = ["SpotMetrics", "spot_metrics", "suggested_atv_size_px"]


@dataclass(frozen=True)
class SpotMetrics:
    """Summary numbers of a retinal image (module doc for the definitions)."""

    total_flux: float
    peak: float
    peak_pixel: float
    peak_relative_std: float  # of ``peak``, from a standard-error image (nan without one)
    spot_diameter_arcmin: float
    centroid_arcmin: tuple[float, float]  # (right, up) from straight ahead
    peak_smoothing_px: float  # sigma of the Gaussian behind ``peak`` (0: none)


def _half_max_diameter_px(where: np.ndarray, profile: np.ndarray, half: float) -> float:
    """Twice the radius where the profile last falls below ``half``, searched from the outside.

    From the outside, because outside a traced spot there is no light and hence no noise,
    while noise inside the spot can dip below half of a peak.
    """
    above = np.nonzero(profile >= half)[0]
    if not above.size or above[-1] + 1 >= profile.size:
        return math.nan  # no light, or the spot reaches the edge of the field
    k = int(above[-1])
    r0, r1, p0, p1 = where[k], where[k + 1], profile[k], profile[k + 1]
    return 2.0 * (r0 + (p0 - half) * (r1 - r0) / (p0 - p1))


def spot_metrics(image, arcmin_per_px: float, std_image=None) -> SpotMetrics:
    """Flux, peak, radial-profile FWHM and centroid of ``image`` (flux per arcmin², vissim grid).

    ``std_image``, the per-pixel standard error when known, gives ``peak_relative_std``.
    """
    data = np.asarray(image, dtype=float)
    step = float(arcmin_per_px)
    if data.ndim != 2 or min(data.shape) < 1 or not np.all(np.isfinite(data)):
        raise VissimInputError(f"a spot image must be a finite 2-D array, got shape {data.shape}")
    if not math.isfinite(step) or step <= 0.0:
        raise VissimInputError(f"angular sampling must be > 0 arcmin per pixel, got {arcmin_per_px!r}")
    total = float(data.sum())
    if total <= 0.0:
        return SpotMetrics(0.0, 0.0, 0.0, math.nan, math.nan, (math.nan, math.nan), 0.0)
    rows, cols = np.indices(data.shape)
    cy, cx = float((rows * data).sum() / total), float((cols * data).sum() / total)
    where, profile = ring_means(data, np.hypot(rows - cy, cols - cx))
    first = _half_max_diameter_px(where, profile, 0.5 * profile.max())
    sigma = first / 20.0 if math.isfinite(first) and first >= 10.0 else 0.0
    smoothed = scipy_ndimage.gaussian_filter(data, sigma, mode="constant") if sigma else data
    at = np.unravel_index(int(np.argmax(smoothed)), data.shape)
    fwhm_px = _half_max_diameter_px(where, profile, 0.5 * float(smoothed[at])) if sigma else first
    relative_std = math.nan
    if std_image is not None:
        variance = np.square(np.asarray(std_image, dtype=float))
        if sigma:  # a normalised Gaussian g has sum(g^2) = 1 / (4 pi sigma^2), g^2 ~ Gaussian of sigma / sqrt 2
            variance = scipy_ndimage.gaussian_filter(variance, sigma / math.sqrt(2.0), mode="constant")
            variance /= 4.0 * math.pi * sigma**2
        relative_std = float(math.sqrt(variance[at]) / smoothed[at]) if smoothed[at] > 0 else math.inf
    n0, n1 = data.shape
    return SpotMetrics(total_flux=total * step * step, peak=float(smoothed[at]), peak_pixel=float(data.max()),
                       peak_relative_std=relative_std, spot_diameter_arcmin=float(fwhm_px * step),
                       centroid_arcmin=((cx - n1 // 2) * step, -(cy - n0 // 2) * step),
                       peak_smoothing_px=float(sigma))


def suggested_atv_size_px(config: AtvConfig, arcmin_per_px: float, margin_arcmin: float = 4.0) -> int:
    """An odd image size holding the blur, the pixel and its offset, with ``margin_arcmin`` each side."""
    par = atv_paraxial(config)
    reach = 0.5 * (par.blur_diameter_arcmin + math.sqrt(2.0) * par.pixel_angle_arcmin) + margin_arcmin
    reach += max(abs(v) for v in par.pixel_direction_arcmin)
    return 2 * int(math.ceil(reach / float(arcmin_per_px))) + 1
