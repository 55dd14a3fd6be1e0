"""Where the blur's arrays live: NumPy on the CPU, or CuPy on a CUDA GPU (an optional extra).

CuPy, not PyTorch: vissim's blur is NumPy and ``scipy.fft`` code (``rfft2``/``irfft2`` with
``axes`` and ``s``, ``pad`` with ``edge``/``symmetric`` modes, ufuncs with ``out=``, fancy
indexing, ``bincount``), and CuPy implements those same calls under the same names
(``cupy`` for ``numpy``, ``cupyx.scipy.fft`` for ``scipy.fft``).  So one code path serves both
devices: every function takes its array module from its inputs (`array_module`), and
the CPU path, which the test suite runs, is the GPU path's code.  PyTorch would mean a second
implementation in its own vocabulary (``torch.fft``, ``torch.nn.functional.pad``) and a far
larger dependency for no function this code needs.

Install the extra with ``pip install -e ".[gpu]"`` (CuPy for CUDA 12) on a machine with an
NVIDIA driver.  ``device="cuda"`` then runs there; ``"auto"`` runs there when CuPy imports and
sees a device, else on the CPU; ``"cpu"`` (the default everywhere) never touches CuPy.
"""

from __future__ import annotations

import functools
import logging
from dataclasses import dataclass
from types import ModuleType

import numpy as np

from vissim.errors import VissimInputError
from vissim.lazy_import import lazy_module
from vissim.optics.runtime.devices import DEVICES

scipy_fft = lazy_module("scipy.fft")

__all__ = ["ArrayBackend", "DEVICES", "array_backend", "array_module", "cuda_available"]

log = logging.getLogger(__name__)



@dataclass(frozen=True)
class ArrayBackend:
    """An array module and its FFT module: ``xp`` is ``numpy`` or ``cupy``, ``fft`` ``scipy.fft`` or ``cupyx.scipy.fft``."""

    name: str
    xp: ModuleType
    fft: ModuleType

    def asarray(self, array, dtype=None):
        """``array`` on this backend's device (a copy to the GPU for CuPy)."""
        return self.xp.asarray(array, dtype=dtype)

    def to_numpy(self, array) -> np.ndarray:
        """``array`` back in host memory as a NumPy array."""
        return array.get() if hasattr(array, "get") and not isinstance(array, np.ndarray) else np.asarray(array)

    def fft_kwargs(self) -> dict:
        """Keyword arguments of this FFT module's transforms (``workers`` is scipy's only)."""
        return {"workers": -1} if self.name == "cpu" else {}


CPU = ArrayBackend("cpu", np, scipy_fft)


@functools.lru_cache(maxsize=1)
def _cupy():
    try:
        import cupy
        import cupyx.scipy.fft as cupy_fft
    except Exception as exc:  # ImportError, or a CuPy that cannot find its CUDA libraries
        return None, f"CuPy is not importable ({type(exc).__name__}: {exc})"
    try:
        count = cupy.cuda.runtime.getDeviceCount()
    except Exception as exc:
        return None, f"CuPy sees no CUDA device ({type(exc).__name__}: {exc})"
    if count < 1:
        return None, "CuPy sees no CUDA device"
    return ArrayBackend("cuda", cupy, cupy_fft), None


def cuda_available() -> bool:
    """True when CuPy imports and sees at least one CUDA device."""
    return _cupy()[0] is not None


def array_backend(device: str = "cpu") -> ArrayBackend:
    """The backend for ``device`` (``"cpu"``, ``"cuda"`` or ``"auto"``; module doc)."""
    if device not in DEVICES:
        raise VissimInputError(f"device must be one of {', '.join(DEVICES)}, got {device!r}")
    if device == "cpu":
        return CPU
    backend, reason = _cupy()
    if backend is not None:
        return backend
    if device == "cuda":
        raise VissimInputError(f"device 'cuda' asked for, but {reason}; install the gpu extra "
                               "(pip install -e '.[gpu]') on a machine with an NVIDIA GPU, or use device 'cpu'")
    log.info("device auto: %s; running on the CPU", reason)
    return CPU


def array_module(*arrays) -> ModuleType:
    """``cupy`` if any of ``arrays`` is a CuPy array, else ``numpy`` (without importing CuPy)."""
    for array in arrays:
        if type(array).__module__.startswith("cupy"):
            return _cupy()[0].xp
    return np
