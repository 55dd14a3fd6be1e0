"""How a blur continues an image beyond its edges: the modes `vissim.optics.blur.convolve` takes (readable
without NumPy: the command line's help lists them)."""

from __future__ import annotations

__all__ = ["PADDING_MODES"]

PADDING_MODES = ("constant", "edge", "reflect", "wrap")
