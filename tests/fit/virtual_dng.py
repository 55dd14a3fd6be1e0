"""A linear image as a virtual DNG capture, read back through rawpy (the campaign's RAW path).

The image (reflectance, paper 0.9) is exposed at 60 % of full scale under a warm light (the
colour channels see different levels), sampled through an RGGB Bayer filter, given photon shot
noise (30 000 e- full well) and 2 e- read noise, quantised (black 2048, white 15000 DN) and
written as a DNG (:mod:`vissim.imaging.virtual_capture`).  It is read back with
:func:`vissim.imaging.raw.read_raw_linear` (CFA planes, levels from the file) and made grey
again as the campaign's capture path does: each CFA plane divided by its paper level
(:func:`vissim.validation.dslr.captures.neutral_mosaic`, paper from the tile's 4-px border), times 0.9.
"""

from __future__ import annotations

import numpy as np

from vissim.validation.dslr.captures import neutral_mosaic
from vissim.imaging.raw import read_raw_linear
from vissim.imaging.virtual_capture import add_sensor_noise, mosaic_bayer, quantise, write_dng

GAINS = np.array([0.55, 1.0, 0.45])
PAPER = 0.9
EXPOSURE = 0.6  # paper at this fraction of full scale
BORDER_PX = 4


def through_virtual_dng(linear: np.ndarray, path, seed: int) -> np.ndarray:
    """``linear`` (H, W; H, W even) after the virtual camera, the DNG and rawpy: the capture tile (paper 0.9)."""
    radiance = np.clip(np.asarray(linear, dtype=np.float64), 0.0, None) / PAPER * EXPOSURE
    mosaic = mosaic_bayer(radiance[..., None] * GAINS, "RGGB")
    noisy = add_sensor_noise(mosaic, full_well_electrons=30000, read_noise_electrons=2.0, rng=seed)
    write_dng(path, quantise(noisy, black_level=2048, white_level=15000), black_level=2048, white_level=15000,
              pattern="RGGB", overwrite=True)
    raw = read_raw_linear(path, mode="planes")
    border = np.ones(raw.pixels.shape[:2], dtype=bool)
    b = BORDER_PX // 2
    border[b:-b, b:-b] = False
    return neutral_mosaic(raw.pixels, border, raw.sensor_px_per_pixel) * PAPER
