"""Zernike polynomials in the OSA/ANSI standard (Thibos et al. 2002; ANSI Z80.28).

Conventions (see ``docs/conventions.md``):

* Double index ``(n, m)``; single index ``j = (n(n+2) + m) / 2`` (OSA/ANSI, from 0).
* Unit-RMS normalisation over the unit disc:
  ``Z_n^m = N_n^m R_n^|m|(rho) cos(m theta)`` for m >= 0 and
  ``Z_n^m = -N_n^m R_n^|m|(rho) sin(m theta)`` for m < 0, with
  ``N_n^m = sqrt(2(n+1) / (1 + delta_m0))``.  So ``Z(2,-2) = sqrt(6) rho^2 sin 2theta`` and
  ``Z(2,2) = sqrt(6) rho^2 cos 2theta`` (errata item 2).
* ``theta`` counter-clockwise from +x, where +x is the examiner's right (the subject's
  left) and +y is up, looking at the eye (OSA; same frame as the TABO axis).

Radial polynomials use Jacobi polynomials, which stay accurate to high order.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import eval_jacobi

from vissim.errors import VissimInputError

__all__ = ["ansi_j_to_nm", "nm_to_ansi_j", "noll_to_nm", "nm_to_noll", "zernike_keys", "zernike_norm",
           "zernike_radial", "zernike_nm", "fit_zernike_um"]


def _check_nm(n: int, m: int) -> tuple[int, int]:
    if int(n) != n or int(m) != m:
        raise VissimInputError(f"Zernike indices must be integers, got n={n!r}, m={m!r}")
    n, m = int(n), int(m)
    if n < 0 or abs(m) > n or (n - m) % 2:
        raise VissimInputError(f"invalid Zernike term (n={n}, m={m}): need n >= 0, |m| <= n and n - m even")
    return n, m


def nm_to_ansi_j(n: int, m: int) -> int:
    """OSA/ANSI single index (from 0) of the term (n, m)."""
    n, m = _check_nm(n, m)
    return (n * (n + 2) + m) // 2


def zernike_keys(max_order: int) -> list[tuple[int, int]]:
    """Every term (n, m) up to radial order ``max_order``, in OSA/ANSI order."""
    return [(n, m) for n in range(max_order + 1) for m in range(-n, n + 1, 2)]


def ansi_j_to_nm(j: int) -> tuple[int, int]:
    """(n, m) of the OSA/ANSI single index j (from 0)."""
    if int(j) != j or j < 0:
        raise VissimInputError(f"OSA/ANSI Zernike index must be an integer >= 0, got {j!r}")
    j = int(j)
    n = int(math.ceil((-3.0 + math.sqrt(9.0 + 8.0 * j)) / 2.0))
    m = 2 * j - n * (n + 2)
    return n, m


def noll_to_nm(j: int) -> tuple[int, int]:
    """(n, m) of Noll's (1976) index j (from 1); even j carry cos, odd j carry sin."""
    if int(j) != j or j < 1:
        raise VissimInputError(f"Noll Zernike index must be an integer >= 1, got {j!r}")
    j = int(j)
    n = int(math.ceil((-3.0 + math.sqrt(1.0 + 8.0 * j)) / 2.0))
    first = n * (n + 1) // 2 + 1  # Noll index of the first term of order n
    k = j - first  # 0 .. n
    # |m| runs (n%2), (n%2), (n%2)+2, (n%2)+2, ... except that m = 0 appears once.
    abs_m = n % 2 + 2 * ((k + (n + 1) % 2) // 2)
    if abs_m == 0:
        return n, 0
    return n, (abs_m if j % 2 == 0 else -abs_m)


def nm_to_noll(n: int, m: int) -> int:
    """Noll index (from 1) of the term (n, m)."""
    n, m = _check_nm(n, m)
    first = n * (n + 1) // 2 + 1
    for j in range(first, first + n + 1):
        if noll_to_nm(j) == (n, m):
            return j
    raise AssertionError("unreachable")  # pragma: no cover


def zernike_norm(n: int, m: int) -> float:
    """Unit-RMS normalisation factor N_n^m."""
    n, m = _check_nm(n, m)
    return math.sqrt(2.0 * (n + 1) / (2.0 if m == 0 else 1.0))


def zernike_radial(n: int, m: int, rho: np.ndarray) -> np.ndarray:
    """Radial polynomial R_n^|m|(rho) = (-1)^k rho^|m| P_k^(|m|,0)(1 - 2 rho^2), k = (n-|m|)/2."""
    n, m = _check_nm(n, m)
    m = abs(m)
    rho = np.asarray(rho, dtype=float)
    k = (n - m) // 2
    return (-1.0) ** k * rho**m * eval_jacobi(k, m, 0.0, 1.0 - 2.0 * rho**2)


def zernike_nm(n: int, m: int, rho: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Unit-RMS OSA Zernike term (n, m) at normalised radius rho and angle theta (radians).

    Defined for any rho (the polynomial continues outside the unit disc); callers mask.
    """
    n, m = _check_nm(n, m)
    radial = zernike_norm(n, m) * zernike_radial(n, m, rho)
    if m > 0:
        return radial * np.cos(m * np.asarray(theta))
    if m < 0:
        return -radial * np.sin(m * np.asarray(theta))
    return radial * np.ones_like(np.asarray(theta, dtype=float))


def fit_zernike_um(x_mm, y_mm, opd_um, pupil_diameter_mm: float, max_order: int = 8):
    """Least-squares OSA Zernike coefficients (µm) of OPD samples inside the pupil disc.

    Returns ``(coefficients {(n, m): µm}, rms of the fit residual in µm)``; samples with
    ``r > R`` are ignored.
    """
    if int(max_order) != max_order or not 2 <= max_order <= 20:
        raise VissimInputError(f"Zernike radial order must be a whole number within 2-20 (defocus needs 2), "
                               f"got {max_order!r}")
    radius = 0.5 * pupil_diameter_mm
    x, y, w = (np.asarray(a, dtype=float).ravel() for a in (x_mm, y_mm, opd_um))
    rho = np.hypot(x, y) / radius
    inside = rho <= 1.0 + 1e-12
    keys = zernike_keys(int(max_order))
    if inside.sum() < 2 * len(keys):
        raise VissimInputError(f"{int(inside.sum())} samples inside the pupil cannot fit {len(keys)} Zernike terms")
    theta = np.arctan2(y[inside], x[inside])
    basis = np.stack([zernike_nm(n, m, rho[inside], theta) for n, m in keys], axis=1)
    solution, *_ = np.linalg.lstsq(basis, w[inside], rcond=None)
    residual = w[inside] - basis @ solution
    return {k: float(v) for k, v in zip(keys, solution)}, float(np.sqrt(np.mean(residual**2)))
