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

__all__ = ["available_cores", "single_threaded_blas"]

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


@functools.cache
def _openblas_controls() -> tuple:
    """(set, get) functions of each OpenBLAS loaded in this process."""
    try:
        with open("/proc/self/maps") as maps:
            paths = sorted({line.split()[-1] for line in maps if "openblas" in line.lower() and "/" in line})
    except OSError:  # pragma: no cover  (not Linux)
        return ()
    controls = []
    for path in paths:
        try:
            library = ctypes.CDLL(path)
        except OSError:  # pragma: no cover
            continue
        for set_name, get_name in _OPENBLAS_SYMBOLS:
            if hasattr(library, set_name) and hasattr(library, get_name):
                controls.append((getattr(library, set_name), getattr(library, get_name)))
                break
    return tuple(controls)


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
