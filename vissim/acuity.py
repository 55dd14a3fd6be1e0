"""Visual-acuity notation and the size of a letter of given acuity.

Notations (Bailey & Lovie 1976; Ferris et al. 1982; ISO 8596):

* **LogMAR** -- log10 of the minimum angle of resolution in arcmin.  0.0 is "normal"
  acuity (20/20, 6/6); +1.0 is 20/200; -0.3 is 20/10.
* **decimal acuity** -- 1 / MAR, e.g. 20/40 -> 0.5 (thesis Eq. 4.2:
  LogMAR = -log10(decimal)).
* **Snellen fraction** -- ``"<test distance>/<distance at which the letter subtends 5 arcmin>"``,
  in feet (``"20/200"``) or metres (``"6/60"``).

A letter of acuity LogMAR is 5 MAR tall, i.e. ``5 * 10**logmar`` arcmin (Sloan letters sit
on a 5 x 5 grid whose stroke is one MAR).  Each conversion lives in exactly one function
below; the other functions call it.
"""

from __future__ import annotations

import math
import re

from vissim.checks import finite_number as _finite
from vissim.checks import positive_number as _positive
from vissim.errors import VissimInputError
from vissim.units import arcmin_to_rad, m_to_mm, rad_to_arcmin

__all__ = ["LETTER_HEIGHT_MAR", "decimal_to_logmar", "letter_height_arcmin",
           "letter_height_mm", "logmar_to_decimal", "logmar_to_snellen", "snellen_to_logmar",
           "subtense_arcmin", "subtense_mm"]

#: A Sloan letter is five strokes (five MAR) tall.
LETTER_HEIGHT_MAR = 5.0

#: Beyond this 10**logmar leaves the range of a float.
_MAX_ABS_LOGMAR = 300.0

_SNELLEN = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*/\s*([0-9]*\.?[0-9]+)\s*$")


def logmar_to_decimal(logmar: float) -> float:
    """Decimal acuity of a LogMAR value: ``10**(-logmar)`` (thesis Eq. 4.2 inverted)."""
    logmar = _finite(logmar, "LogMAR", "log10 arcmin")
    if abs(logmar) > _MAX_ABS_LOGMAR:
        raise VissimInputError(f"LogMAR must lie within +-{_MAX_ABS_LOGMAR:g} (log10 arcmin), got {logmar:g}")
    return 10.0 ** (-logmar)


def decimal_to_logmar(decimal: float) -> float:
    """LogMAR of a decimal acuity: ``-log10(decimal)`` (thesis Eq. 4.2)."""
    return -math.log10(_positive(decimal, "decimal acuity", "(1/arcmin)"))


def snellen_to_logmar(snellen: str) -> float:
    """LogMAR of a Snellen fraction such as ``"20/200"`` (feet) or ``"6/60"`` (metres) -> 1.0."""
    match = _SNELLEN.match(str(snellen))
    if match is None:
        raise VissimInputError(
            f"Snellen fraction must look like '20/200' or '6/60' (test distance / letter distance), got {snellen!r}"
        )
    numerator = _positive(float(match.group(1)), "Snellen test distance", "(ft or m)")
    denominator = _positive(float(match.group(2)), "Snellen letter distance", "(ft or m)")
    return decimal_to_logmar(numerator / denominator)


def logmar_to_snellen(logmar: float, test_distance: float = 20, *, significant_figures: int = 3) -> str:
    """Snellen fraction of a LogMAR value, e.g. ``logmar_to_snellen(1.0) == "20/200"``.

    ``test_distance`` is the numerator (20 for feet, 6 for metres).  The denominator is
    ``test_distance / decimal`` rounded to ``significant_figures`` (LogMAR 0.1 -> ``"20/25.2"``;
    charts print the nearest preferred number, 20/25), so a round trip through
    `snellen_to_logmar` is exact to within ``log10(1 + 5 * 10**-significant_figures)``.
    """
    test_distance = _positive(test_distance, "Snellen test distance", "(ft or m)")
    if int(significant_figures) < 1:
        raise VissimInputError(f"significant_figures must be >= 1, got {significant_figures!r}")
    denominator = test_distance / logmar_to_decimal(logmar)
    return f"{test_distance:g}/{float(f'{denominator:.{int(significant_figures)}g}'):g}"


def letter_height_arcmin(logmar: float) -> float:
    """Angular height of a letter of acuity ``logmar``: ``5 * 10**logmar`` arcmin (5 MAR)."""
    return LETTER_HEIGHT_MAR / logmar_to_decimal(logmar)


def letter_height_mm(logmar: float, viewing_distance_m: float) -> float:
    """Physical height (mm) of a letter that subtends ``5 * 10**logmar`` arcmin at the distance.

    Thesis Eq. 4.1 generalised: the letter is centred on the line of sight, so its height is
    ``2 d tan(theta / 2)``.  Eq. 4.1 itself writes ``d * tan(5') * 10**LogMAR``; the two differ
    by about ``theta**2 / 12 - theta_0**2 / 3`` relative (``theta_0`` = 5') -- below 1e-6 for LogMAR < 0.45 at any distance, 1.7e-5
    at LogMAR 1.0 (0.2 um on the 13.3 mm letter), always far below print resolution.

    Checks: LogMAR 0 at 914.4 mm -> 1.330 mm; at 6 m -> 8.727 mm.
    """
    return subtense_mm(letter_height_arcmin(logmar), viewing_distance_m)


def subtense_mm(arcmin: float, viewing_distance_m: float) -> float:
    """Size (mm) of an object centred on the line of sight that subtends ``arcmin`` at the distance.

    ``2 d tan(theta / 2)``: the one conversion from visual angle to size on the chart.
    """
    distance_m = _positive(viewing_distance_m, "viewing distance", "m")
    theta_rad = arcmin_to_rad(_positive(arcmin, "visual angle", "arcmin"))
    if theta_rad >= math.pi:
        raise VissimInputError(f"visual angle must be below 10800 arcmin (180 deg), got {arcmin:g} arcmin")
    return m_to_mm(2.0 * distance_m * math.tan(theta_rad / 2.0))


def subtense_arcmin(size_mm: float, viewing_distance_m: float) -> float:
    """Visual angle (arcmin) of an object ``size_mm`` tall centred on the line of sight; inverse of
    `subtense_mm`."""
    distance_m = _positive(viewing_distance_m, "viewing distance", "m")
    size_mm = _positive(size_mm, "size", "mm")
    return rad_to_arcmin(2.0 * math.atan(size_mm / 2000.0 / distance_m))
