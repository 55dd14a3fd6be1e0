"""One depth layer on its window: its tent matte, its continuation behind nearer content, its blur.

Used by `vissim.optics.depth.depth_map.blur_depth` (module doc there: "Compositing" and "Cost").
"""

from __future__ import annotations

import math

import numpy as np

from vissim.optics.runtime.array_backend import CPU as CPU_BACKEND
from vissim.optics.runtime.array_backend import ArrayBackend, array_module
from vissim.optics.blur.device import WINDOW_PADDING_MODES, convolve_window
from vissim.optics.psf.compute import PSF
from vissim.optics.depth.pullpush import pull_push, upsample2

__all__ = ["DEPTH_PADDING_MODES", "COARSE_FACTOR", "occlusion_weight", "extended_layer", "layer_boxes", "grow_box",
           "nonzero_box", "add_overlap", "blur_coarse"]

#: How a depth blur continues the image beyond its border: as each layer's window is padded.
DEPTH_PADDING_MODES = WINDOW_PADDING_MODES


def occlusion_weight(proximity_gap_diopters, threshold_diopters: float):
    """How much nearer content occludes: 0 up to the threshold, rising to 1 at twice it."""
    return np.clip(np.asarray(proximity_gap_diopters) / threshold_diopters - 1.0, 0.0, 1.0)


def extended_layer(colour, lower, upper, frac, layer_diopters: np.ndarray, k: int, threshold_diopters: float, work=None,
                    rows: tuple[int, int] | None = None, keep: tuple[int, int] | None = None):
    """Layer ``k``: premultiplied colours and coverage (C + 1, H, W), extended behind its occluders.

    ``lower``/``upper`` are each pixel's two layers and ``frac`` (float32) its weight in
    ``upper`` (the tent matte).  ``hidden`` is the part of each pixel that occludes layer ``k``
    (its mattes on nearer layers, weighted by `occlusion_weight`); there layer ``k``
    continues with the pull-push estimate of its own colour and coverage from the rest of the
    image (where its coverage is 0 the estimate is 0 too: no layer grows sideways).  The
    extended coverage also occludes the layers behind it: they are behind its continuation.
    ``work`` (from `_workspace`) holds reused buffers; the result may be one of them.
    ``rows`` (first, end): the rows outside which layer ``k``'s matte is zero (default: unknown).
    ``keep`` (first, end): the rows of the result the caller uses; others are left undefined
    (default: all).
    """
    xp = array_module(colour)
    n_ch = colour.shape[0]
    work = _workspace(colour.shape, xp) if work is None else work
    stack, hidden, scratch = work["stack"], work["hidden"], work["scratch"]
    height = colour.shape[1]
    first, end = rows or (0, height)
    keep_first, keep_end = keep or (0, height)
    # zero beside the matte: in the rows kept, and a row either side (pull-push's first 2 x 2 cells read it)
    stack[:, min(keep_first, max(first - 1, 0)) : first] = 0.0
    stack[:, end : max(keep_end, min(end + 1, height))] = 0.0
    band = (slice(first, end), slice(None))
    matte = stack[n_ch, first:end]
    matte[...] = _matte(lower[band], upper[band], frac[band], k, xp)
    xp.multiply(colour[:, first:end], matte, out=stack[:n_ch, first:end])
    weights = occlusion_weight(layer_diopters - layer_diopters[k], threshold_diopters).astype(np.float32)
    if not weights.any():
        return stack
    weights = xp.asarray(weights)
    xp.take(weights, lower, out=hidden)
    xp.take(weights, upper, out=scratch)
    scratch -= hidden
    scratch *= frac
    hidden += scratch
    hidden_rows = keep_first + np.flatnonzero(_to_host(hidden[keep_first:keep_end].any(axis=1)))
    if hidden_rows.size == 0:  # nothing of layer k is hidden in the rows kept
        return stack
    xp.subtract(1.0, hidden, out=scratch)
    # Where hidden > 0 the pixel has no coverage of its own on layer k (its layers are nearer),
    # so level 0 of the push is hidden * (upsampled estimate); it enters weighted by hidden again
    # (rows without hidden pixels: nothing to add).
    r0, r1 = int(hidden_rows[0]) // 2, (int(hidden_rows[-1]) + 2) // 2  # estimate rows: 2 x 2 cells
    estimate = pull_push(stack, scratch, rows=(first, end), wanted=(r0, r1))
    # each estimate cell's two columns, then its two rows one parity at a time (nearest upsampling, unbuilt)
    columns = xp.repeat(estimate, 2, axis=2)[:, :, : hidden.shape[1]]
    low, high = max(2 * r0, keep_first), min(2 * r1, keep_end)
    squared = hidden[low:high]
    squared *= squared
    for parity in (0, 1):
        start = low + (parity - low) % 2  # the first row of this parity
        count = len(range(start, high, 2))
        if count:
            cells = columns[:, (start - 2 * r0) // 2 : (start - 2 * r0) // 2 + count]
            stack[:, start:high:2] += cells * squared[start - low :: 2]
    return stack


def _matte(lower, upper, frac, k: int, xp):
    """Layer ``k``'s tent matte: ``1 - frac`` where it is the pixel's farther layer, ``frac`` where the nearer."""
    return xp.where(lower == k, 1.0 - frac, xp.where(upper == k, frac, 0.0))


def layer_boxes(lower, upper, frac, n_layers: int) -> dict[int, tuple[int, int, int, int]]:
    """Each layer's bounding box (row0, row1, col0, col1) of the pixels its tent matte touches."""
    rows, cols = lower.shape
    row_index = np.arange(rows, dtype=np.int64)[:, None]
    col_index = np.arange(cols, dtype=np.int64)[None, :]
    in_lower, in_upper = (frac < 1.0).astype(np.float32), (frac > 0.0).astype(np.float32)
    hits = []
    for index, size in ((row_index, rows), (col_index, cols)):
        count = np.zeros(n_layers * size)
        for layer, present in ((lower, in_lower), (upper, in_upper)):
            count += np.bincount((layer * size + index).ravel(), weights=present.ravel(),
                                 minlength=n_layers * size)
        hits.append(count.reshape(n_layers, size) > 0)
    boxes = {}
    for k in range(n_layers):
        r, c = np.flatnonzero(hits[0][k]), np.flatnonzero(hits[1][k])
        if r.size:
            boxes[k] = (int(r[0]), int(r[-1]) + 1, int(c[0]), int(c[-1]) + 1)
    return boxes


def grow_box(box, reach: int, shape, within=None) -> tuple[int, int, int, int]:
    """``box`` grown by ``reach`` on every side, inside the image (``shape``) and ``within`` a window."""
    r0, r1, c0, c1 = box
    w0, w1, v0, v1 = within or (0, shape[0], 0, shape[1])
    return max(r0 - reach, w0), min(r1 + reach, w1), max(c0 - reach, v0), min(c1 + reach, v1)


def nonzero_box(planes, origin: tuple[int, int]) -> tuple[int, int, int, int]:
    """The box (row0, row1, col0, col1) of the image holding every nonzero pixel of (C, h, w) ``planes``
    whose pixel [0, 0] is the image's ``origin``; all of them if none is nonzero."""
    nonzero = planes.any(axis=0)
    rows = np.flatnonzero(_to_host(nonzero.any(axis=1)))
    cols = np.flatnonzero(_to_host(nonzero.any(axis=0)))
    if rows.size == 0:
        rows, cols = np.arange(planes.shape[1]), np.arange(planes.shape[2])
    r0, c0 = origin
    return r0 + int(rows[0]), r0 + int(rows[-1]) + 1, c0 + int(cols[0]), c0 + int(cols[-1]) + 1


def _to_host(array) -> np.ndarray:
    return array.get() if hasattr(array, "get") and not isinstance(array, np.ndarray) else np.asarray(array)


def add_overlap(target: np.ndarray, window, source: np.ndarray, source_window, scale) -> None:
    """``target`` (on ``window``) += ``scale`` x ``source`` (on ``source_window``) where the two windows overlap."""
    r0, r1 = max(window[0], source_window[0]), min(window[1], source_window[1])
    c0, c1 = max(window[2], source_window[2]), min(window[3], source_window[3])
    if r0 < r1 and c0 < c1:
        part = source[r0 - source_window[0] : r1 - source_window[0], c0 - source_window[2] : c1 - source_window[2]]
        target[r0 - window[0] : r1 - window[0], c0 - window[2] : c1 - window[2]] += \
            scale * part


#: The coarse grid's pixel, in image pixels per side (``coarse_blur_px`` of `blur_depth`).
COARSE_FACTOR = 2


def blur_coarse(planes, psf: PSF, padding: str, touches, factor: int, backend: ArrayBackend = CPU_BACKEND,
                threads: int | None = None) -> tuple:
    """Blur on a grid ``factor`` times coarser: block means in, the coarse PSF, bilinear (cell-centred) back.

    ``psf`` is sampled at ``factor`` times the image's arcmin/px.  For a wide PSF the blurred
    image holds little above the coarse grid's Nyquist frequency, so this is close to the fine
    blur (`COARSE_MIN_DB` at `COARSE_BLUR_PX`) at a quarter of the FFT work.
    """
    n, h, w = planes.shape
    q = factor
    xp = backend.xp
    even = xp.pad(planes, ((0, 0), (0, (-h) % q), (0, (-w) % q)), mode="edge")
    coarse = even.reshape(n, even.shape[1] // q, q, even.shape[2] // q, q).mean(axis=(2, 4))
    blurred, shape = convolve_window(xp.ascontiguousarray(coarse, dtype=np.float32), psf, padding, touches, backend,
                                     threads=threads)
    fine = blurred
    for _ in range(int(round(math.log2(q)))):
        fine = upsample2(fine, (2 * fine.shape[1], 2 * fine.shape[2]))
    return fine[:, :h, :w], shape


def _workspace(shape: tuple[int, int, int], xp=np) -> dict:
    """Buffers for `extended_layer` (``xp``: the array module, NumPy or CuPy)."""
    n_ch, rows, cols = shape
    return {
        "stack": xp.empty((n_ch + 1, rows, cols), np.float32),
        "hidden": xp.empty((rows, cols), np.float32),
        "scratch": xp.empty((rows, cols), np.float32),
    }
