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

import functools
import math

import numpy as np
from vissim.errors import VissimInputError

__all__ = ["ansi_j_to_nm", "nm_to_ansi_j", "noll_to_nm", "nm_to_noll", "zernike_keys", "zernike_norm",
           "zernike_radial", "zernike_nm", "zernike_sum", "zernike_basis", "zernike_monomials", "zernike_gradient",
           "fit_zernike_um"]


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
    return (-1.0) ** k * rho**m * _jacobi_beta0(k, m, 1.0 - 2.0 * rho**2)


def _jacobi_beta0(k: int, alpha: int, x: np.ndarray) -> np.ndarray:
    """Jacobi polynomial P_k^(alpha, 0)(x) (`_jacobi_beta0_up_to`'s last)."""
    for value in _jacobi_beta0_up_to(k, alpha, x):
        pass
    return value


def _jacobi_beta0_up_to(k: int, alpha: int, x: np.ndarray):
    """P_0^(alpha, 0)(x), ..., P_k^(alpha, 0)(x) in turn, by the three-term recurrence (Abramowitz & Stegun
    22.7.1), stable on [-1, 1]."""
    previous, current = np.ones_like(x), (alpha + 1.0) + (alpha + 2.0) * (x - 1.0) / 2.0
    yield previous
    if k >= 1:
        yield current
    for order in range(2, k + 1):
        total = 2 * order + alpha  # 2n + alpha + beta, beta = 0
        a = 2.0 * order * (order + alpha) * (total - 2)
        b = (total - 1) * (total * (total - 2) * x + alpha * alpha)
        c = 2.0 * (order + alpha - 1) * (order - 1) * total
        previous, current = current, (b * current - c * previous) / a
        yield current


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


@functools.lru_cache(maxsize=256)
def _by_azimuth(keys: tuple) -> dict[int, dict[int, list[tuple[int, float, bool]]]]:
    """|m| -> {k = (n - |m|) / 2: [(row, N_n^m (-1)^k, whether sin)]} of the terms ``keys``, each checked."""
    groups: dict[int, dict[int, list[tuple[int, float, bool]]]] = {}
    for row, (n, m) in enumerate(keys):
        n, m = _check_nm(n, m)
        k = (n - abs(m)) // 2
        groups.setdefault(abs(m), {}).setdefault(k, []).append((row, zernike_norm(n, m) * (-1.0) ** k, m < 0))
    return groups


def _zernike_terms(keys, u: np.ndarray, v: np.ndarray, visit) -> None:
    """Every term of ``keys`` at the unit-disc points (u, v) = rho (cos theta, sin theta), handed to
    ``visit(row, values)`` one by one.  Shared work: rho^|m| cos|m|theta and rho^|m| sin|m|theta are the real
    and imaginary parts of (u + iv)^|m|, raised step by step (no arctan2, no trigonometry), and each |m|'s
    radial polynomials come from one Jacobi recurrence in k (`_jacobi_beta0_up_to`)."""
    groups = _by_azimuth(tuple(_check_nm(*key) for key in keys))
    x = 1.0 - 2.0 * (u * u + v * v)
    real, imag = np.ones_like(x), np.zeros_like(x)
    for alpha in range(max(groups, default=-1) + 1):
        wanted = groups.get(alpha)
        if wanted:
            for k, radial in enumerate(_jacobi_beta0_up_to(max(wanted), alpha, x)):
                for row, norm, sine in wanted.get(k, ()):
                    visit(row, norm * radial * (imag if sine else real))
        real, imag = real * u - imag * v, real * v + imag * u


def zernike_sum(coefficients, u, v) -> np.ndarray:
    """``sum c Z_n^m`` at unit-disc points (u, v) (x and y over the pupil radius; OSA frame): ``coefficients``
    a mapping or pairs ``(n, m) -> c``.  Equals summing `zernike_nm` term by term (to 1e-12 of the front's scale to order 16:
    tests/test_zernike.py), several
    times faster: up to `MAX_MONOMIAL_ORDER` as its monomials (`zernike_monomials`) by Horner's rule, above it
    term by term with shared recurrences.  Points outside the disc get the polynomials' continuation."""
    items = _checked_items(coefficients)
    u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
    if max((n for (n, _), _ in items), default=0) <= MAX_MONOMIAL_ORDER:
        return _horner(zernike_monomials(items), u, v)
    out = np.zeros(u.shape)
    values = [value for _, value in items]

    def add(row, term):
        out.__iadd__(values[row] * term)

    _zernike_terms([key for key, _ in items], u, v, add)
    return out


def _horner(table: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``sum A[p, q] u^p v^q`` (``table`` = A) at the points (u, v), by Horner's rule in each variable."""
    out = np.zeros(u.shape)
    if table.size == 0:
        return out
    for q in range(table.shape[1] - 1, -1, -1):  # sum_q v^q (sum_p A[p, q] u^p)
        if table.shape[0] == 1:
            along_u = np.full(u.shape, table[0, q])
        else:
            along_u = u * table[-1, q]
            along_u += table[-2, q]
            for p in range(table.shape[0] - 3, -1, -1):
                along_u *= u
                along_u += table[p, q]
        out *= v
        out += along_u
    return out


def zernike_gradient(coefficients, u, v) -> tuple[np.ndarray, np.ndarray] | None:
    """``(d/du, d/dv)`` of ``sum c Z_n^m`` at unit-disc points (u, v): the monomials' exact derivatives, by Horner's
    rule; None above `MAX_MONOMIAL_ORDER` (where the monomials cancel too much)."""
    items = _checked_items(coefficients)
    if max((n for (n, _), _ in items), default=0) > MAX_MONOMIAL_ORDER:
        return None
    u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
    table = zernike_monomials(items)
    powers = np.arange(1, table.shape[0])
    along_u = table[1:, :] * powers[:, None]  # A[p, q] u^p -> p A[p, q] u^(p-1)
    along_v = table[:, 1:] * powers[None, :]
    return _horner(along_u, u, v), _horner(along_v, u, v)


#: The highest radial order `zernike_sum` takes as monomials (their cancellation stays under 1e-12 of the front's
#: scale there: tests/test_zernike.py).
MAX_MONOMIAL_ORDER = 12


def zernike_basis(keys, u, v) -> np.ndarray:
    """The terms ``keys`` at unit-disc points (u, v), one column each: (N, len(keys))."""
    u, v = (np.asarray(a, dtype=float).ravel() for a in (u, v))
    basis = np.empty((len(u), len(keys)))

    def put(row, term):
        basis[:, row] = term

    _zernike_terms(list(keys), u, v, put)
    return basis


def _checked_items(coefficients) -> list[tuple[tuple[int, int], float]]:
    """``(n, m) -> c`` pairs from a mapping or pairs, each index pair checked and made whole numbers."""
    pairs = coefficients.items() if hasattr(coefficients, "items") else coefficients
    return [(_check_nm(*key), value) for key, value in pairs]


@functools.lru_cache(maxsize=None)
def _monomials_nm(n: int, m: int) -> dict[tuple[int, int], int]:
    """Z_n^m / N_n^m as a polynomial in (u, v) with whole-number coefficients, {(power of u, power of v): c}:
    R_n^|m| = sum_s (-1)^s (n-s)! / (s! ((n+|m|)/2-s)! ((n-|m|)/2-s)!) rho^(n-2s), rho^(n-2s) = (u^2 + v^2)^j
    rho^|m|, and rho^|m| cos |m|theta, rho^|m| sin |m|theta the real and imaginary parts of (u + iv)^|m|."""
    alpha, half = abs(m), (n - abs(m)) // 2
    angular = {}
    for k in range(alpha + 1):  # (u + iv)^alpha = sum C(alpha, k) u^(alpha-k) (iv)^k
        if (k % 2 == 1) == (m < 0):  # cos: i^k real (k even); sin: i^k imaginary (k odd)
            angular[(alpha - k, k)] = math.comb(alpha, k) * (-1) ** (k // 2)
    poly: dict[tuple[int, int], int] = {}
    for s in range(half + 1):
        c = (-1) ** s * math.factorial(n - s) // (math.factorial(s) * math.factorial(half + alpha - s)
                                                   * math.factorial(half - s))
        j = half - s
        for i in range(j + 1):  # (u^2 + v^2)^j
            for (p, q), a in angular.items():
                key = (p + 2 * i, q + 2 * (j - i))
                poly[key] = poly.get(key, 0) + c * math.comb(j, i) * a
    return {key: value for key, value in poly.items() if value}


def zernike_monomials(coefficients) -> np.ndarray:
    """``sum c Z_n^m`` as a polynomial ``sum A[p, q] u^p v^q`` in unit-disc coordinates: A, (order+1, order+1).
    Exact whole-number coefficients scaled once; for the low orders of eyes (to 1e-12 of the front's scale up to
    `MAX_MONOMIAL_ORDER`, tests/test_zernike.py: the monomials cancel more as the order grows)."""
    items = _checked_items(coefficients)
    order = max((n for (n, _), _ in items), default=0)
    table = np.zeros((order + 1, order + 1))
    for (n, m), value in items:
        scale = value * zernike_norm(n, m)
        for (p, q), c in _monomials_nm(*_check_nm(n, m)).items():
            table[p, q] += scale * c
    return table


#: Largest condition number of a fit's normal matrix solved as it is: its error is then below
#: 1e-16 x this (relative), else the fit goes by SVD.
MAX_NORMAL_CONDITION = 1e6


def _least_squares(basis: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``argmin |basis c - values|``: by the normal equations when they are well conditioned (Zernike terms over
    a disc are near orthogonal: cond 2-4 for pupil grids), ten times faster than an SVD; else by the SVD. The sums
    by einsum, not BLAS, whose threads would change their round-off from machine to machine and task to task."""
    normal = np.einsum("ki,kj->ij", basis, basis, optimize=False)
    scale = np.sqrt(np.diag(normal))
    if np.all(scale > 0):
        scaled = normal / np.outer(scale, scale)
        if np.linalg.cond(scaled) <= MAX_NORMAL_CONDITION:
            return np.linalg.solve(scaled, np.einsum("ki,k->i", basis, values, optimize=False) / scale) / scale
    solution, *_ = np.linalg.lstsq(basis, values, rcond=None)
    return solution


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
    basis = zernike_basis(keys, x[inside] / radius, y[inside] / radius)
    solution = _least_squares(basis, w[inside])
    residual = w[inside] - basis @ solution
    return {k: float(v) for k, v in zip(keys, solution)}, float(np.sqrt(np.mean(residual**2)))
