"""A module imported on its first use, so that importing vissim stays light.

``ndimage = lazy_module("scipy.ndimage")`` at the top of a module costs nothing; the first attribute
read (``ndimage.affine_transform``) imports scipy.ndimage.  scipy's namespaces (fft, special,
ndimage, signal, stats, optimize, sparse, linalg) are reached only this way, and NumPy from the
modules the command line's help reads (`vissim.units`); a test imports every vissim module and fails
if one of scipy's loads.
"""

from __future__ import annotations

import importlib
from types import ModuleType

__all__ = ["lazy_module"]


class _LazyModule:
    """Stands for a module until an attribute is read, then forwards to it."""

    def __init__(self, name: str) -> None:
        self._name = name
        self._module: ModuleType | None = None

    def __getattr__(self, attribute: str):
        if attribute.startswith("__") or "_name" not in self.__dict__:  # copy and pickle probe before __init__
            raise AttributeError(attribute)
        module = self.__dict__.get("_module")
        if module is None:
            module = self.__dict__["_module"] = importlib.import_module(self.__dict__["_name"])
        value = getattr(module, attribute)
        self.__dict__[attribute] = value  # read once through here; after, as fast as the module's own attribute
        return value

    def __repr__(self) -> str:
        return f"<module {self._name!r}, imported on first use>"


def lazy_module(name: str):
    """The module `name`, imported when one of its attributes is first read."""
    return _LazyModule(name)
