"""Scratch arrays reused across calls, one set per thread.

Fresh memory costs a page fault per 4 KiB on first touch; on this project's 2-core virtual
machines a fault took about 2 µs, as long as the arithmetic on the page, and a 512^2 wave PSF
made ~2200 of them (4 of its 17 ms).  The wave PSF's hot paths therefore write their
intermediates into arrays that persist between calls.  An array from `scratch` is valid
until the next request for the same name in the same thread: never return one to a caller.
"""

from __future__ import annotations

import threading

import numpy as np

__all__ = ["scratch"]

#: Distinct (name, shape, dtype) arrays kept per thread before all are dropped.
MAX_ARRAYS = 64
#: Larger arrays are not kept (their faults cost little beside their arithmetic; memory is returned).
MAX_KEPT_BYTES = 64 * 2**20


class _Workspace(threading.local):
    def __init__(self):
        self.arrays: dict = {}


_WORKSPACE = _Workspace()


def scratch(name: str, shape: tuple, dtype) -> np.ndarray:
    """An uninitialised array of ``shape`` and ``dtype``, reused by later calls with the same name."""
    arrays = _WORKSPACE.arrays
    key = (name, tuple(shape), np.dtype(dtype).str)
    if np.prod(shape, dtype=float) * np.dtype(dtype).itemsize > MAX_KEPT_BYTES:
        return np.empty(shape, dtype)
    if key not in arrays:
        if len(arrays) >= MAX_ARRAYS:
            arrays.clear()
        arrays[key] = np.empty(shape, dtype)
    return arrays[key]
