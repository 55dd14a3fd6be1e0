"""The pupil sampled for geometric optics: a stratified, jittered grid of rays with a fixed seed.

One ray per cell of an ``n x n`` grid over the unit square, jittered within its cell, kept
inside the unit disc: each ray stands for an equal share of the pupil's area.  The points are
image-oriented (``u`` along columns, ``v`` along rows; `vissim.units.image_colrow_to_osa_xy`
gives the OSA pupil point).  The geometric PSF (`vissim.optics.psf.compute.compute_psf`) and the
layered depth blur (`vissim.optics.depth.layered.composite_layers`) both draw their rays here,
so that one layer alone blurs exactly by the geometric PSF; the field estimate
(`vissim.optics.psf.field_size`) takes the grid's cell centres, unjittered.  `landing_arcmin` is
where a ray lands in the image, for all of them.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from vissim.units import image_colrow_to_osa_xy, osa_xy_to_image_colrow, rad_to_arcmin

__all__ = ["PUPIL_RAY_SEED", "MIN_RAYS", "MAX_RAYS", "RAYS_PER_COVERED_PX", "ray_count", "stratified_pupil_rays",
           "pupil_cell_centres", "landing_arcmin", "histogram_on_edges"]

#: Fixed: the same wavefront gives the same rays, hence the same PSF.
PUPIL_RAY_SEED = 20151218
#: Rays per PSF: this many per pixel the blur covers, within [`MIN_RAYS`, `MAX_RAYS`].
MIN_RAYS, MAX_RAYS = 250_000, 4_000_000
RAYS_PER_COVERED_PX = 400


def ray_count(blur_radius_px: float) -> int:
    """Rays for a blur of radius ``blur_radius_px``: `RAYS_PER_COVERED_PX` per pixel of its disc, one pixel wider."""
    covered_px = math.pi * (blur_radius_px + 1.0) ** 2
    return int(min(MAX_RAYS, max(MIN_RAYS, RAYS_PER_COVERED_PX * covered_px)))


@functools.lru_cache(maxsize=8)
def stratified_pupil_rays(n_rays: int) -> tuple[np.ndarray, np.ndarray]:
    """Image-oriented unit-disc pupil points ``(u, v)``: about ``n_rays`` of them (the grid's cells inside the disc).

    Kept, read-only: every PSF and depth layer of the same ray count draws the same rays.
    """
    n_side = int(math.ceil(math.sqrt(n_rays * 4.0 / math.pi)))
    rng = np.random.default_rng(PUPIL_RAY_SEED)
    u, v = _cell_grid(n_side)
    u = u + (rng.random(u.shape) - 0.5) * (2.0 / n_side)
    v = v + (rng.random(v.shape) - 0.5) * (2.0 / n_side)
    u, v = _in_disc(u, v)
    u.setflags(write=False)
    v.setflags(write=False)
    return u, v


def pupil_cell_centres(n_side: int) -> tuple[np.ndarray, np.ndarray]:
    """The centres ``(u, v)`` of an ``n_side x n_side`` grid's cells inside the unit disc (no jitter)."""
    return _in_disc(*_cell_grid(n_side))


def _cell_grid(n_side: int) -> tuple[np.ndarray, np.ndarray]:
    cells = (np.arange(n_side) + 0.5) / n_side * 2.0 - 1.0
    return np.meshgrid(cells, cells)


def _in_disc(u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    keep = u * u + v * v <= 1.0
    return u[keep], v[keep]


def landing_arcmin(wavefront, pupil_diameter_mm: float, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where the rays through image-oriented unit-disc points ``(u, v)`` land: image offsets (col, row), arcmin.

    A ray goes in the direction ``+grad W`` of ``wavefront`` (a Zernike `Wavefront` or an `OpdMap`) at its
    OSA pupil point (``docs/conventions.md``, "Sign of the wavefront"), mapped to the image by
    `vissim.units.osa_xy_to_image_colrow`.
    """
    radius = pupil_diameter_mm / 2.0
    sx, sy = wavefront.slopes_mrad(*image_colrow_to_osa_xy(u * radius, v * radius))  # image-oriented pupil -> OSA
    col_mrad, row_mrad = osa_xy_to_image_colrow(sx, sy)
    return rad_to_arcmin(col_mrad * 1e-3), rad_to_arcmin(row_mrad * 1e-3)


def _bins_on_edges(x: np.ndarray, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each value's bin among near-uniform ``edges`` (``edges[i] <= x < edges[i + 1]``; the last edge in the last
    bin), and which values fall inside: a division's guess, then put right against the edges themselves."""
    n = len(edges) - 1
    inside = (x >= edges[0]) & (x <= edges[-1])  # NaN is outside
    guess = np.floor((np.where(inside, x, edges[0]) - edges[0]) * (n / (edges[-1] - edges[0])))
    index = np.clip(guess, 0, n - 1).astype(np.intp)
    while True:
        low = x < edges[index]
        high = (x >= edges[index + 1]) & (index < n - 1)
        moved = inside & (low | high)
        if not moved.any():
            return index, inside
        index = np.clip(index - (moved & low) + (moved & high), 0, n - 1)


def histogram_on_edges(row: np.ndarray, col: np.ndarray, edges: np.ndarray, weights=None) -> np.ndarray:
    """``np.histogram2d(row, col, bins=(edges, edges), weights=weights)[0]``, bin for bin, without its binary
    search: ``edges`` are near uniform (a pixel grid), so each value's bin is found by division and checked."""
    edges = np.asarray(edges, dtype=float)
    n = len(edges) - 1
    row_bin, row_in = _bins_on_edges(np.asarray(row, dtype=float), edges)
    col_bin, col_in = _bins_on_edges(np.asarray(col, dtype=float), edges)
    keep = row_in & col_in
    flat = row_bin[keep] * n + col_bin[keep]
    kept = None if weights is None else np.asarray(weights, dtype=float)[keep]
    return np.bincount(flat, kept, minlength=n * n).reshape(n, n).astype(float)
