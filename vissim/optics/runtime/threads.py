"""CPU threads: how many cores this process may use, and OpenBLAS's own threads held at one.

When vissim runs its own threads (`vissim.optics.depth.depth_map.blur_depth` blurs layers and computes
their PSFs on one thread per core), OpenBLAS's threads inside each small matrix product
(a wave PSF's, `vissim.optics.psf.wave`) only compete with them: measured on the
project's 2-core machine under load, 24 depth-layer PSFs took 3.6 s with OpenBLAS's default two
threads and 1.0 s with one.  `single_threaded_blas` sets OpenBLAS to one thread for a
block and back after; it finds OpenBLAS among the loaded libraries (Linux) and does nothing
where it cannot.  The setting is the process's, so it holds for every thread during the block.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import logging
import os
import threading
from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait

__all__ = ["available_cores", "map_on_threads", "map_shares", "single_threaded_blas", "spare_threads", "split_evenly"]

log = logging.getLogger(__name__)

#: (set, get) entry points of the OpenBLAS builds NumPy and SciPy ship, and of a plain OpenBLAS.
_OPENBLAS_SYMBOLS = (("scipy_openblas_set_num_threads64_", "scipy_openblas_get_num_threads64_"),
                     ("scipy_openblas_set_num_threads", "scipy_openblas_get_num_threads"),
                     ("openblas_set_num_threads", "openblas_get_num_threads"))
_LOCK = threading.Lock()
_DEPTH = [0, []]  # nesting depth, and the thread counts to restore


def available_cores() -> int:
    """The cores this process may use (its CPU affinity where the system tells it)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover  (not Linux)
        return os.cpu_count() or 1


def _openblas_controls() -> tuple:
    """(set, get) functions of each OpenBLAS loaded in this process now (SciPy's may load after NumPy's)."""
    try:
        with open("/proc/self/maps") as maps:
            paths = sorted({line.split()[-1] for line in maps if "openblas" in line.lower() and "/" in line})
    except OSError:  # pragma: no cover  (not Linux)
        return ()
    return tuple(control for path in paths for control in _controls_of(path))


@functools.cache
def _controls_of(path: str) -> tuple:
    try:
        library = ctypes.CDLL(path)
    except OSError:  # pragma: no cover
        return ()
    for set_name, get_name in _OPENBLAS_SYMBOLS:
        if hasattr(library, set_name) and hasattr(library, get_name):
            return ((getattr(library, set_name), getattr(library, get_name)),)
    return ()


def spare_threads() -> int:
    """Threads a computation may run at once: the available cores, or one inside a `single_threaded_blas` block
    (whose owner already runs its work on every core)."""
    with _LOCK:
        return 1 if _DEPTH[0] else available_cores()


@contextlib.contextmanager
def single_threaded_blas():
    """OpenBLAS on one thread inside the block (nested and concurrent blocks allowed), as before after it."""
    with _LOCK:
        if _DEPTH[0] == 0:
            controls = _openblas_controls()
            _DEPTH[1] = [(setter, getter()) for setter, getter in controls]
            for setter, _ in _DEPTH[1]:
                setter(1)
        _DEPTH[0] += 1
    try:
        yield
    finally:
        with _LOCK:
            _DEPTH[0] -= 1
            if _DEPTH[0] == 0:
                for setter, threads in _DEPTH[1]:
                    setter(threads)


def map_on_threads(work, shares) -> list:
    """``[work(share) for share in shares]``, the shares at once on `spare_threads` threads (OpenBLAS on one thread
    meanwhile), or one after another where there is one thread or one share. The first failure is raised as soon as
    the shares then running have finished; shares not yet started are dropped."""
    shares = list(shares)
    threads = min(spare_threads(), len(shares))
    if threads <= 1:
        return [work(share) for share in shares]
    with single_threaded_blas():
        pool = ThreadPoolExecutor(threads)
        try:
            futures = [pool.submit(work, share) for share in shares]
            done, _ = wait(futures, return_when=FIRST_EXCEPTION)
            failed = [future for future in futures if future in done and future.exception() is not None]
            if failed:
                raise failed[0].exception()
            return [future.result() for future in futures]
        finally:  # on a failure or Ctrl-C, what has not started is dropped; what runs finishes its share
            pool.shutdown(wait=True, cancel_futures=True)


def split_evenly(items, parts: int) -> list[list]:
    """``items`` in at most ``parts`` contiguous runs of near-equal length, in order (none empty)."""
    items = list(items)
    parts = max(1, min(parts, len(items)))
    bounds = [round(k * len(items) / parts) for k in range(parts + 1)]
    return [items[a:b] for a, b in zip(bounds, bounds[1:])]


def map_shares(work, items) -> list:
    """``work(share)`` for ``items`` split in one contiguous share per spare thread (`split_evenly`), at once
    (`map_on_threads`): one result per share, in order."""
    return map_on_threads(work, split_evenly(items, spare_threads()))
