"""Where arrays may live, by name: the devices `vissim.optics.runtime.array_backend` takes (readable without NumPy:
the command line's help lists them)."""

from __future__ import annotations

__all__ = ["DEVICES"]

DEVICES = ("cpu", "cuda", "auto")
