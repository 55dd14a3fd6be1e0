"""Pull-push interpolation (Gortler et al. 1996): filling data behind occluders.

Used by `vissim.optics.depth.depth_map` to extend each depth layer's colour and coverage behind nearer
content, as in Kraus & Strengert (2007), so a blurred near edge shows the background's
continuation instead of a dark or bright halo.
"""

from __future__ import annotations

import numpy as np

from vissim.optics.runtime.array_backend import array_module

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
        near, far = out * 0.75, out * 0.25  # a fine sample: 3/4 of its coarse sample, 1/4 of the next one out
        xp.add(near[at(slice(1, None))], far[at(slice(None, -1))], out=fine[at(slice(2, None, 2))])
        xp.add(near[at(slice(None, -1))], far[at(slice(1, None))], out=fine[at(slice(1, -1, 2))])
        for edge in (slice(0, 1), slice(-1, None)):  # the first and last take their own sample's quarter
            xp.add(near[at(edge)], far[at(edge)], out=fine[at(edge)])
        out = fine[at(slice(0, size))]
    return out


def pull_push(premultiplied: np.ndarray, weight: np.ndarray, rows: tuple[int, int] | None = None,
              wanted: tuple[int, int] | None = None) -> np.ndarray:
    """Estimate ``premultiplied / weight`` (C, H, W) where ``weight`` (H, W) < 1 (Gortler et al. 1996).

    Pull: 2 x 2 box sums, weights saturated at 1.  Push: each level keeps its own data and
    takes ``1 - weight`` of the bilinearly upsampled coarser estimate, so a pixel of weight 1
    keeps its value and one of weight 0 gets a smooth estimate from its neighbourhood.  The
    estimate is returned at *half* resolution (level 1, cells of 2 x 2 pixels): the caller
    uses it only where its own data are missing, nearest-upsampled.  ``rows`` (first, end): the
    rows outside which ``premultiplied`` is zero, whose sums need not be formed (default: all).
    ``wanted`` (first, end): the estimate's rows (at half resolution) the caller uses; only those
    are returned, pushed from only the coarser rows they depend on (default: all).
    """
    xp = array_module(premultiplied)
    levels = []
    q, w = premultiplied, weight
    first, end = rows or (0, weight.shape[0])
    while max(w.shape) > 1:
        first, end = first // 2, min((end + 1) // 2, (w.shape[0] + 1) // 2)  # this level's rows holding data
        coarse = xp.zeros((q.shape[0], (w.shape[0] + 1) // 2, (w.shape[1] + 1) // 2), q.dtype)
        coarse[:, first:end] = _box_sum(q[:, 2 * first : 2 * end], xp)  # elsewhere sums of zeros
        q, w = coarse, _box_sum(w, xp)
        scale = 1.0 / xp.maximum(w, 1.0)
        q[:, first:end] *= scale[first:end]
        w *= scale
        levels.append((q, w))
    if not levels:  # a single pixel
        return premultiplied / xp.where(weight > 0, weight, 1.0)
    # The rows each level must push: a fine row of the cell-centred bilinear upsampling reads its
    # own coarse row and the next one up or down.
    spans = [wanted or (0, levels[0][1].shape[0])]
    for _, w in levels[1:]:
        first, end = spans[-1]
        spans.append((max(first // 2 - 1, 0), min((end - 1) // 2 + 2, w.shape[0])))
    q, w = levels[-1]
    first, end = spans[-1]
    value = q[:, first:end] / xp.where(w[first:end] > 0, w[first:end], 1.0)
    for (q, w), (fine_first, fine_end), coarse_first in zip(reversed(levels[:-1]), reversed(spans[:-1]),
                                                            reversed([s[0] for s in spans[1:]])):
        # q + (1 - w) x the coarser estimate, in place, on the rows needed
        value = upsample2(value, (2 * value.shape[1], w.shape[1]))[:, fine_first - 2 * coarse_first :
                                                                    fine_end - 2 * coarse_first]
        value *= 1.0 - w[fine_first:fine_end]
        value += q[:, fine_first:fine_end]
    return value


def _box_sum(array, xp):
    """Sums of 2 x 2 cells over the last two axes (an odd last row or column: cells of its pixels alone).

    Each cell adds its pixels in the order (0, 0), (1, 0), (0, 1), (1, 1), as if the array were
    padded with zeros to even sizes (x + 0 = x), without copying it.
    """
    h, w = array.shape[-2:]
    out = array[..., 0::2, 0::2].copy()
    out[..., : h // 2, :] += array[..., 1::2, 0::2]
    out[..., :, : w // 2] += array[..., 0::2, 1::2]
    out[..., : h // 2, : w // 2] += array[..., 1::2, 1::2]
    return out
