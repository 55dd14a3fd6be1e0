"""The eye's longitudinal chromatic aberration: Thibos et al. (1992) "chromatic eye".

``chromatic_difference_of_refraction_diopters(w)`` is the refraction (a *prescription*
sphere, correcting-lens sign) at wavelength ``w`` relative to a reference wavelength:

    Rx(lambda) = p - q / (lambda - c),  p = 1.68524, q = 0.63346, c = 0.21410, lambda in µm

(Thibos, Ye, Zhang & Bradley 1992, Appl. Opt. 31:3594, Eq. 5; zero near 589 nm).  Blue light
is focused in front of the retina, so the eye is myopic for it: the value is negative
(about -0.92 D at 440 nm and +0.58 D at 700 nm relative to 550 nm; ERRATA item 7).
"""

from __future__ import annotations

import math

from vissim.checks import DEFAULT_WAVELENGTH_NM
from vissim.checks import wavelength_nm
from vissim.errors import VissimInputError

__all__ = ["chromatic_difference_of_refraction_diopters", "gaussian_band", "THIBOS_1992"]

THIBOS_1992 = {"p": 1.68524, "q": 0.63346, "c_um": 0.21410}


def _thibos_rx(wavelength_nm: float) -> float:
    wavelength = float(wavelength_nm)
    if not math.isfinite(wavelength) or not 380.0 <= wavelength <= 1000.0:
        raise VissimInputError(
            f"wavelength {wavelength_nm!r} nm is outside the chromatic-eye model's 380-1000 nm range"
        )
    return THIBOS_1992["p"] - THIBOS_1992["q"] / (wavelength * 1e-3 - THIBOS_1992["c_um"])


def chromatic_difference_of_refraction_diopters(wavelength_nm: float, reference_nm: float = DEFAULT_WAVELENGTH_NM) -> float:
    """Prescription-sphere change at ``wavelength_nm`` relative to ``reference_nm`` (D)."""
    return _thibos_rx(wavelength_nm) - _thibos_rx(reference_nm)


def gaussian_band(center_nm: float, fwhm_nm: float, samples: int = 7) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """A Gaussian spectral weighting: ``samples`` wavelengths over +-FWHM and their weights.

    A simple stand-in for a colour channel's spectral sensitivity (e.g. FWHM 40 nm); pass the
    result to `vissim.optics.psf.compute.compute_psf` as ``wavelength_nm`` and ``weights``.
    """
    center, fwhm = float(center_nm), float(fwhm_nm)
    if not (math.isfinite(center) and math.isfinite(fwhm)) or fwhm <= 0:
        raise VissimInputError(f"a spectral band needs a finite centre and a positive FWHM in nm, got {center_nm!r}, {fwhm_nm!r}")
    if int(samples) != samples or samples < 3:
        raise VissimInputError(f"a spectral band needs at least 3 samples, got {samples!r}")
    for edge in (center - fwhm, center + fwhm):  # the band's outermost samples
        wavelength_nm(edge, f"the band {center:g} +- {fwhm:g} nm (its FWHM each way) reaches a wavelength that")
    sigma = fwhm / (2.0 * math.sqrt(2.0 * math.log(2.0)))
    offsets = [fwhm * (2.0 * k / (samples - 1) - 1.0) for k in range(samples)]
    weights = [math.exp(-0.5 * (d / sigma) ** 2) for d in offsets]
    total = sum(weights)
    return tuple(center + d for d in offsets), tuple(w / total for w in weights)
