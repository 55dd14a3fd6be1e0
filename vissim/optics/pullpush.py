"""Pull-push interpolation (Gortler et al. 1996): filling data behind occluders.

Used by :mod:`vissim.optics.depth` to extend each depth layer's colour and coverage behind nearer
content, as in Kraus & Strengert (2007), so a blurred near edge shows the background's
continuation instead of a dark or bright halo.
"""

from __future__ import annotations

import numpy as np

from vissim.optics.array_backend import array_module

__all__ = ["pull_push", "upsample2"]


def upsample2(coarse: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """x2 bilinear upsampling of (C, h, w) onto (C, *shape) (cell-centred, edges clamped)."""
    xp = array_module(coarse)
    out = coarse
    for axis, size in ((1, shape[0]), (2, shape[1])):
        def at(part, axis=axis):  # ``part`` (a slice) along ``axis``
            return (slice(None),) * axis + (part,)

        n = out.shape[axis]
        fine = xp.empty(out.shape[:axis] + (2 * n,) + out.shape[axis + 1 :], out.dtype)
        xp.multiply(out, 0.75, out=fine[at(slice(0, None, 2))])
        fine[at(slice(1, None, 2))] = fine[at(slice(0, None, 2))]
        quarter = out * 0.25
        fine[at(slice(2, None, 2))] += quarter[at(slice(None, -1))]
        fine[at(slice(0, 1))] += quarter[at(slice(0, 1))]
        fine[at(slice(1, -1, 2))] += quarter[at(slice(1, None))]
        fine[at(slice(-1, None))] += quarter[at(slice(-1, None))]
        out = fine[at(slice(0, size))]
    return out


def pull_push(premultiplied: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Estimate ``premultiplied / weight`` (C, H, W) where ``weight`` (H, W) < 1 (Gortler et al. 1996).

    Pull: 2 x 2 box sums, weights saturated at 1.  Push: each level keeps its own data and
    takes ``1 - weight`` of the bilinearly upsampled coarser estimate, so a pixel of weight 1
    keeps its value and one of weight 0 gets a smooth estimate from its neighbourhood.  The
    estimate is returned at *half* resolution (level 1, cells of 2 x 2 pixels): the caller
    uses it only where its own data are missing, nearest-upsampled.
    """
    xp = array_module(premultiplied)
    levels = []
    q, w = premultiplied, weight
    while max(w.shape) > 1:
        h, wd = w.shape
        if h % 2 or wd % 2:
            q = xp.pad(q, ((0, 0), (0, h % 2), (0, wd % 2)))
            w = xp.pad(w, ((0, h % 2), (0, wd % 2)))
        q = _box_sum(q[:, 0::2, 0::2], q[:, 1::2, 0::2], q[:, 0::2, 1::2], q[:, 1::2, 1::2], xp)
        w = _box_sum(w[0::2, 0::2], w[1::2, 0::2], w[0::2, 1::2], w[1::2, 1::2], xp)
        scale = 1.0 / xp.maximum(w, 1.0)
        q *= scale
        w *= scale
        levels.append((q, w))
    if not levels:  # a single pixel
        return premultiplied / xp.where(weight > 0, weight, 1.0)
    q, w = levels[-1]
    value = q / xp.where(w > 0, w, 1.0)
    for q, w in reversed(levels[:-1]):
        value = upsample2(value, w.shape)  # q + (1 - w) x the coarser estimate, in place
        value *= 1.0 - w
        value += q
    return value


def _box_sum(a, b, c, d, xp):
    """``a + b + c + d``, summed in that order into one new array."""
    out = xp.add(a, b)
    out += c
    out += d
    return out
