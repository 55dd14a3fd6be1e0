"""Optical media for the exact trace: homogeneous (a number, or a function of wavelength) or GRIN.

A medium is given as

* a number: the index at every wavelength (the trial lenses' glass, already evaluated);
* a callable ``index(wavelength_nm) -> float``: a dispersive homogeneous medium;
* a `GradientIndex`: the polynomial index of Liou & Brennan (1997, JOSA A 14:1684)
  ``n(x, y, z) = a0 + a1 (z - z0) + a2 (z - z0)^2 + b (x^2 + y^2)`` in the trace's frame (mm),
  its ``a0`` a number or a callable of wavelength (their dispersion shifts every medium's index
  by one function of wavelength).

`resolve_medium` turns any of them into a number or a `GradientIndex` with a numeric ``a0`` at
one wavelength, once per trace; or, for a trace of many wavelengths at once (one per ray), into an
array of indices, one per ray, or a `GradientIndex` whose ``a0`` is that array (`GradientIndex.rows`
keeps it aligned with a subset of the rays).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Callable, Union

import numpy as np

from vissim.errors import VissimInputError

__all__ = ["GradientIndex", "Medium", "resolve_medium", "DEFAULT_GRIN_STEP_MM"]

#: The GRIN integrator's default step in Sharma's parameter t (dt = ds / n), mm: an OPL error
#: below 1e-9 mm through a human lens (tests/test_raytrace.py, the step-halving table).
DEFAULT_GRIN_STEP_MM = 0.05


@dataclass(frozen=True)
class GradientIndex:
    """``n = a0 + a1_per_mm (z - origin_z_mm) + a2_per_mm2 (z - origin_z_mm)^2 + b_per_mm2 (x^2 + y^2)``.

    ``step_mm``: the RK4 step in Sharma's parameter t (`vissim.optics.raytrace.grin`).
    """

    a0: Union[float, Callable[[float], float]]
    a1_per_mm: float = 0.0
    a2_per_mm2: float = 0.0
    b_per_mm2: float = 0.0
    origin_z_mm: float = 0.0
    step_mm: float = DEFAULT_GRIN_STEP_MM
    name: str = "gradient-index medium"

    def __post_init__(self) -> None:
        for value, what in ((self.a1_per_mm, "a1 (1/mm)"), (self.a2_per_mm2, "a2 (1/mm^2)"),
                            (self.b_per_mm2, "b (1/mm^2)"), (self.origin_z_mm, "origin z (mm)")):
            if not math.isfinite(float(value)):
                raise VissimInputError(f"GRIN coefficient {what} must be finite, got {value!r}")
        if not (math.isfinite(float(self.step_mm)) and self.step_mm > 0.0):
            raise VissimInputError(f"GRIN step must be a positive number of mm, got {self.step_mm!r}")

    def rows(self, which) -> GradientIndex:
        """The medium for the rays ``which`` (indices or a mask) when ``a0`` holds one value per ray."""
        return self if np.ndim(self.a0) == 0 else replace(self, a0=self.a0[which])

    def index(self, points_mm: np.ndarray) -> np.ndarray:
        """n at points (N, 3) mm (``a0`` numeric, or one per point: a resolved medium)."""
        u = points_mm[:, 2] - self.origin_z_mm
        r2 = points_mm[:, 0] ** 2 + points_mm[:, 1] ** 2
        return self.a0 + u * (self.a1_per_mm + self.a2_per_mm2 * u) + self.b_per_mm2 * r2

    def gradient_per_mm(self, points_mm: np.ndarray) -> np.ndarray:
        """grad n (N, 3), 1/mm."""
        u = points_mm[:, 2] - self.origin_z_mm
        return np.stack([2.0 * self.b_per_mm2 * points_mm[:, 0], 2.0 * self.b_per_mm2 * points_mm[:, 1],
                         self.a1_per_mm + 2.0 * self.a2_per_mm2 * u], axis=1)


Medium = Union[float, Callable[[float], float], GradientIndex]


def _index_number(value, wavelength_nm, what: str):
    if callable(value):
        if wavelength_nm is None:
            raise VissimInputError(f"the {what} is dispersive: trace it at a wavelength (wavelength_nm)")
        if np.ndim(wavelength_nm):  # one wavelength per ray: the medium evaluated once per distinct wavelength
            distinct, where = np.unique(np.asarray(wavelength_nm, dtype=float), return_inverse=True)
            return _index_array(np.array([_index_number(value, w, what) for w in distinct])[where], what)
        value = value(float(wavelength_nm))
    if np.ndim(value):
        return _index_array(value, what)
    index = float(value)
    if not (math.isfinite(index) and index > 0.0):
        raise VissimInputError(f"the {what}'s refractive index must be a positive number, got {value!r}")
    return index


def _index_array(values, what: str) -> np.ndarray:
    index = np.asarray(values, dtype=float)
    if not np.all(np.isfinite(index) & (index > 0.0)):
        raise VissimInputError(f"the {what}'s refractive index must be a positive number at every wavelength")
    return index


def resolve_medium(medium: Medium, wavelength_nm, what: str = "medium"):
    """A number (homogeneous) or a `GradientIndex` with numeric ``a0``, at ``wavelength_nm``; for an array of
    wavelengths (one per ray), an array of indices or a `GradientIndex` with one ``a0`` per ray."""
    if isinstance(medium, GradientIndex):
        return replace(medium, a0=_index_number(medium.a0, wavelength_nm, medium.name))
    return _index_number(medium, wavelength_nm, what)
