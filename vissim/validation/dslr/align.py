"""Aligning a simulation onto the truth it is compared with.

**Alignment.**  A simulation of the bench's no-lens render is registered onto the truth and
shifted there (cubic spline): that render exists only at the campaign's sampling.  A
simulation of the synthetic chart is aligned on the fine grid instead: the fine chart is
shifted by the accumulated offset, simulated and registered again, until the remaining
registration is below `ALIGN_TOLERANCE_PX` (at most `MAX_ALIGN_PASSES` passes);
the simulated image is compared as it comes, never resampled.  One registration of the
under-sampled result is biased by 0.01-0.03 px, and shifting it by a spline costs accuracy:
together they held six astigmatic configurations of the thesis campaign (N, K x 180, Z x 90)
at -0.1...+1.8 dB over the noise floor, for geometric optics that reaches it elsewhere.
"""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np

from vissim.imaging.registration import Registration, register
from vissim.lazy_import import lazy_module

ndimage = lazy_module("scipy.ndimage")

__all__ = ["align", "ALIGN_TOLERANCE_PX", "MAX_ALIGN_PASSES", "MAX_SHIFT_PX", "UNREGISTERED"]

log = logging.getLogger(__name__)


#: The fine pre-alignment stops when the registration left is below this in both axes (px) ...
ALIGN_TOLERANCE_PX = 0.01


#: ... or after this many simulations (the thesis campaign: 1-3 passes for 482 of its 497 fine
#: alignments; 15 reached 4, 11 of them with one 0.01 px step left).
MAX_ALIGN_PASSES = 4


#: Registrations resolve 1/100 px: "below 0.01 px" is then "measured as 0", within 0.005 px.
REGISTRATION_UPSAMPLE = 100


FINE_ALIGNMENT = ("fine pre-alignment: the fine input shifted (cubic spline) by the accumulated registration "
                  f"(cross-correlation, normalization=None) until < {ALIGN_TOLERANCE_PX:g} px is left; "
                  "the simulated image itself is not resampled")


def _fine_shift(image: np.ndarray, offset_px: tuple[float, float], oversample: int) -> np.ndarray:
    if offset_px == (0.0, 0.0):
        return image
    return ndimage.shift(image, (offset_px[0] * oversample, offset_px[1] * oversample), order=3, mode="nearest")


def align(reference: np.ndarray, simulate_fine, image: np.ndarray, oversample: int,
          start_px: tuple[float, float] = (0.0, 0.0)) -> tuple[Registration, dict]:
    """``simulate_fine(image)`` aligned onto ``reference``: the registration (with the image) and its record.

    ``oversample == 1`` (the no-lens render): one registration, the result shifted onto the
    reference.  Finer inputs: the module docstring's fine pre-alignment, from ``start_px`` (a
    previous simulation's offset; the letter's placement is the same for every simulation).
    The recorded shift is the offset applied to the input, in campaign pixels.
    """
    if oversample == 1:
        registration = register(reference, simulate_fine(image), upsample_factor=REGISTRATION_UPSAMPLE)
        return registration, registration.as_json()
    offset = (float(start_px[0]), float(start_px[1]))
    for passes in range(1, MAX_ALIGN_PASSES + 1):
        simulated = simulate_fine(_fine_shift(image, offset, oversample))
        residual = register(reference, simulated, upsample_factor=REGISTRATION_UPSAMPLE)
        if max(abs(residual.shift_rows_px), abs(residual.shift_cols_px)) < ALIGN_TOLERANCE_PX:
            break
        if passes < MAX_ALIGN_PASSES:
            offset = (offset[0] + residual.shift_rows_px, offset[1] + residual.shift_cols_px)
    else:
        log.info("fine alignment stopped after %d passes with (%.3f, %.3f) px left", MAX_ALIGN_PASSES,
                 residual.shift_rows_px, residual.shift_cols_px)
    registration = replace(residual, shift_rows_px=offset[0], shift_cols_px=offset[1], registered=simulated)
    record = {**registration.as_json(), "method": FINE_ALIGNMENT, "passes": passes,
              "residual_px": [residual.shift_rows_px, residual.shift_cols_px]}
    return registration, record


#: The wave bench's truth and a simulation share one grid: nothing is registered (module wave_bench).
UNREGISTERED = {"shift_rows_px": 0.0, "shift_cols_px": 0.0, "error": None, "upsample_factor": None,
                "method": "none: the wave truth and the simulation are laid out on one grid from one chart"}


#: Registration may not move an image further than this (px); more means a wrong crop.
MAX_SHIFT_PX = 6.0
