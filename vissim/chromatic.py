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

from vissim.errors import VissimInputError

__all__ = ["chromatic_difference_of_refraction_diopters", "THIBOS_1992"]

THIBOS_1992 = {"p": 1.68524, "q": 0.63346, "c_um": 0.21410}


def _thibos_rx(wavelength_nm: float) -> float:
    wavelength = float(wavelength_nm)
    if not math.isfinite(wavelength) or not 380.0 <= wavelength <= 1000.0:
        raise VissimInputError(
            f"wavelength {wavelength_nm!r} nm is outside the chromatic-eye model's 380-1000 nm range"
        )
    return THIBOS_1992["p"] - THIBOS_1992["q"] / (wavelength * 1e-3 - THIBOS_1992["c_um"])


def chromatic_difference_of_refraction_diopters(wavelength_nm: float, reference_nm: float = 550.0) -> float:
    """Prescription-sphere change at ``wavelength_nm`` relative to ``reference_nm`` (D)."""
    return _thibos_rx(wavelength_nm) - _thibos_rx(reference_nm)
