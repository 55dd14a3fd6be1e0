"""The fit's input checks: two real 2-D images of one size with structure, a sharp reference, and the settings.

Bad inputs raise one `VissimInputError` (or `VissimTypeError`) that names what is wrong,
before any fitting starts.
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.checks import MODEL_ERROR_RANGE_DIOPTERS, describe, size_text
from vissim.checks import pupil_diameter_mm as check_pupil_mm
from vissim.errors import VissimInputError, VissimTypeError
from vissim.fit.forward import FORWARD_MODES
from vissim.fit.power_model import MAGNIFICATION_MODELS

__all__ = ["check_fit_inputs", "check_fit_arguments", "reference_sharpness", "MIN_REFERENCE_SHARPNESS",
           "MIN_CONTRAST_OVER_NOISE"]

#: A sharp reference's steepest step is at least this fraction of its contrast (an edge spread <~ 3 px).
MIN_REFERENCE_SHARPNESS = 0.3
#: An image has structure when its contrast exceeds this many times its pixel-to-pixel noise.
MIN_CONTRAST_OVER_NOISE = 8.0


def _as_image(value: Any, name: str) -> np.ndarray:
    if isinstance(value, (str, bytes, os.PathLike)):
        raise VissimTypeError(f"the {name} must be an ndarray of linear light (read a file with "
                              f"vissim.imageio.read_image(path).pixels), got {describe(value)}")
    array = np.asarray(value)
    if array.ndim == 3 and array.shape[2] == 3:
        raise VissimInputError(f"the {name} has 3 channels; fit one channel (or luminance) at a time")
    if array.ndim != 2 or min(array.shape) < 16:
        raise VissimInputError(f"the {name} must be one 2-D channel of at least 16 x 16 px, got shape {array.shape}")
    if not np.issubdtype(array.dtype, np.number) or np.iscomplexobj(array):
        raise VissimInputError(f"the {name} must hold real numbers, got dtype {array.dtype}")
    array = array.astype(np.float64)
    if not np.all(np.isfinite(array)):
        raise VissimInputError(f"the {name} has NaN or infinite pixels")
    return array


def _contrast(image: np.ndarray) -> float:
    low, high = np.percentile(image, (0.5, 99.5))
    return float(high - low)


def _pixel_noise(image: np.ndarray) -> float:
    """Robust pixel noise: the MAD of horizontal and vertical differences / sqrt 2 (0 for noise-free renders)."""
    diffs = np.concatenate([np.diff(image, axis=0).ravel(), np.diff(image, axis=1).ravel()])
    return float(1.4826 * np.median(np.abs(diffs - np.median(diffs))) / math.sqrt(2.0))


def reference_sharpness(reference: np.ndarray) -> float:
    """The steepest pixel step (99.9th percentile of |differences|) over the contrast: ~0.5-1 when sharp."""
    diffs = np.concatenate([np.abs(np.diff(reference, axis=0)).ravel(), np.abs(np.diff(reference, axis=1)).ravel()])
    return float(np.percentile(diffs, 99.9) / max(_contrast(reference), 1e-300))


def check_fit_inputs(image: Any, reference: Any) -> tuple[np.ndarray, np.ndarray]:
    """The two images as float64 arrays, or one `VissimInputError` naming what is wrong."""
    img = _as_image(image, "image")
    ref = _as_image(reference, "reference")
    if img.shape != ref.shape:
        raise VissimInputError(f"the image is {size_text(img.shape)} but the reference is {size_text(ref.shape)}; "
                               "they must match, pixel for pixel")
    for array, name in ((img, "image"), (ref, "reference")):
        contrast, noise = _contrast(array), _pixel_noise(array)
        if contrast <= max(MIN_CONTRAST_OVER_NOISE * noise, 1e-9 * max(1.0, float(np.abs(array).max()))):
            raise VissimInputError(f"the {name} has no structure to fit: contrast {contrast:.3g} against pixel "
                                   f"noise {noise:.3g} (linear units); it needs a chart or letter")
    sharpness = reference_sharpness(ref)
    if sharpness < MIN_REFERENCE_SHARPNESS:
        raise VissimInputError(
            f"the reference is itself blurred: its steepest step is {sharpness:.2f} of its contrast (a sharp "
            f"reference has >= {MIN_REFERENCE_SHARPNESS}); give the no-lens capture or the chart")
    return img, ref


def check_fit_arguments(image, reference, arcmin_per_px, pupil_diameter_mm, mode: str, magnification: str,
                        model_error_diopters) -> tuple[float, float, np.ndarray, np.ndarray, float]:
    """Checks: (arcmin per px, pupil mm, image, reference, model error D), or a `VissimInputError`."""
    step = check_arcmin_per_px(arcmin_per_px)
    pupil = check_pupil_mm(pupil_diameter_mm)
    if mode not in FORWARD_MODES:
        raise VissimInputError(f"fit mode must be one of {', '.join(FORWARD_MODES)}, got {mode!r}")
    if magnification not in MAGNIFICATION_MODELS:
        raise VissimInputError(f"magnification model must be one of {', '.join(MAGNIFICATION_MODELS)}, got {magnification!r}")
    img, ref = check_fit_inputs(image, reference)
    model_error_diopters = float(model_error_diopters)
    low, high = MODEL_ERROR_RANGE_DIOPTERS
    if not (math.isfinite(model_error_diopters) and low <= model_error_diopters <= high):
        raise VissimInputError(f"the model error must be within {low:g}-{high:g} D, got {model_error_diopters!r} D")
    return step, pupil, img, ref, model_error_diopters
