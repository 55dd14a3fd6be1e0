"""The depth blur's PSFs and its threads: one PSF per distinct wavefront, layers worked on ahead.

Used by `vissim.optics.depth.depth_map.blur_depth` (module doc there: "Cost" and "Threads").
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from vissim.optics.runtime.array_backend import CPU as CPU_BACKEND
from vissim.optics.runtime.array_backend import ArrayBackend
from vissim.optics.psf.compute import PSF, compute_psf, suggested_size_px
from vissim.optics.runtime.threads import single_threaded_blas, spare_threads
from vissim.optics.pupil.wavefront import Wavefront

__all__ = ["cached_psf", "LayerOptics", "worker_threads", "layer_pool", "in_order"]

@functools.lru_cache(maxsize=128)
def cached_psf(items: tuple, pupil_mm: float, wavelength_nm: float, step: float, mode: str,
                size_px: int | None = None) -> PSF:
    """The PSF of one layer's wavefront (cached by wavefront), on a field that holds its blur or of ``size_px``
    (a coarse grid's, the fine field's arcmin; refused if it cannot hold it)."""
    front = Wavefront(dict(items), pupil_mm)
    return compute_psf(front, pupil_diameter_mm=pupil_mm, wavelength_nm=wavelength_nm, arcmin_per_px=step,
                       size_px="auto" if size_px is None else size_px, mode=mode)


def _wavefront_key(coefficients: dict, sign: float = 1.0) -> tuple:
    return tuple(sorted((k, round(sign * v, 12)) for k, v in coefficients.items() if round(v, 12) != 0.0))


def _reflected(psf: PSF, front: Wavefront) -> PSF:
    """``psf`` reflected through its centre, as the PSF of ``front`` (the negative of its wavefront).

    ``|F(P e^{-ikW})(x)|^2 = |F(P e^{ikW})(-x)|^2``, and the geometric PSF's rays land at
    ``-grad W``: both PSFs of ``-W`` are those of ``W`` reflected through the origin (to round-off;
    odd sizes only, whose origin ``[N//2, N//2]`` is the centre).  For an eye whose wavefront is
    defocus alone, the symmetric layer plan pairs every layer with one of opposite defocus.
    """
    data = np.ascontiguousarray(psf.data[::-1, ::-1])
    data.setflags(write=False)
    return dataclasses.replace(psf, data=data, wavefront=front)


class LayerOptics:
    """Each non-empty layer's PSF, computed at most once.

    ``fronts`` and ``scales`` (the grid's pixel, in image pixels) by layer, far to near.  A layer
    either computes its PSF (cached by wavefront) or reflects that of an earlier layer whose
    wavefront is its negative (and whose size is odd).  ``sizes``: each PSF's side (px of its
    grid), found on ``pool``'s threads if given.  `prefetch` computes a layer's PSF in
    ``pool``; `psf` waits for it.
    """

    def __init__(self, fronts: dict, scales: dict, pupil_mm: float, wavelength_nm: float, step: float, mode: str,
                 pool: ThreadPoolExecutor | None = None):
        self.fronts, self.scales = fronts, scales
        self.optics = (pupil_mm, wavelength_nm, step, mode)
        self.source, seen = {}, {}
        for k, front in fronts.items():
            key = (scales[k], _wavefront_key(front.coefficients_um))
            opposite = seen.get((scales[k], _wavefront_key(front.coefficients_um, -1.0)))
            self.source[k] = opposite if scales[k] == 1 and key not in seen and opposite is not None else None
            seen[key] = k
        own = [k for k in fronts if self.source[k] is None]
        self.sizes = dict(zip(own, (map if pool is None else pool.map)(self._size, own)))
        for k in fronts:  # far to near: a layer's source comes first
            if self.source[k] is None:
                continue
            if self.sizes[self.source[k]] % 2 == 1:
                self.sizes[k] = self.sizes[self.source[k]]
            else:  # an even field has no centre pixel to reflect through
                self.source[k], self.sizes[k] = None, self._size(k)
        self.futures: dict = {}

    def _size(self, k: int) -> int:
        pupil_mm, wavelength_nm, step, _ = self.optics
        size = suggested_size_px(self.fronts[k], step, pupil_diameter_mm=pupil_mm, wavelength_nm=wavelength_nm)
        if self.scales[k] == 1:
            return size
        size //= self.scales[k]  # the fine grid's field (arcmin) on the coarse grid: windows as wide as the fine's
        return size + 1 - size % 2

    def _compute(self, k: int) -> PSF:
        pupil_mm, wavelength_nm, step, mode = self.optics
        items = tuple(self.fronts[k].coefficients_um.items())
        if self.scales[k] == 1:  # size_px=None as depth_layers passes it: one lru_cache entry
            return cached_psf(items, pupil_mm, wavelength_nm, step, mode, None)
        return cached_psf(items, pupil_mm, wavelength_nm, step * self.scales[k], mode, size_px=self.sizes[k])

    def prefetch(self, pool, k: int) -> None:
        """Start computing the PSF layer ``k`` needs in ``pool`` (once)."""
        while self.source[k] is not None:
            k = self.source[k]
        if k not in self.futures:
            self.futures[k] = pool.submit(self._compute, k)

    def psf(self, k: int) -> PSF:
        if self.source[k] is not None:
            return _reflected(self.psf(self.source[k]), self.fronts[k])
        return self.futures[k].result() if k in self.futures else self._compute(k)



def worker_threads(backend: ArrayBackend) -> int:
    """Threads that blur layers at once: the cores this process may use on the CPU (one inside another's threads,
    `spare_threads`); one on a GPU."""
    return spare_threads() if backend is CPU_BACKEND else 1


@contextlib.contextmanager
def layer_pool(threads: int):
    """A pool of ``threads`` threads, OpenBLAS on one thread meanwhile (ours use the cores); None for one thread."""
    if threads <= 1:
        yield None
        return
    with single_threaded_blas(), ThreadPoolExecutor(threads) as pool:
        try:
            yield pool
        finally:
            pool.shutdown(wait=True, cancel_futures=True)


def in_order(work, optics: LayerOptics, order, pool: ThreadPoolExecutor | None, threads: int, cost=None):
    """``(k, work(k))`` for each layer ``k`` of ``order``, in that order.

    With a ``pool`` (of ``threads``) the layers are worked on ahead on it: at most ``2 threads`` layers
    ahead of the caller, their PSFs twice as far ahead, so that a layer seldom waits for its own.  Each
    PSF is queued just before its layer, so that the first layers start at once.  A layer's
    extension and blur depend on no other layer, only its compositing (the caller's) does.  A
    layer's task waits only for PSF tasks submitted before it, which have therefore started: no
    deadlock.  Once every layer left is within the PSFs' reach (``4 threads + 1`` layers), those not
    yet queued are queued at once, each after its PSF, the largest by ``cost(k)`` first (when given):
    a large last layer (a scene's background, farthest) then does not run alone while the other
    threads wait.
    """
    order = list(order)
    if pool is None:
        for k in order:
            yield k, work(k)
        return
    reach = 4 * threads + 1
    futures: dict = {}
    all_queued = False
    for i, k in enumerate(order):
        if not all_queued:
            all_queued = cost is not None and i + reach >= len(order)
            ahead = sorted(order[i:], key=cost, reverse=True) if all_queued else order[i : i + reach]
            for j, later in enumerate(ahead):
                optics.prefetch(pool, later)
                if (all_queued or j <= 2 * threads) and later not in futures:
                    futures[later] = pool.submit(work, later)
        yield k, futures.pop(k).result()
