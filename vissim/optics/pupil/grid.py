"""The pupil sampled for Fourier optics: cell averages of the generalised pupil, exact at the edge.

A square grid of cells of side ``step_mm`` is centred on the pupil (cell ``[h, h]`` holds the
axis).  Each cell carries the *average over the cell* of the generalised pupil
``P(x) exp(i k W(x))`` (``P`` the hard-edged disc), not its value at the cell centre:

* inside cells: from the phase at the centre and its central differences, the linear phase
  averaged exactly (a sinc per axis) and its curvature to leading order;
* cells the rim crosses: Gauss-Legendre over the part of the cell inside the disc, split where
  the rim enters and leaves, so the covered area is exact and the phase is integrated over it.

Sampling cell averages makes the grid's discrete Fourier sum the transform of the pupil
convolved with the cell: at angle ``a`` it carries the factor ``sinc(a_x step/lambda)
sinc(a_y step/lambda)`` for every wavefront, which `vissim.optics.psf.wave` divides out.
What is left is aliasing of light from ``lambda/step`` away, kept out of the field by the
sampling criterion (``docs/conventions.md``, "Pupil sampling").

Orientation as in `vissim.optics.psf.compute`: array columns run to the observer's right and rows
down, so a cell at offsets (u, v) is the OSA pupil point (x, y) = (-u, -v)
(`vissim.units.image_colrow_to_osa_xy`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.polynomial.legendre import leggauss

from vissim.optics.runtime.workspace import scratch
from vissim.optics.pupil.zernike import MAX_MONOMIAL_ORDER, zernike_monomials, zernike_sum
from vissim.units import image_colrow_to_osa_xy, nm_to_um

__all__ = ["PupilGrid", "pupil_grid", "generalised_pupil", "generalised_pupil_parts"]

#: Gauss-Legendre points per axis in each piece of a rim cell.
RIM_POINTS = 4


@dataclass(frozen=True, eq=False)
class PupilGrid:
    """Quadrature of the disc on ``(2 half + 1)^2`` cells of side ``step_mm``.

    Every cell's centre (inside cells are averaged from the phase there and its derivatives);
    rim cells: one point list, each point's cell ``rim_cells[rim_slot]``, weights fractions
    of a cell's area.
    """

    step_mm: float
    diameter_mm: float
    half: int
    inside: np.ndarray  # (n_inside,) flat cell indices
    inside_mask: np.ndarray  # (size, size) 1.0 on inside cells, 0.0 elsewhere
    centre_x_mm: np.ndarray  # (size, size) OSA coordinates of every cell's centre
    centre_y_mm: np.ndarray
    rim_cells: np.ndarray  # (n_rim_cells,) the distinct rim cells, flat indices
    rim_slot: np.ndarray  # (n_rim_points,) each rim point's position in rim_cells
    rim_x_mm: np.ndarray
    rim_y_mm: np.ndarray
    rim_weights: np.ndarray

    @property
    def size(self) -> int:
        return 2 * self.half + 1

    @property
    def offsets_mm(self) -> np.ndarray:
        """Cell-centre offsets along the array's columns (and rows), mm."""
        return np.arange(-self.half, self.half + 1) * self.step_mm

    @property
    def area_cells(self) -> float:
        """The disc's area in cells."""
        return math.pi * (self.diameter_mm / 2.0 / self.step_mm) ** 2

    def points(self) -> tuple[np.ndarray, np.ndarray]:
        """Where to evaluate W (OSA x, y in mm): every cell's centre, then the rim's points."""
        return (np.concatenate([self.centre_x_mm.ravel(), self.rim_x_mm]),
                np.concatenate([self.centre_y_mm.ravel(), self.rim_y_mm]))


def _rim_points(centres_u, centres_v, step, radius):
    """Gauss-Legendre over cell ∩ disc: pieces in u between the rim's crossings, then v in each column."""
    u0, u1 = centres_u - step / 2, centres_u + step / 2
    v0, v1 = centres_v - step / 2, centres_v + step / 2
    breaks = [u0, u1, np.full_like(u0, -radius), np.full_like(u0, radius)]
    for v in (v0, v1):
        root = np.sqrt(np.maximum(radius**2 - v**2, 0.0))
        breaks += [root, -root]
    cuts = np.sort(np.clip(np.stack(breaks, axis=1), u0[:, None], u1[:, None]), axis=1)
    nodes, w = leggauss(RIM_POINTS)
    a, b = cuts[:, :-1, None], cuts[:, 1:, None]  # (cell, piece, node in u); pieces may have zero length
    u = (a + b) / 2 + (b - a) / 2 * nodes
    chord = np.sqrt(np.maximum(radius**2 - u**2, 0.0))
    lo, hi = np.maximum(v0[:, None, None], -chord), np.minimum(v1[:, None, None], chord)
    height = np.maximum(hi - lo, 0.0)
    v = (lo + hi)[..., None] / 2 + (height / 2)[..., None] * nodes  # (cell, piece, node in u, node in v)
    weights = np.multiply.outer(w, w) * (b - a)[..., None] / 2 * height[..., None] / 2 / step**2
    cells = len(centres_u)
    return (np.broadcast_to(u[..., None], v.shape).reshape(cells, -1), v.reshape(cells, -1),
            weights.reshape(cells, -1))


@functools.lru_cache(maxsize=32)
def pupil_grid(step_mm: float, diameter_mm: float) -> PupilGrid:
    """The cells and quadrature points of a ``diameter_mm`` disc at ``step_mm`` (cached)."""
    radius = diameter_mm / 2.0
    half = int(math.ceil(radius / step_mm + 0.5))
    offsets = np.arange(-half, half + 1) * step_mm
    u, v = (a.ravel() for a in np.meshgrid(offsets, offsets))  # u along columns, v along rows
    near = np.hypot(np.maximum(np.abs(u) - step_mm / 2, 0), np.maximum(np.abs(v) - step_mm / 2, 0))
    far = np.hypot(np.abs(u) + step_mm / 2, np.abs(v) + step_mm / 2)
    inside = np.flatnonzero(far <= radius)
    rim = np.flatnonzero((near < radius) & (far > radius))
    ru, rv, rw = _rim_points(u[rim], v[rim], step_mm, radius)
    keep = rw > 0  # zero-length pieces and columns outside the disc carry nothing
    cell = np.broadcast_to(rim[:, None], rw.shape)[keep]
    cells, slot = np.unique(cell, return_inverse=True)
    size = 2 * half + 1
    mask = np.zeros(size * size)
    mask[inside] = 1.0
    centre_x, centre_y = image_colrow_to_osa_xy(u.reshape(size, size), v.reshape(size, size))
    rim_x, rim_y = image_colrow_to_osa_xy(ru[keep], rv[keep])
    arrays = (inside, mask.reshape(size, size), centre_x, centre_y, cells, slot.ravel(), rim_x, rim_y, rw[keep])
    for array in arrays:
        array.setflags(write=False)
    return PupilGrid(step_mm, diameter_mm, half, *arrays)


def opd_on_points_um(grid: PupilGrid, wavefront, dtype=np.float64, out: np.ndarray | None = None) -> np.ndarray:
    """The wavefront's optical path difference (µm) at `PupilGrid.points`, of ``dtype``.

    A Zernike wavefront's cell centres, a square lattice, take its polynomial in monomials
    (`zernike_monomials`) as two small matrix products (x^p along the columns, y^q down the rows), and the rim's
    points `zernike_sum`; above `MAX_MONOMIAL_ORDER` every point takes `zernike_sum`. Any other wavefront (an
    `OpdMap`) is evaluated through its ``opd_um(x, y)``. Written into ``out`` when given.
    """
    size = grid.centre_x_mm.size + grid.rim_x_mm.size
    opd = np.empty(size, dtype) if out is None else out
    if not hasattr(wavefront, "coefficients_um"):
        opd[...] = wavefront.opd_um(*grid.points())
        return opd
    terms = [(key, value) for key, value in wavefront.coefficients_um.items() if key[0] > 0]  # piston changes nothing
    radius = wavefront.pupil_diameter_mm / 2.0
    centres = grid.centre_x_mm.size
    if max((n for (n, _), _ in terms), default=0) <= MAX_MONOMIAL_ORDER:
        table = zernike_monomials(terms)
        columns = np.vander(grid.centre_x_mm[0] / radius, len(table), increasing=True)  # x varies along a row
        rows = np.vander(grid.centre_y_mm[:, 0] / radius, len(table), increasing=True)  # y down a column
        opd[:centres] = (rows @ table.T @ columns.T).ravel()
    else:
        opd[:centres] = zernike_sum(terms, grid.centre_x_mm.ravel() / radius, grid.centre_y_mm.ravel() / radius)
    opd[centres:] = zernike_sum(terms, grid.rim_x_mm / radius, grid.rim_y_mm / radius)
    return opd


def generalised_pupil(grid: PupilGrid, opd_um: np.ndarray, wavelength_nm: float, dtype=np.complex128) -> np.ndarray:
    """Cell averages of ``P exp(i k W)`` on the ``size x size`` grid (a cell's area = 1), complex."""
    real, imag = generalised_pupil_parts(grid, opd_um, wavelength_nm, np.float32 if dtype == np.complex64 else np.float64)
    values = np.empty(real.shape, dtype)
    values.real, values.imag = real, imag
    return values


def _sinc_into(x: np.ndarray, out: np.ndarray) -> np.ndarray:
    """sin(x) / x (1 at 0) into ``out``: the average of exp(i phi) over a cell whose phase changes by 2x."""
    np.sin(x, out=out)
    zero = x == 0
    np.divide(out, x, out=out, where=~zero)
    out[zero] = 1.0
    return out


@functools.lru_cache(maxsize=32)
def _inside_mask(grid: PupilGrid, dtype) -> np.ndarray:
    mask = grid.inside_mask.astype(dtype)
    mask.setflags(write=False)
    return mask


def generalised_pupil_parts(grid: PupilGrid, opd_um: np.ndarray, wavelength_nm: float, dtype=np.float64,
                            out: tuple[np.ndarray, np.ndarray] | None = None):
    """The cell averages' real and imaginary parts, each ``size x size`` of ``dtype`` (float32 or float64).

    Inside cells: ``exp(i phi) sinc(phi_x h / 2) sinc(phi_y h / 2) + i h^2 lap(phi) / 24`` at the
    centre (h the step; the linear phase averaged exactly, its curvature to leading order),
    derivatives by central differences of the centres' phase.  Rim cells: their quadrature.
    Written into ``out`` (real, imaginary) when given; intermediates in `workspace`.
    """
    n = grid.size
    work = functools.partial(scratch, dtype=dtype)
    phase = np.multiply(opd_um, 2.0 * math.pi / nm_to_um(wavelength_nm), out=work("phase", opd_um.shape))
    centre = phase[: n * n].reshape(n, n)
    # Neighbours by edge padding: inside cells never touch the grid's border (it lies beyond the disc).
    padded = work("padded", (n + 2, n + 2))
    padded[1:-1, 1:-1] = centre
    padded[0, 1:-1], padded[-1, 1:-1] = centre[0], centre[-1]
    padded[:, 0], padded[:, -1] = padded[:, 1], padded[:, -2]
    up, down, left, right = padded[:-2, 1:-1], padded[2:, 1:-1], padded[1:-1, :-2], padded[1:-1, 2:]
    mask = _inside_mask(grid, np.dtype(dtype).type)
    half_step, factor = work("half_step", (n, n)), work("factor", (n, n))
    linear = _sinc_into(np.multiply(np.subtract(down, up, out=half_step), 0.25, out=half_step), work("linear", (n, n)))
    linear *= _sinc_into(np.multiply(np.subtract(right, left, out=half_step), 0.25, out=half_step), factor)
    linear *= mask
    curvature = work("curvature", (n, n))
    np.add(up, down, out=curvature)
    curvature += left
    curvature += right
    curvature -= np.multiply(centre, 4.0, out=factor)
    curvature *= mask
    curvature *= 1.0 / 24.0
    cos, sin = np.cos(centre, out=work("cos", (n, n))), np.sin(centre, out=work("sin", (n, n)))
    real, imag = (np.empty((n, n), dtype), np.empty((n, n), dtype)) if out is None else out
    np.multiply(cos, linear, out=real)
    np.multiply(sin, linear, out=imag)
    real -= np.multiply(sin, curvature, out=factor)
    imag += np.multiply(cos, curvature, out=factor)
    rim = phase[n * n:]
    weights = grid.rim_weights.astype(dtype, copy=False)
    cells = grid.rim_cells
    real.ravel()[cells] += np.bincount(grid.rim_slot, np.cos(rim) * weights, cells.size).astype(dtype, copy=False)
    imag.ravel()[cells] += np.bincount(grid.rim_slot, np.sin(rim) * weights, cells.size).astype(dtype, copy=False)
    return real, imag
