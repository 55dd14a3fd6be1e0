"""Published fits of measured human MTFs, to set beside measured and schematic eyes.

Each fit states its conditions; compare at those only. Double-pass MTFs include the eye's scatter, and MTFs
computed from wavefronts (Watson's, and vissim's) do not.

* `watson_2013_mtf`: A. B. Watson (2013) J. Vision 13(6):18. The mean MTF of the best-corrected eye (orders
  3 and up; sphere and cylinder corrected), fitted to MTFs computed from about 200 eyes' wavefronts (Thibos
  et al. 2002) at 555 nm, for 2-6 mm pupils: M(u, d) = (1 + (u / u1)²)^-0.62 · √D(u, d),
  u1 = 21.95 − 5.512 d + 0.3922 d², D the diffraction-limited MTF of a d mm pupil at 555 nm.
* `artal_navarro_1994_mtf`: P. Artal, R. Navarro (1994) JOSA A 11:246. Double-pass, fovea, natural
  accommodation, pupils 2.5-8 mm: MTF(f) = (1 − C) e^(−A f) + C e^(−B f); A, B, C tabulated per pupil
  (read from third-party code, not the paper: `ARTAL_NAVARRO_1994`).
* `navarro_1993_mtf`: R. Navarro, P. Artal, D. R. Williams (1993) JOSA A 10:201. Double-pass, 4 mm natural pupil,
  0-60° of eccentricity, the same form (`NAVARRO_1993`, from Psychtoolbox-3's NavarroMTF.m).

Frequencies in cycles per degree. A pupil or eccentricity a fit does not tabulate is refused, not interpolated.
"""

from __future__ import annotations

import math

import numpy as np

from vissim.errors import VissimInputError

__all__ = ["watson_2013_mtf", "artal_navarro_1994_mtf", "navarro_1993_mtf", "ARTAL_NAVARRO_1994", "NAVARRO_1993", "NAVARRO_1993_PUPIL_MM",
           "WATSON_2013_PUPILS_MM", "WATSON_2013_WAVELENGTH_NM"]

#: Watson's fit: the pupils (mm) it was fitted over, and its light (nm).
WATSON_2013_PUPILS_MM = (2.0, 6.0)
WATSON_2013_WAVELENGTH_NM = 555.0
#: Artal & Navarro 1994: pupil (mm) -> (A, B, C).
ARTAL_NAVARRO_1994 = {2.5: (0.16, 0.06, 0.36), 3.0: (0.16, 0.05, 0.28), 4.0: (0.18, 0.04, 0.18),
                      6.0: (0.31, 0.06, 0.20), 8.0: (0.53, 0.08, 0.11)}
#: Navarro, Artal & Williams 1993: their natural pupil (mm), and eccentricity (deg) -> (A, B, C).
NAVARRO_1993_PUPIL_MM = 4.0
NAVARRO_1993 = {0.0: (0.172, 0.037, 0.22), 5.0: (0.245, 0.041, 0.20), 10.0: (0.245, 0.041, 0.20),
                20.0: (0.328, 0.038, 0.14), 30.0: (0.606, 0.064, 0.12), 40.0: (0.82, 0.064, 0.09),
                50.0: (0.93, 0.059, 0.067), 60.0: (1.89, 0.108, 0.05)}


def _frequencies(frequencies_cyc_per_deg) -> np.ndarray:
    f = np.asarray(frequencies_cyc_per_deg, dtype=float)
    if not np.all(np.isfinite(f)) or np.any(f < 0):
        raise VissimInputError(f"MTF frequencies are cycles/deg >= 0, got {frequencies_cyc_per_deg!r}")
    return f


def watson_2013_mtf(frequencies_cyc_per_deg, pupil_mm: float) -> np.ndarray:
    """Watson's (2013) mean MTF of the best-corrected eye at 555 nm (module doc), for a 2-6 mm pupil."""
    low, high = WATSON_2013_PUPILS_MM
    d = float(pupil_mm)
    if not low <= d <= high:
        raise VissimInputError(f"Watson's 2013 fit covers {low:g}-{high:g} mm pupils, got {pupil_mm!r} mm")
    u = _frequencies(frequencies_cyc_per_deg)
    u0 = d * math.pi * 1e6 / (WATSON_2013_WAVELENGTH_NM * 180.0)  # the diffraction cutoff, cycles/deg
    s = np.minimum(u / u0, 1.0)
    diffraction = (2.0 / math.pi) * (np.arccos(s) - s * np.sqrt(1.0 - s * s))
    u1 = 21.95 - 5.512 * d + 0.3922 * d * d
    return (1.0 + (u / u1) ** 2) ** -0.62 * np.sqrt(diffraction)


def _double_exponential(f: np.ndarray, abc: tuple[float, float, float]) -> np.ndarray:
    a, b, c = abc
    return (1.0 - c) * np.exp(-a * f) + c * np.exp(-b * f)


def artal_navarro_1994_mtf(frequencies_cyc_per_deg, pupil_mm: float) -> np.ndarray:
    """Artal & Navarro's (1994) double-pass foveal MTF at a tabulated pupil (module doc)."""
    if float(pupil_mm) not in ARTAL_NAVARRO_1994:
        raise VissimInputError(f"Artal & Navarro 1994 tabulate pupils of {', '.join(f'{p:g}' for p in ARTAL_NAVARRO_1994)}"
                               f" mm, got {pupil_mm!r} mm")
    return _double_exponential(_frequencies(frequencies_cyc_per_deg), ARTAL_NAVARRO_1994[float(pupil_mm)])


def navarro_1993_mtf(frequencies_cyc_per_deg, eccentricity_deg: float) -> np.ndarray:
    """Navarro, Artal & Williams's (1993) double-pass MTF (4 mm) at a tabulated eccentricity (module doc)."""
    if float(eccentricity_deg) not in NAVARRO_1993:
        raise VissimInputError(f"Navarro et al. 1993 tabulate eccentricities of "
                               f"{', '.join(f'{e:g}' for e in NAVARRO_1993)} deg, got {eccentricity_deg!r} deg")
    return _double_exponential(_frequencies(frequencies_cyc_per_deg), NAVARRO_1993[float(eccentricity_deg)])
