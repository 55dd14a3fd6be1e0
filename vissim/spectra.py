"""Spectra: the CIE 1924 photopic luminous efficiency V(λ), and named sampled spectra.

`PHOTOPIC_V_5NM` is the CIE 1924 photopic luminous efficiency function V(λ), every 5 nm from
380 to 780 nm, as tabulated in CIE 018:2019 / ISO 23539:2005 (CIE/ISO joint standard
"Photometry -- The CIE system of physical photometry"; the same numbers as the CIE 1931 2°
observer's ȳ(λ) at 5 nm, e.g. CVRL's "CIE 1924 photopic V(λ)" table, cvrl.org). Its peak is 1
at 555 nm; the 683 lm/W of the candela's definition (at 540 THz, 555.016 nm) makes
K_m V(λ) the luminous efficacy of radiation. ∫ V dλ over the 1 nm table (360-830 nm) is
106.857 nm; the 5 nm table summed with 5 nm steps over 380-780 nm gives 106.8566 nm
(``tests/test_spectra.py``).

`photopic_weights` reads V(λ) at any wavelengths within the table by linear interpolation of
the 5 nm entries (the CIE's own 1 nm table interpolates them by a smoother rule; where V bends most
the two differ by about 1e-3 of the peak, e.g. 0.44558 against 0.44431 at 507 nm); outside
380-780 nm it refuses.

`named_spectrum` gives a spectrum as wavelengths (nm) and relative weights, for the wave PSF of a
polychromatic light:

* ``"photopic"``: an equal-energy light seen by the photopic eye, weight V(λ) Δλ, at
  `SPECTRUM_START_NM`-`SPECTRUM_STOP_NM` every `SPECTRUM_STEP_NM` (the sampled sum times the
  step is within 0.04 % of ∫ V dλ). Halving the step changes a schematic eye's polychromatic MTF by
  less than 1e-3 (Navarro, 3 mm on axis: 2e-5; ``tests/test_eye_spectral.py``, slow).
* ``"equal-energy"``: the same wavelengths, equal weights (radiometric, not photometric).

Plain Python (no numpy): the renderer's response reads the same table.
"""

from __future__ import annotations

import math

from vissim.checks import instance_of
from vissim.errors import VissimInputError

__all__ = ["PHOTOPIC_V_5NM", "PHOTOPIC_TABLE_START_NM", "PHOTOPIC_TABLE_STEP_NM", "SPECTRA",
           "SPECTRUM_START_NM", "SPECTRUM_STEP_NM", "SPECTRUM_STOP_NM", "named_spectrum", "photopic_weights",
           "photopic_v"]

#: The table's first wavelength and step, nm.
PHOTOPIC_TABLE_START_NM = 380.0
PHOTOPIC_TABLE_STEP_NM = 5.0
#: CIE 1924 V(λ), 380, 385, ..., 780 nm (CIE 018:2019 / ISO 23539:2005).
PHOTOPIC_V_5NM = (
    0.000039, 0.000064, 0.000120, 0.000217, 0.000396, 0.000640, 0.001210, 0.002180, 0.004000, 0.007300,  # 380-425
    0.011600, 0.016840, 0.023000, 0.029800, 0.038000, 0.048000, 0.060000, 0.073900, 0.090980, 0.112600,  # 430-475
    0.139020, 0.169300, 0.208020, 0.258600, 0.323000, 0.407300, 0.503000, 0.608200, 0.710000, 0.793200,  # 480-525
    0.862000, 0.914850, 0.954000, 0.980300, 0.994950, 1.000000, 0.995000, 0.978600, 0.952000, 0.915400,  # 530-575
    0.870000, 0.816300, 0.757000, 0.694900, 0.631000, 0.566800, 0.503000, 0.441200, 0.381000, 0.321000,  # 580-625
    0.265000, 0.217000, 0.175000, 0.138200, 0.107000, 0.081600, 0.061000, 0.044580, 0.032000, 0.023200,  # 630-675
    0.017000, 0.011920, 0.008210, 0.005723, 0.004102, 0.002929, 0.002091, 0.001484, 0.001047, 0.000740,  # 680-725
    0.000520, 0.000361, 0.000249, 0.000172, 0.000120, 0.000085, 0.000060, 0.000042, 0.000030, 0.000021,  # 730-775
    0.000015,  # 780
)
_TABLE_STOP_NM = PHOTOPIC_TABLE_START_NM + PHOTOPIC_TABLE_STEP_NM * (len(PHOTOPIC_V_5NM) - 1)

#: The sampled spectra's wavelengths: start, stop and step, nm.
SPECTRUM_START_NM = 400.0
SPECTRUM_STOP_NM = 700.0
SPECTRUM_STEP_NM = 10.0
#: The named spectra `named_spectrum` knows.
SPECTRA = ("photopic", "equal-energy")


def photopic_v(wavelength_nm: float) -> float:
    """V(λ) at ``wavelength_nm`` (380-780 nm), linearly interpolated between the 5 nm entries."""
    try:
        w = float(wavelength_nm)
    except (TypeError, ValueError):
        raise VissimInputError(f"wavelength must be a number of nm, got {wavelength_nm!r}") from None
    if not math.isfinite(w) or not PHOTOPIC_TABLE_START_NM <= w <= _TABLE_STOP_NM:
        raise VissimInputError(f"wavelength {w:g} nm is outside the photopic V(λ) table "
                               f"({PHOTOPIC_TABLE_START_NM:g}-{_TABLE_STOP_NM:g} nm)")
    position = (w - PHOTOPIC_TABLE_START_NM) / PHOTOPIC_TABLE_STEP_NM
    i = min(int(position), len(PHOTOPIC_V_5NM) - 2)
    t = position - i
    return (1.0 - t) * PHOTOPIC_V_5NM[i] + t * PHOTOPIC_V_5NM[i + 1]


def photopic_weights(wavelengths_nm) -> tuple[float, ...]:
    """V(λ) at each of ``wavelengths_nm`` (`photopic_v`); refuses any outside 380-780 nm."""
    return tuple(photopic_v(w) for w in wavelengths_nm)


def _sampled_wavelengths_nm(step_nm: float) -> tuple[float, ...]:
    count = int(round((SPECTRUM_STOP_NM - SPECTRUM_START_NM) / step_nm))
    if count < 1 or not math.isclose(count * step_nm, SPECTRUM_STOP_NM - SPECTRUM_START_NM):
        raise VissimInputError(f"spectrum step {step_nm:g} nm must divide {SPECTRUM_START_NM:g}-"
                               f"{SPECTRUM_STOP_NM:g} nm into whole steps")
    return tuple(SPECTRUM_START_NM + k * step_nm for k in range(count + 1))


def named_spectrum(name: str, step_nm: float = SPECTRUM_STEP_NM) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """(wavelengths nm, relative weights) of the spectrum ``name`` (one of `SPECTRA`), sampled every
    ``step_nm`` from `SPECTRUM_START_NM` to `SPECTRUM_STOP_NM` (module doc).

    Examples
    --------
    >>> wavelengths, weights = named_spectrum("photopic")
    >>> wavelengths[0], wavelengths[-1], len(wavelengths), weights[wavelengths.index(560.0)]
    (400.0, 700.0, 31, 0.995)
    """
    instance_of(name, str, "a spectrum's name", "text, one of " + ", ".join(SPECTRA))
    if name not in SPECTRA:
        raise VissimInputError(f"spectrum {name!r} is not known; known: {', '.join(SPECTRA)}")
    wavelengths = _sampled_wavelengths_nm(float(step_nm))
    if name == "photopic":
        return wavelengths, photopic_weights(wavelengths)
    return wavelengths, (1.0,) * len(wavelengths)
