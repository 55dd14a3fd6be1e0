"""Field-dependent (spatially variant) blur: PSFs known on a grid of nodes, interpolated between them.

The image is blurred by the PSFs of a regular grid of nodes spanning it, interpolated
bilinearly between nodes (Nagy & O'Leary 1998, "Restoring images degraded by spatially
variant blur", SIAM J. Sci. Comput. 19:1063)::

    blurred = sum_k PSF_k * (w_k . image)

``*`` the convolution and ``w_k`` the bilinear tent of node k (1 at the node, falling linearly to
0 at its neighbours, the tents summing to 1 everywhere). So a point source is blurred by the
bilinear interpolation of its neighbouring nodes' PSFs: at a node exactly that node's PSF, halfway
between two nodes the mean of theirs. A PSF that sums to 1 at every node conserves the energy
(each source point's light is spread, none lost); a uniform image stays uniform only where the
PSFs do not change (as it should: light spreads differently where they do).

Each node's term is computed on a window: its tent's support (out to its neighbours) plus the
largest PSF's reach, convolved by `vissim.optics.blur.convolve.blur_image` (zero outside the window, where
the weighted image is zero). The padding outside the image (``padding``, ``background``) is that of
`blur_image`, applied once to the whole image before it is weighted; the edge nodes' tents extend
flat into it. With one node it is `blur_image` itself (isoplanatic).

Generic: the PSFs come as a `PSFGrid` (or from a callable of a node's pixel position,
`psf_grid`); nothing here knows what made them.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from vissim.errors import VissimInputError
from vissim.optics.blur.convolve import blur_image, border_mean, checked_blur_inputs, pad_array, padding_width_px
from vissim.optics.psf.compute import PSF

__all__ = ["PSFGrid", "node_positions_px", "psf_grid", "tent_weights", "blur_field_dependent"]


@dataclass(frozen=True, eq=False)
class PSFGrid:
    """PSFs at the nodes of a regular grid over an image: ``psfs[i][j]`` at row ``rows_px[i]``, column ``cols_px[j]``.

    Node positions are pixel coordinates (row 0 at the top, column 0 at the left; a pixel's centre
    is its integer index), increasing and evenly spaced along each axis.
    """

    rows_px: tuple[float, ...]
    cols_px: tuple[float, ...]
    psfs: tuple[tuple[PSF, ...], ...]

    def __post_init__(self) -> None:
        if len(self.psfs) != len(self.rows_px) or any(len(row) != len(self.cols_px) for row in self.psfs):
            raise VissimInputError(f"a PSF grid of {len(self.rows_px)} x {len(self.cols_px)} nodes needs as many PSFs")
        for name, nodes in (("rows", self.rows_px), ("columns", self.cols_px)):
            if len(nodes) < 1 or any(b <= a for a, b in zip(nodes, nodes[1:])):
                raise VissimInputError(f"a PSF grid's node {name} (px) must increase, got {nodes}")

    @property
    def shape(self) -> tuple[int, int]:
        return len(self.rows_px), len(self.cols_px)

    @property
    def node_count(self) -> int:
        return len(self.rows_px) * len(self.cols_px)

    def all_psfs(self) -> list[PSF]:
        return [psf for row in self.psfs for psf in row]


def node_positions_px(length_px: int, spacing_px: float) -> tuple[float, ...]:
    """Evenly spaced nodes from the first pixel's centre (0) to the last's (``length_px - 1``), at most ``spacing_px`` apart.

    One node at the centre when the whole length is within one spacing (or one pixel).
    """
    if not (math.isfinite(spacing_px) and spacing_px > 0):
        raise VissimInputError(f"the node spacing must be a positive number of pixels, got {spacing_px!r}")
    span = length_px - 1
    if span < spacing_px:
        return (span / 2.0,)
    count = math.ceil(span / spacing_px - 1e-9) + 1
    return tuple(float(v) for v in np.linspace(0.0, span, count))


def psf_grid(shape: tuple[int, int], spacing_px: float, psf_at: Callable[[float, float], PSF]) -> PSFGrid:
    """The `PSFGrid` of ``psf_at(row_px, col_px)`` at `node_positions_px` over an image of ``shape`` (rows, cols)."""
    rows = node_positions_px(shape[0], spacing_px)
    cols = node_positions_px(shape[1], spacing_px)
    return PSFGrid(rows, cols, tuple(tuple(psf_at(r, c) for c in cols) for r in rows))


def tent_weights(positions_px: np.ndarray, nodes_px: Sequence[float], k: int) -> np.ndarray:
    """Node ``k``'s bilinear tent along one axis at ``positions_px``: 1 at the node, 0 at and beyond its neighbours.

    Beyond the first and last nodes the end tents stay 1 (the weights sum to 1 everywhere).
    """
    x = np.clip(np.asarray(positions_px, dtype=float), nodes_px[0], nodes_px[-1])
    node = nodes_px[k]
    weight = np.ones_like(x)
    if k > 0:
        left = nodes_px[k - 1]
        weight = np.where(x < node, (x - left) / (node - left), weight)
    if k < len(nodes_px) - 1:
        right = nodes_px[k + 1]
        weight = np.where(x > node, (right - x) / (right - node), weight)
    return np.clip(weight, 0.0, 1.0)


def _support_padded(nodes_px: Sequence[float], k: int, reach: int, length_px: int) -> tuple[int, int]:
    """Rows (or columns) [start, stop) of the image padded by ``reach`` where node ``k``'s tent is not zero."""
    start = 0 if k == 0 else math.floor(nodes_px[k - 1]) + 1 + reach
    stop = length_px + 2 * reach if k == len(nodes_px) - 1 else math.ceil(nodes_px[k + 1]) + reach
    return start, stop


def _blur_channel(channel: np.ndarray, grid: PSFGrid, step: float, padding: str, background, dtype) -> np.ndarray:
    """One channel: the image padded once, then each node's weighted window blurred and added."""
    rows, cols = channel.shape
    reach = max(padding_width_px(p.data.shape[0]) for p in grid.all_psfs())
    if padding == "constant" and background is None:
        background = border_mean(channel)
    padded = pad_array(np.asarray(channel, dtype=np.float64), ((reach, reach), (reach, reach)), padding, background)
    out = np.zeros(padded.shape, dtype=np.float64)
    for i in range(len(grid.rows_px)):
        r0, r1 = _support_padded(grid.rows_px, i, reach, rows)
        w_rows = tent_weights(np.arange(r0, r1) - reach, grid.rows_px, i)
        a0, a1 = max(r0 - reach, 0), min(r1 + reach, padded.shape[0])  # the window: support and the PSF's reach
        for j in range(len(grid.cols_px)):
            c0, c1 = _support_padded(grid.cols_px, j, reach, cols)
            w_cols = tent_weights(np.arange(c0, c1) - reach, grid.cols_px, j)
            b0, b1 = max(c0 - reach, 0), min(c1 + reach, padded.shape[1])
            window = np.zeros((a1 - a0, b1 - b0))
            window[r0 - a0:r1 - a0, c0 - b0:c1 - b0] = padded[r0:r1, c0:c1] * np.outer(w_rows, w_cols)
            out[a0:a1, b0:b1] += blur_image(window, grid.psfs[i][j], arcmin_per_px=step, padding="constant",
                                            background=0.0, dtype=dtype)
    return out[reach:reach + rows, reach:reach + cols].astype(dtype)


def blur_field_dependent(image: np.ndarray, grid: PSFGrid | Sequence[PSFGrid], *, arcmin_per_px: float,
                         padding: str = "constant", background: float | Sequence[float] | None = None,
                         dtype=np.float32) -> np.ndarray:
    """Blur a linear-light image by PSFs that vary over it (module doc), one `PSFGrid` for all channels or one per channel.

    Parameters and result as `vissim.optics.blur.convolve.blur_image` (``padding``, ``background``,
    ``dtype``); every node's PSF is checked as `blur_image` checks its PSF. A grid of one node is
    `blur_image` with that PSF.
    """
    if dtype not in (np.float32, np.float64):
        raise VissimInputError(f"dtype must be float32 or float64, got {dtype!r}")
    array = np.asarray(image)
    n_channels = array.shape[2] if array.ndim == 3 else 1
    grids = [grid] * n_channels if isinstance(grid, PSFGrid) else list(grid)
    if not grids or not all(isinstance(g, PSFGrid) for g in grids):
        raise VissimInputError("grid must be a PSFGrid or a list of PSFGrids, one per channel")
    firsts = grids[0].psfs[0][0] if array.ndim != 3 else [g.psfs[0][0] for g in grids]
    array, _, backgrounds = checked_blur_inputs(array, firsts, arcmin_per_px, padding, background)
    for c, g in enumerate(grids):  # every node's PSF checked against its channel as blur_image checks a PSF
        for psf in g.all_psfs():
            checked_blur_inputs(array if array.ndim == 2 else array[..., c], psf, arcmin_per_px, padding,
                                backgrounds[c])
    channels = [array] if array.ndim == 2 else [array[..., c] for c in range(array.shape[2])]
    blurred = []
    for channel, g, b in zip(channels, grids, backgrounds):
        if g.node_count == 1:
            blurred.append(blur_image(channel, g.psfs[0][0], arcmin_per_px=arcmin_per_px, padding=padding,
                                      background=b, dtype=dtype))
        else:
            blurred.append(_blur_channel(channel, g, arcmin_per_px, padding, b, dtype))
    return blurred[0] if array.ndim == 2 else np.stack(blurred, axis=-1)
