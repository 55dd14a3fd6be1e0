"""Quantities derived from a sampled `PSF`: OTF, MTF, encircled energy."""

from __future__ import annotations

import numpy as np

from vissim.checks import instance_of, number_array
from vissim.checks import pupil_diameter_mm as check_pupil_mm
from vissim.checks import wavelength_nm as check_wavelength_nm
from vissim.lazy_import import lazy_module
from vissim.optics.psf.compute import PSF
from vissim.units import cyc_per_rad_to_cyc_per_deg, nm_to_mm

scipy_fft = lazy_module("scipy.fft")

__all__ = ["otf", "mtf", "frequencies_cyc_per_deg", "encircled_energy", "radius_of_encircled_energy_arcmin", "diffraction_mtf",
           "ring_means"]


#: What the metrics of a sampled PSF take.
PSF_ACCEPTED = "a PSF (from vissim.compute_psf or PSF.from_array)"


def ring_means(values, radius, ring_width: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Means over rings: ``(mean radius, mean value)`` of each non-empty ring, inner to outer.

    Ring ``k`` holds the samples whose ``radius`` lies within half a ``ring_width`` of
    ``k * ring_width`` (``rint(radius / ring_width) == k``): ring 0 is the centre alone on a grid
    centred on a sample, and ring ``k`` is centred on the ``k``-th sample along an axis.
    ``values`` and ``radius`` are arrays of one shape, ``radius`` >= 0 in any unit.
    """
    radius = np.asarray(radius, dtype=float).ravel()
    rings = np.rint(radius / ring_width).astype(np.int64)
    counts = np.bincount(rings)
    used = counts > 0
    return (np.bincount(rings, weights=radius)[used] / counts[used],
            np.bincount(rings, weights=np.asarray(values, dtype=float).ravel())[used] / counts[used])


def frequencies_cyc_per_deg(psf: PSF) -> np.ndarray:
    """Spatial frequencies (cycles/degree) of the OTF samples, zero at index N//2.

    Parameters
    ----------
    psf : PSF
        An N x N PSF sampled at ``psf.arcmin_per_px``.

    Returns
    -------
    ndarray of shape (N,)
        The frequency of each row (and column) of `otf` / `mtf`, cycles/degree,
        increasing, 0 at index N // 2; the Nyquist frequency is 30 / ``arcmin_per_px``.

    Examples
    --------
    >>> import vissim
    >>> psf = vissim.compute_psf(vissim.Wavefront.zero(3.0), arcmin_per_px=0.5, size_px=64)
    >>> f = vissim.frequencies_cyc_per_deg(psf)
    >>> float(f[32]), float(-f[0])  # zero, and the Nyquist frequency 30 / 0.5 cycles/degree
    (0.0, 60.0)
    """
    instance_of(psf, PSF, "frequencies_cyc_per_deg's psf", PSF_ACCEPTED)
    n = psf.data.shape[0]
    return scipy_fft.fftshift(scipy_fft.fftfreq(n, d=psf.arcmin_per_px / 60.0))


def otf(psf: PSF, *, remove_pixel: bool = False) -> np.ndarray:
    """Optical transfer function, centred (zero frequency at ``[N//2, N//2]``), OTF(0) = 1.

    The PSF is pixel-integrated, so its transform carries the pixel's sinc; with
    ``remove_pixel=True`` that factor is divided out (valid below the sampling's Nyquist).

    Parameters
    ----------
    psf : PSF
        A square PSF (origin at ``[N//2, N//2]``), e.g. from `vissim.compute_psf`.
    remove_pixel : bool
        Divide out the pixel's ``sinc(f) sinc(g)``.

    Returns
    -------
    ndarray of complex, shape (N, N)
        ``[row, col]`` = (vertical frequency, horizontal frequency), both
        `frequencies_cyc_per_deg` (cycles/degree), zero at ``[N//2, N//2]``. The OTF is of
        the PSF as sampled: its energy outside the field is not in it (OTF(0) = 1 over the field).

    Examples
    --------
    >>> import vissim
    >>> psf = vissim.compute_psf(vissim.Wavefront.zero(3.0), arcmin_per_px=0.25, size_px=128)
    >>> h = vissim.otf(psf)
    >>> h.shape, complex(h[64, 64])
    ((128, 128), (1+0j))
    """
    instance_of(psf, PSF, "the psf", PSF_ACCEPTED)
    data = np.asarray(psf.data, dtype=float)
    spectrum = scipy_fft.fftshift(scipy_fft.fft2(scipy_fft.ifftshift(data)))
    spectrum /= spectrum[data.shape[0] // 2, data.shape[1] // 2]
    if remove_pixel:
        f = frequencies_cyc_per_deg(psf) * psf.arcmin_per_px / 60.0  # cycles per pixel
        spectrum /= np.sinc(f)[:, None] * np.sinc(f)[None, :]
    return spectrum


def mtf(psf: PSF, *, remove_pixel: bool = False) -> np.ndarray:
    """Modulation transfer function ``|OTF|``, centred like `otf`, MTF(0) = 1.

    Frequencies along each axis are `frequencies_cyc_per_deg` (cycles/degree).

    Parameters
    ----------
    psf : PSF
        A square PSF (origin at ``[N//2, N//2]``).
    remove_pixel : bool
        Divide out the pixel's sinc, as in `otf`.

    Returns
    -------
    ndarray of float, shape (N, N)
        ``[row, col]`` = (vertical, horizontal) frequency in cycles/degree, zero frequency at
        ``[N//2, N//2]``; a horizontal cut ``m[N//2, N//2:]`` is the MTF along x.

    Examples
    --------
    Defocus of 0.25 D in a 3 mm pupil against the diffraction limit at 10 cycles/degree:

    >>> import numpy as np
    >>> import vissim
    >>> front = vissim.Wavefront.from_prescription(vissim.Prescription(-0.25), 3.0)
    >>> psf = vissim.compute_psf(front, arcmin_per_px=0.25, size_px=128)
    >>> m, f = vissim.mtf(psf), vissim.frequencies_cyc_per_deg(psf)
    >>> at_10 = int(np.argmin(np.abs(f - 10.0)))
    >>> bool(m[64, at_10] < vissim.diffraction_mtf(f[at_10], 3.0, 550.0))
    True
    """
    return np.abs(otf(psf, remove_pixel=remove_pixel))


def diffraction_cutoff_cyc_per_deg(pupil_diameter_mm: float, wavelength_nm: float) -> float:
    """The incoherent cutoff frequency D / lambda of a circular pupil, cycles/degree."""
    return float(cyc_per_rad_to_cyc_per_deg(pupil_diameter_mm / nm_to_mm(wavelength_nm)))


def diffraction_mtf(frequency_cyc_per_deg, pupil_diameter_mm: float, wavelength_nm: float) -> np.ndarray:
    """MTF of an aberration-free circular pupil (Goodman 2005, Eq. 6-32).

    Parameters
    ----------
    frequency_cyc_per_deg : float or array_like
        Spatial frequency, cycles/degree (its sign is ignored).
    pupil_diameter_mm : float
        Pupil diameter, mm.
    wavelength_nm : float
        Wavelength, nm.

    Returns
    -------
    ndarray of float
        The MTF, shaped like ``frequency_cyc_per_deg``: 1 at zero, 0 at and beyond the cutoff
        ``D / lambda`` (radians^-1; 114 cycles/degree for 3.6 mm at 550 nm). No pixel sinc.

    Examples
    --------
    >>> import vissim
    >>> vissim.diffraction_mtf([0.0, 30.0, 60.0, 200.0], 3.0, 550.0).round(3)
    array([1.   , 0.606, 0.254, 0.   ])
    """
    cutoff = diffraction_cutoff_cyc_per_deg(check_pupil_mm(pupil_diameter_mm), check_wavelength_nm(wavelength_nm))
    nu = np.clip(np.abs(number_array(frequency_cyc_per_deg, "frequency_cyc_per_deg", "cycles/degree")) / cutoff, 0.0, 1.0)
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
    inside = float(np.sum(psf.data[_radii_arcmin(psf) <= radius_arcmin])) / psf.data_sum  # of the field's energy
    return inside * (psf.energy_in_field if of_total else 1.0)


def radius_of_encircled_energy_arcmin(psf: PSF, fraction: float) -> float:
    """Smallest radius holding ``fraction`` of the energy, interpolated between pixel rings."""
    radii = _radii_arcmin(psf).ravel()
    order = np.argsort(radii, kind="stable")
    cumulative = np.cumsum(np.asarray(psf.data, dtype=float).ravel()[order]) * (psf.energy_in_field / psf.data_sum)
    return float(np.interp(fraction, cumulative, radii[order]))
