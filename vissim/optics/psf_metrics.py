"""Quantities derived from a sampled :class:`~vissim.optics.psf.PSF`: OTF, MTF, encircled energy."""

from __future__ import annotations

import numpy as np
import scipy.fft

from vissim.optics.psf import PSF
from vissim.units import cyc_per_rad_to_cyc_per_deg, nm_to_mm

__all__ = ["otf", "mtf", "frequencies_cyc_per_deg", "encircled_energy", "radius_of_encircled_energy_arcmin", "diffraction_mtf"]


def frequencies_cyc_per_deg(psf: PSF) -> np.ndarray:
    """Spatial frequencies (cycles/degree) of the OTF samples, zero at index N//2."""
    n = psf.data.shape[0]
    return scipy.fft.fftshift(scipy.fft.fftfreq(n, d=psf.arcmin_per_px / 60.0))


def otf(psf: PSF, *, remove_pixel: bool = False) -> np.ndarray:
    """Optical transfer function, centred (zero frequency at ``[N//2, N//2]``), OTF(0) = 1.

    The PSF is pixel-integrated, so its transform carries the pixel's sinc; with
    ``remove_pixel=True`` that factor is divided out (valid below the sampling's Nyquist).
    """
    data = np.asarray(psf.data, dtype=float)
    spectrum = scipy.fft.fftshift(scipy.fft.fft2(scipy.fft.ifftshift(data)))
    spectrum /= spectrum[data.shape[0] // 2, data.shape[1] // 2]
    if remove_pixel:
        f = frequencies_cyc_per_deg(psf) * psf.arcmin_per_px / 60.0  # cycles per pixel
        spectrum /= np.sinc(f)[:, None] * np.sinc(f)[None, :]
    return spectrum


def mtf(psf: PSF, *, remove_pixel: bool = False) -> np.ndarray:
    """Modulation transfer function ``|OTF|``, centred like :func:`otf`, MTF(0) = 1.

    Frequencies along each axis are :func:`frequencies_cyc_per_deg` (cycles/degree).
    """
    return np.abs(otf(psf, remove_pixel=remove_pixel))


def diffraction_mtf(frequency_cyc_per_deg, pupil_diameter_mm: float, wavelength_nm: float) -> np.ndarray:
    """MTF of an aberration-free circular pupil (Goodman 2005, Eq. 6-32)."""
    cutoff = cyc_per_rad_to_cyc_per_deg(pupil_diameter_mm / nm_to_mm(wavelength_nm))  # D / lambda
    nu = np.clip(np.abs(np.asarray(frequency_cyc_per_deg, dtype=float)) / cutoff, 0.0, 1.0)
    return 2.0 / np.pi * (np.arccos(nu) - nu * np.sqrt(1.0 - nu**2))


def _radii_arcmin(psf: PSF) -> np.ndarray:
    n = psf.data.shape[0]
    offsets = (np.arange(n) - n // 2) * psf.arcmin_per_px
    return np.hypot(offsets[:, None], offsets[None, :])


def encircled_energy(psf: PSF, radius_arcmin: float, *, of_total: bool = True) -> float:
    """Energy within ``radius_arcmin`` of the origin (pixel centres inside the circle).

    With ``of_total`` (default) the fraction of all the PSF's energy, including what fell
    outside the field (``psf.energy_in_field``); otherwise of the energy in the field.
    """
    inside = float(np.sum(psf.data[_radii_arcmin(psf) <= radius_arcmin]))
    return inside * (psf.energy_in_field if of_total else 1.0)


def radius_of_encircled_energy_arcmin(psf: PSF, fraction: float) -> float:
    """Smallest radius holding ``fraction`` of the energy, interpolated between pixel rings."""
    radii = _radii_arcmin(psf).ravel()
    order = np.argsort(radii, kind="stable")
    cumulative = np.cumsum(np.asarray(psf.data, dtype=float).ravel()[order]) * psf.energy_in_field
    return float(np.interp(fraction, cumulative, radii[order]))
