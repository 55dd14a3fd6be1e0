"""The pupil sampled for geometric optics: a stratified, jittered grid of rays with a fixed seed.

One ray per cell of an ``n x n`` grid over the unit square, jittered within its cell, kept
inside the unit disc: each ray stands for an equal share of the pupil's area.  The points are
image-oriented (``u`` along columns, ``v`` along rows; `vissim.units.image_colrow_to_osa_xy`
gives the OSA pupil point).  The geometric PSF (`vissim.optics.psf.compute_psf`) and the
layered depth blur (`vissim.optics.depth_layers.composite_layers`) both draw their rays here,
so that one layer alone blurs exactly by the geometric PSF.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["PUPIL_RAY_SEED", "MIN_RAYS", "MAX_RAYS", "RAYS_PER_COVERED_PX", "ray_count", "stratified_pupil_rays"]

#: Fixed: the same wavefront gives the same rays, hence the same PSF.
PUPIL_RAY_SEED = 20151218
#: Rays per PSF: this many per pixel the blur covers, within [`MIN_RAYS`, `MAX_RAYS`].
MIN_RAYS, MAX_RAYS = 250_000, 4_000_000
RAYS_PER_COVERED_PX = 400


def ray_count(blur_radius_px: float) -> int:
    """Rays for a blur of radius ``blur_radius_px``: `RAYS_PER_COVERED_PX` per pixel of its disc, one pixel wider."""
    covered_px = math.pi * (blur_radius_px + 1.0) ** 2
    return int(min(MAX_RAYS, max(MIN_RAYS, RAYS_PER_COVERED_PX * covered_px)))


def stratified_pupil_rays(n_rays: int) -> tuple[np.ndarray, np.ndarray]:
    """Image-oriented unit-disc pupil points ``(u, v)``: about ``n_rays`` of them (the grid's cells inside the disc)."""
    n_side = int(math.ceil(math.sqrt(n_rays * 4.0 / math.pi)))
    rng = np.random.default_rng(PUPIL_RAY_SEED)
    cells = (np.arange(n_side) + 0.5) / n_side * 2.0 - 1.0
    u, v = np.meshgrid(cells, cells)
    u = u + (rng.random(u.shape) - 0.5) * (2.0 / n_side)
    v = v + (rng.random(v.shape) - 0.5) * (2.0 / n_side)
    keep = u * u + v * v <= 1.0
    return u[keep], v[keep]
