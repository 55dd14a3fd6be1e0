"""A tensor-product spline as one polynomial per knot cell, evaluated at millions of points at once.

SciPy's ``RectBivariateSpline.ev`` evaluates point by point in FITPACK and holds the GIL while it
does: a traced OPD map's ray-optics PSF asks for the slopes at 4 million rays, and two such PSFs
computed on two threads then take turns.  `CellPolynomials` holds the same spline (or one of its
partial derivatives) as a polynomial in ``(x - x_I, y - y_J)`` on each cell ``[x_I, x_I+1) x
[y_J, y_J+1)`` of its breakpoints -- the B-spline basis on each interval converted by SciPy's
``PPoly.from_spline`` -- and evaluates it in numpy, a block of points at a time: a cell lookup and
Horner's rule, most of it with the GIL released.  Values agree with ``ev`` to round-off
(tests/test_opd_map.py); points outside the breakpoints are clamped to them, as FITPACK clamps.
"""

from __future__ import annotations

import functools

import numpy as np

__all__ = ["CellPolynomials"]

#: Points evaluated per block: the gathered coefficients of a block stay in cache.
BLOCK_POINTS = 1 << 14


@functools.lru_cache(maxsize=16)
def _basis_on_intervals(knots: tuple[float, ...], degree: int) -> tuple[np.ndarray, np.ndarray]:
    """The breakpoints (the distinct knots of the domain) and each basis function's polynomial on each interval:
    (n_coefficients, degree + 1, n_intervals), powers of ``x - breakpoint`` from the highest."""
    from scipy.interpolate import PPoly

    t = np.asarray(knots)
    n_coefficients = len(t) - degree - 1
    pieces = []
    for j in range(n_coefficients):
        unit = np.zeros(len(t))
        unit[j] = 1.0
        pieces.append(PPoly.from_spline((t, unit, degree)))
    breaks = pieces[0].x
    keep = np.flatnonzero(np.diff(breaks) > 0)  # the intervals of positive length, in order
    basis = np.stack([p.c[:, keep] for p in pieces])
    return np.append(breaks[keep], breaks[keep[-1] + 1]), basis


class CellPolynomials:
    """The spline ``sum_ij c_ij B_i(x) B_j(y)`` of FITPACK's ``(tx, ty, c)`` and degrees, cell by cell."""

    def __init__(self, tck, degrees) -> None:
        tx, ty, coefficients = tck
        kx, ky = (int(d) for d in degrees)
        self.x_breaks, basis_x = _basis_on_intervals(tuple(np.asarray(tx, float)), kx)
        self.y_breaks, basis_y = _basis_on_intervals(tuple(np.asarray(ty, float)), ky)
        c = np.asarray(coefficients, float).reshape(basis_x.shape[0], basis_y.shape[0])
        # P[I, J, a, b]: the coefficient of (x - x_I)^(kx - a) (y - y_J)^(ky - b) on cell (I, J).
        cells = np.einsum("ij,iaI,jbJ->IJab", c, basis_x, basis_y, optimize=True)
        self.terms = np.ascontiguousarray(cells.reshape(-1, (kx + 1) * (ky + 1)).T)  # (terms, cells)
        self.kx, self.ky = kx, ky

    @classmethod
    def of(cls, spline) -> CellPolynomials:
        """SciPy's ``spline`` (a ``RectBivariateSpline`` or its ``partial_derivative``), cell by cell."""
        return cls(spline.tck, spline.degrees)

    def __call__(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The spline at the points ``(x[i], y[i])`` (any matching shapes)."""
        x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
        flat_x, flat_y = x.ravel(), y.ravel()
        out = np.empty(flat_x.size)
        for start in range(0, flat_x.size, BLOCK_POINTS):
            block = slice(start, start + BLOCK_POINTS)
            out[block] = self._block(flat_x[block], flat_y[block])
        return out.reshape(x.shape)

    def _block(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        column, dx = _cell_and_offset(self.x_breaks, x)
        row, dy = _cell_and_offset(self.y_breaks, y)
        cell = column * (len(self.y_breaks) - 1) + row
        out = np.zeros(x.size)
        for a in range(self.kx + 1):  # Horner in x over polynomials in y
            along_y = self.terms[a * (self.ky + 1)].take(cell)
            for b in range(1, self.ky + 1):
                along_y *= dy
                along_y += self.terms[a * (self.ky + 1) + b].take(cell)
            out *= dx
            out += along_y
        return out


def _cell_and_offset(breaks: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each point's interval among ``breaks`` (the last one closed) and its offset from the interval's start."""
    x = np.clip(x, breaks[0], breaks[-1])
    cell = np.clip(np.searchsorted(breaks, x, side="right") - 1, 0, len(breaks) - 2)
    return cell, x - breaks[cell]
