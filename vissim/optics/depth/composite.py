"""One depth layer extended and blurred on its window, and the layers composited near to far.

The stages of `vissim.optics.depth.depth_map.blur_depth` after its plan and matte (that module's doc:
"Compositing" and "Cost"): `blurred_layer` extends a layer behind nearer content by pull-push and
blurs it on its window; `Compositor` adds the blurred layers, nearest first, each through the
transmission of the nearer ones, and normalises by the blurred coverage.
"""

from __future__ import annotations

import functools
import logging
from dataclasses import dataclass

import numpy as np

from vissim.optics.depth.psfs import LayerOptics
from vissim.optics.runtime.array_backend import CPU as CPU_BACKEND
from vissim.optics.blur.device import convolve_window
from vissim.optics.depth.windows import (add_overlap, blur_coarse, extended_layer, grow_box, nonzero_box,
                                         occlusion_weight)

__all__ = ["Compositor", "EXTENSION_HALO_PX", "LayerScene", "blurred_layer"]

log = logging.getLogger(__name__)

#: Pixels by which a layer's continuation behind nearer content is estimated beyond its window.
EXTENSION_HALO_PX = 64


@dataclass(frozen=True, eq=False)
class LayerScene:
    """What blurring one layer needs: the scene and its matte on the array backend, each layer's box,
    PSF (``optics``) and reach (px: its PSF's half-width + 1, on the image's grid)."""

    colour: object
    lower: object
    upper: object
    frac: object
    layer_diopters: np.ndarray
    threshold_diopters: float
    boxes: dict
    reach: dict
    optics: LayerOptics
    padding: str
    backend: object
    threads: int | None  # FFT threads per convolution: 1 while the pool's threads blur layers at once

    @classmethod
    def on(cls, backend, colour, matte: tuple, layer_diopters, threshold_diopters, boxes, optics: LayerOptics,
           padding: str, threads: int | None) -> LayerScene:
        """The scene and its tent ``matte`` (lower, upper, frac) moved to ``backend``; each non-empty layer's
        reach found from its PSF's size."""
        reach = {k: (optics.sizes[k] // 2 + 1) * optics.scales[k] for k in optics.fronts}
        lower, upper, frac = matte  # indices of NumPy's own type (its take() converts others at every layer)
        if backend is not CPU_BACKEND:  # half the bytes to send
            lower, upper = (np.asarray(a, np.int32) for a in (lower, upper))
        colour, lower, upper, frac = (backend.asarray(a) for a in (colour, lower, upper, frac))
        return cls(colour, lower, upper, frac, layer_diopters, threshold_diopters, boxes, reach, optics, padding,
                   backend, threads)

    @property
    def shape(self) -> tuple[int, int]:
        return self.lower.shape

    @functools.cached_property
    def widest_reach(self) -> int:
        """``r_max``: the largest PSF's reach (px)."""
        return max(self.reach.values())

    def window(self, k: int) -> tuple[int, int, int, int]:
        """Layer ``k``'s window (`blurred_layer`): its matte's box grown by ``2 (r_k + r_max)``, inside the image."""
        return grow_box(self.boxes[k], 2 * (self.reach[k] + self.widest_reach), self.shape)

    def window_px(self, k: int) -> int:
        """Pixels in layer ``k``'s window: what its extension and blur cost, roughly."""
        r0, r1, c0, c1 = self.window(k)
        return (r1 - r0) * (c1 - c0)


def blurred_layer(scene: LayerScene, k: int) -> tuple:
    """Layer ``k`` extended behind nearer content and blurred on its window: (window, blurred planes, padded shape).

    The planes are the premultiplied colours and, last, the extended coverage.  Layer k reaches
    its matte's box grown by its own PSF; its continuation behind nearer content matters only
    where that content's blur leaves it visible: the largest PSF's reach further.  The
    continuation is estimated on a larger window: pull-push's coarse levels see farther.
    """
    rows, cols = scene.shape
    boxes, reach, scale = scene.boxes, scene.reach, scene.optics.scales[k]
    window = scene.window(k)
    e0, e1, f0, f1 = grow_box(window, EXTENSION_HALO_PX, (rows, cols))
    wide = (slice(e0, e1), slice(f0, f1))
    planes = extended_layer(scene.colour[:, e0:e1, f0:f1], scene.lower[wide], scene.upper[wide], scene.frac[wide],
                            scene.layer_diopters, k, scene.threshold_diopters, rows=(boxes[k][0] - e0, boxes[k][1] - e0),
                            keep=(window[0] - e0, window[1] - e0))
    window_rows = window[0]
    planes = planes[:, window[0] - e0 : window[1] - e0]  # the rows extended: those of the window
    if scale == 1:  # the blur reaches only the planes' nonzero box grown by the PSF
        window = grow_box(nonzero_box(planes, (window_rows, f0)), reach[k], (rows, cols), within=window)
    r0, r1, c0, c1 = window
    planes = planes[:, r0 - window_rows : r1 - window_rows, c0 - f0 : c1 - f0]
    touches = (r0 == 0, r1 == rows, c0 == 0, c1 == cols)
    if scale == 1:
        blurred, shape = convolve_window(planes, scene.optics.psf(k), scene.padding, touches, scene.backend,
                                         threads=scene.threads)
    else:
        blurred, shape = blur_coarse(planes, scene.optics.psf(k), scene.padding, touches, scale, scene.backend,
                                     scene.threads)
    return window, blurred, shape


class Compositor:
    """Blurred layers composited near to far (module doc, "Compositing"): ``sum_k T_k B_k(P_k)`` and
    ``sum_k T_k B_k(A_k)``, with each nearer layer's blurred coverage kept while it may occlude."""

    def __init__(self, scene: LayerScene, farthest_diopters: float):
        xp, (rows, cols) = scene.backend.xp, scene.shape
        self.scene, self.farthest = scene, farthest_diopters
        self.numerator = xp.zeros_like(scene.colour)
        self.denominator = xp.zeros((rows, cols), np.float32)
        self.occluders = xp.zeros((rows, cols), np.float32)  # blurred coverage of layers that fully occlude this one
        self.pending: list[tuple[float, tuple, np.ndarray]] = []  # nearer layers' blurred coverage, partly occluding
        self.largest = (0, 0)  # the largest padded window blurred

    def add(self, k: int, window: tuple, blurred, shape: tuple[int, int]) -> None:
        """Layer ``k`` (nearer ones added before it), through its transmission ``T_k``."""
        proximity = self.scene.layer_diopters[k]
        transmitted = self._transmission(proximity, window)
        self.largest = max(self.largest, shape)
        if proximity - self.scene.threshold_diopters > self.farthest:  # it occludes layers behind: keep its coverage
            self.pending.append((proximity, window, blurred[-1].copy()))
        first, end = self._seen_rows(transmitted)
        if first == end:
            return
        r0, c0, c1 = window[0], window[2], window[3]
        blurred = blurred[:, first:end]
        blurred *= transmitted[first:end]
        self.numerator[:, r0 + first : r0 + end, c0:c1] += blurred[:-1]
        self.denominator[r0 + first : r0 + end, c0:c1] += blurred[-1]

    def _seen_rows(self, transmitted) -> tuple[int, int]:
        """The rows (first, end) of a window between which a layer shows: the leading and trailing rows that
        nearer content hides completely add nothing (on the CPU; a GPU takes the whole window, unsynchronised)."""
        if self.scene.backend is not CPU_BACKEND:
            return 0, transmitted.shape[0]
        seen = np.flatnonzero(transmitted.any(axis=1))
        return (0, 0) if seen.size == 0 else (int(seen[0]), int(seen[-1]) + 1)

    def _transmission(self, proximity: float, window: tuple):
        """``T`` on ``window`` for a layer at ``proximity`` (D): what the nearer layers added so far let through."""
        threshold, xp = self.scene.threshold_diopters, self.scene.backend.xp
        while self.pending and self.pending[0][0] - proximity >= 2 * threshold:  # near to far
            _, (r0, r1, c0, c1), matte_j = self.pending.pop(0)
            self.occluders[r0:r1, c0:c1] += matte_j
        r0, r1, c0, c1 = window
        transmitted = self.occluders[r0:r1, c0:c1].copy()
        for proximity_j, window_j, matte_j in self.pending:
            weight = occlusion_weight(proximity_j - proximity, threshold)
            if weight > 0:
                add_overlap(transmitted, window, matte_j, window_j, weight)
        xp.subtract(1.0, transmitted, out=transmitted)
        xp.clip(transmitted, 0.0, 1.0, out=transmitted)
        return transmitted

    def image(self, crop: int) -> np.ndarray:
        """The composite, normalised by the blurred coverage, ``crop`` px cut from each side: (C, H', W') on the CPU."""
        xp, (rows, cols) = self.scene.backend.xp, self.scene.shape
        low = int((self.denominator < 0.5).sum())
        if low:
            log.info("depth blur: %d pixels have total blurred coverage below 0.5 (min %.3g)", low,
                     float(self.denominator.min()))
        out = self.numerator / xp.maximum(self.denominator, 1e-6)
        return self.scene.backend.to_numpy(out[:, crop : rows - crop, crop : cols - crop])
