"""What every bench's truth shares: the aperture's diffraction added to a render, and the PSFs a simulation uses.

Mitsuba renders no diffraction, so a wave-optical simulation is compared with the render
convolved with the aperture's in-focus diffraction PSF (`add_bench_diffraction`).  PSFs are
cached by viewing setup, sampling and optics (`cached_psf`), so every item of a campaign that
shares them computes them once.
"""

from __future__ import annotations

import functools

import numpy as np

from vissim.optics.blur.convolve import blur_image
from vissim.optics.psf.compute import PSF, compute_psf
from vissim.optics.rx.viewing_setup import ViewingSetup

__all__ = ["cached_psf", "add_bench_diffraction"]


def cached_psf(setup: ViewingSetup, arcmin_per_px: float, mode: str) -> PSF:
    """The pixel-integrated PSF of ``setup``'s wavefront (magnification left out), ``mode`` wave or geometric."""
    return _cached_psf(setup.without_magnification(), arcmin_per_px, mode)


@functools.lru_cache(maxsize=64)
def _cached_psf(setup: ViewingSetup, arcmin_per_px: float, mode: str) -> PSF:
    return compute_psf(setup.wavefront, wavelength_nm=setup.wavelength_nm, arcmin_per_px=arcmin_per_px, size_px="auto",
                       mode=mode, pixel="integrate")


def add_bench_diffraction(render: np.ndarray, bench: ViewingSetup, arcmin_per_px: float) -> np.ndarray:
    """The render convolved with the diffraction PSF of ``bench``'s pupil, in focus (no aberration)."""
    psf = cached_psf(bench.in_focus(), arcmin_per_px, "wave")
    return blur_image(render, psf, arcmin_per_px=arcmin_per_px, padding="edge")
