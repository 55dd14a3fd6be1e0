"""Image-comparison metrics for validation: SSIM, PSNR and absolute difference, numbers and maps.

Every metric needs the images' value range, ``data_range`` (for linear light normalised to
[0, 1], ``data_range=1.0``).  It is a required argument and is never guessed from the dtype:
a 14-bit RAW in ``uint16`` or a float render whose highlights exceed 1 would get the wrong
range, and SSIM's stabilising constants and PSNR's peak both depend on it.

* **SSIM** is Wang, Bovik, Sheikh & Simoncelli 2004 (IEEE TIP 13:600), as the paper computes
  it: an 11 x 11 Gaussian window with sigma 1.5 px, population (not sample) covariances,
  K1 = 0.01 and K2 = 0.03 -- `skimage.metrics.structural_similarity` with
  ``gaussian_weights=True, sigma=1.5, use_sample_covariance=False``.  The mean SSIM is the mean
  of the SSIM map *after* removing a 5 px border (half the window) where the window leaves the
  image; the map itself is returned full-size.
* **PSNR** is ``10 log10(data_range**2 / MSE)`` dB (`psnr_db`: the one PSNR of vissim, computed as
  `skimage.metrics.peak_signal_noise_ratio` computes it); identical images give ``inf``.
* **Absolute difference** is ``|reference - test|`` per pixel and its mean.

Images are ``(H, W)`` or ``(H, W, C)`` with channels last; SSIM of a colour image is the mean
over channels (scikit-image's ``channel_axis=-1``).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from typing import Any

import numpy as np

from vissim.checks import size_text
from vissim.errors import VissimInputError
from vissim.lazy_import import lazy_module

skimage_metrics = lazy_module("skimage.metrics")

logger = logging.getLogger(__name__)

__all__ = ["SSIM_SETTINGS", "Comparison", "compare_images", "noise_floor", "psnr_db"]

#: Wang et al. 2004's SSIM, in scikit-image's terms (record it in a campaign's manifest).
SSIM_SETTINGS = {"gaussian_weights": True, "sigma": 1.5, "use_sample_covariance": False, "K1": 0.01, "K2": 0.03}
_SSIM_WINDOW_PX = 11  # 2 * int(3.5 * sigma + 0.5) + 1 for sigma = 1.5: scikit-image's Gaussian window


@dataclasses.dataclass(frozen=True)
class Comparison:
    """How far ``test`` is from ``reference``: summary numbers and per-pixel maps.

    ``ssim`` (unitless, 1 = identical), ``psnr_db`` (decibels, ``inf`` for identical
    images), ``mse`` and ``mean_abs_diff`` (in the images' units, squared for MSE).  Maps have
    the images' shape: ``ssim_map`` (local SSIM), ``squared_error_map`` ((ref - test)**2) and
    ``abs_diff_map`` (|ref - test|).
    """

    ssim: float
    psnr_db: float
    mse: float
    mean_abs_diff: float
    max_abs_diff: float
    data_range: float
    shape: tuple[int, ...]
    ssim_map: np.ndarray = dataclasses.field(repr=False)
    squared_error_map: np.ndarray = dataclasses.field(repr=False)
    abs_diff_map: np.ndarray = dataclasses.field(repr=False)

    def as_json(self) -> dict[str, Any]:
        """The numbers (no maps), JSON-ready; an infinite PSNR is written as the string ``"inf"``."""
        out = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if not f.name.endswith("_map")}
        return out | {"psnr_db": self.psnr_db if math.isfinite(self.psnr_db) else "inf", "shape": list(self.shape)}


def psnr_db(mse: float, data_range: float) -> float:
    """PSNR, dB, of a mean squared error ``mse`` (image units squared) at peak ``data_range`` (image units).

    ``10 log10(data_range**2 / mse)`` with numpy's ``log10``, as `skimage.metrics.peak_signal_noise_ratio`
    computes it (Python's `math.log10` differs from it in the last bit for about 1 % of values); ``inf``
    when ``mse`` is 0 (identical images).
    """
    return math.inf if mse == 0.0 else float(10 * np.log10(data_range**2 / mse))


def _check_data_range(data_range: Any) -> float:
    try:
        value = float(data_range)
    except (TypeError, ValueError):
        raise VissimInputError(
            f"data_range must be the images' value range as a number (image units, e.g. 1.0 for "
            f"linear light in [0, 1]), got {data_range!r}; it is never guessed from the dtype"
        ) from None
    if not math.isfinite(value) or value <= 0.0:
        raise VissimInputError(f"data_range must be finite and > 0 (image units), got {value!r}")
    return value


def _as_image(image: Any, name: str) -> np.ndarray:
    array = np.asarray(image)
    if not (np.issubdtype(array.dtype, np.number) and not np.iscomplexobj(array)):
        raise VissimInputError(f"{name} image must hold real numbers, got dtype {array.dtype}")
    array = array.astype(np.float64)
    if array.ndim not in (2, 3):
        raise VissimInputError(f"{name} image must have shape (H, W) or (H, W, C), got {array.shape}")
    if min(array.shape[:2]) < _SSIM_WINDOW_PX:
        raise VissimInputError(
            f"{name} image is {size_text(array.shape)}; SSIM's Gaussian window needs at least "
            f"{size_text((_SSIM_WINDOW_PX, _SSIM_WINDOW_PX))}"
        )
    if not np.all(np.isfinite(array)):
        raise VissimInputError(f"{name} image has NaN or infinite pixels")
    return array


def compare_images(reference: Any, test: Any, *, data_range: float) -> Comparison:
    """Compare ``test`` with ``reference`` (same shape, ``(H, W)`` or ``(H, W, C)``).

    Parameters
    ----------
    reference : array_like
        The reference image (e.g. linear light).  Computed in float64.
    test : array_like
        The image compared with it, in the same units and shape.
    data_range : float
        The value range of the images' units (max possible minus min possible value), e.g.
        1.0 for linear light in [0, 1].  Required: never inferred from the dtype.

    Returns
    -------
    Comparison
    """
    data_range = _check_data_range(data_range)
    ref = _as_image(reference, "reference")
    tst = _as_image(test, "test")
    if ref.shape != tst.shape:
        raise VissimInputError(f"reference is {size_text(ref.shape)} but test is {size_text(tst.shape)}; sizes must match")
    channel_axis = -1 if ref.ndim == 3 else None
    ssim, ssim_map = skimage_metrics.structural_similarity(ref, tst, data_range=data_range, channel_axis=channel_axis, full=True,
                                           **SSIM_SETTINGS)
    diff = ref - tst
    squared = diff * diff
    absolute = np.abs(diff)
    mse = float(squared.mean())
    psnr = psnr_db(mse, data_range)
    result = Comparison(
        ssim=float(ssim), psnr_db=psnr, mse=mse, mean_abs_diff=float(absolute.mean()),
        max_abs_diff=float(absolute.max()), data_range=data_range, shape=tuple(ref.shape),
        ssim_map=ssim_map, squared_error_map=squared, abs_diff_map=absolute,
    )
    logger.debug("compared %s images: SSIM %.4f, PSNR %.2f dB, mean AD %.3g", ref.shape, result.ssim, psnr,
                 result.mean_abs_diff)
    return result


def noise_floor(render_a: Any, render_b: Any, data_range: float) -> Comparison:
    """The Monte-Carlo noise floor: `compare_images` of two renders of one scene, two seeds.

    A render cannot match a reference better than it matches itself re-rendered with another
    seed; metrics against a reference are read against this comparison.  Identical inputs (the
    same seed twice, or a noise-free renderer) are allowed but logged as a warning, since they
    make the floor perfect (SSIM 1, PSNR ``inf``).
    """
    result = compare_images(render_a, render_b, data_range=data_range)
    if result.mse == 0.0:
        logger.warning("noise floor from identical renders: were the two seeds the same?")
    return result
