"""Synthetic bench captures made by vissim's own forward chain (not by :mod:`vissim.fit.forward`).

The chart is rendered ``OVERSAMPLE`` times finer than the capture, magnified by the bench's
spectacle magnification (:func:`vissim.optics.blur.resample.magnify`), blurred by the PSF of the
bench's :class:`~vissim.optics.rx.viewing_setup.ViewingSetup` (:func:`vissim.optics.psf.compute.compute_psf`, ray
histogram or wave optics), shifted, integrated onto the capture's pixels
(:func:`~vissim.optics.blur.resample.block_mean`) and given Gaussian noise: the path the campaign's
simulations take (``vissim.validation.dslr.simulate.simulate(..., oversample=5)``).  The fit's own
model (analytic OTF, blur before magnification) shares none of it but the ViewingSetup.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.ndimage

from vissim.bench.dslr.bench import DslrBench
from vissim.charts import optotype_tile
from vissim.optics.blur.convolve import blur_image
from vissim.optics.psf.compute import compute_psf, suggested_size_px
from vissim.optics.blur.resample import block_mean, magnify
from vissim.optics.rx.trial_lens import TrialLens

OVERSAMPLE = 4
SHAPE = (96, 96)
BENCH = DslrBench(size_px=SHAPE)


def effective_vector(lens: TrialLens | None, bench: DslrBench = BENCH) -> np.ndarray:
    """The power the lens (made physical as the bench makes it) adds at the camera: (M, J0, J45), dioptres."""
    d = np.asarray(dataclasses.replace(bench, lenses=() if lens is None else (lens,)).viewing_setup().defocus_matrix_diopters)
    return np.array([0.5 * (d[0, 0] + d[1, 1]), 0.5 * (d[0, 0] - d[1, 1]), d[0, 1]])


def capture(lens: TrialLens | None, *, letter: str = "K", logmar: float = 1.0, mode: str = "geometric",
            shift_rc=(0.3, -0.4), noise: float = 0.002, seed: int = 0, reference_noise: float = 0.0,
            magnification: bool = True, bench: DslrBench = BENCH):
    """(image, reference, truth (M, J0, J45)) at 1 arcmin/px, ``SHAPE`` px."""
    q = OVERSAMPLE
    step = 1.0 / q
    fine = optotype_tile(letter, logmar, arcmin_per_px=step, size_px=(SHAPE[0] * q, SHAPE[1] * q)).pixels
    rng = np.random.default_rng(seed)
    reference = block_mean(fine, q).astype(np.float64) + reference_noise * rng.standard_normal(SHAPE)
    setup = dataclasses.replace(bench, lenses=() if lens is None else (lens,)).viewing_setup()
    seen = magnify(fine, setup.magnification_matrix) if magnification else fine
    front = setup.wavefront
    size = suggested_size_px(front, step, wavelength_nm=setup.wavelength_nm)
    psf = compute_psf(front, arcmin_per_px=step, size_px=size, mode=mode, wavelength_nm=setup.wavelength_nm)
    blurred = blur_image(seen, psf, arcmin_per_px=step, padding="edge").astype(np.float64)
    moved = scipy.ndimage.shift(blurred, (shift_rc[0] * q, shift_rc[1] * q), order=3, mode="nearest")
    image = block_mean(moved, q).astype(np.float64) + noise * rng.standard_normal(SHAPE)
    return image, reference, effective_vector(lens, bench)
