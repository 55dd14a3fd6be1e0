"""Surface shapes for the exact trace: a sag ``z(x, y)`` and its analytic gradient, in mm.

One protocol (`SagShape`): ``sag_mm(xy_mm)`` and ``sag_gradient(xy_mm)`` at points (..., 2),
in the surface's own frame (vertex at the origin, the sag measured along the direction light
travels; `vissim.optics.raytrace.surface` places it).  A point outside a shape's domain (beyond
a sphere's hemisphere, an ellipsoid's rim) gives NaN, which the trace reports as a ray missing
that surface.  A positive curvature puts the centre of curvature on the side the light goes to.

* `MatrixSag`: ``x^T K x / (1 + sqrt(1 - x^T K^2 x))`` for a symmetric curvature matrix K
  (1/mm): the trial lenses' spheres, cylinders and sphero-cylinders (`vissim.bench.lenses.mesh`).
* `Conic`: ``c r^2 / (1 + sqrt(1 - (1 + Q) c^2 r^2))``, c = 1/R; Q = 0 a sphere, -1 a paraboloid.
* `Biconic` (Zemax's form): ``(cx x'^2 + cy y'^2) / (1 + sqrt(1 - (1+Qx) cx^2 x'^2 - (1+Qy) cy^2 y'^2))``
  in a frame turned by ``axis_deg`` (counter-clockwise from +x); equals `Conic` when the two agree.
* `Plane`: z = 0.

A shape may also offer ``ray_distance_mm(points, directions)`` (in its own frame), a closed-form
first guess for the intersection (`Conic` does): Newton then starts on the surface, not on the
vertex plane, which a ray far off axis can cross outside a steep surface's domain (a retina).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from vissim.errors import VissimInputError

__all__ = ["SagShape", "MatrixSag", "Conic", "Biconic", "Plane", "matrix_sag_mm", "matrix_sag_gradient"]


class SagShape(Protocol):
    def sag_mm(self, xy_mm: np.ndarray) -> np.ndarray: ...

    def sag_gradient(self, xy_mm: np.ndarray) -> np.ndarray: ...


def _quadratic_forms(curvature_per_mm, xy_mm) -> tuple[np.ndarray, ...]:  # xy, K x, K^2 x, x^T K x, x^T K^2 x
    curvature = np.asarray(curvature_per_mm, dtype=float)
    xy = np.asarray(xy_mm, dtype=float)
    kx = xy @ curvature.T  # K x, K symmetric
    kkx = kx @ curvature.T  # K^2 x
    q = np.einsum("...i,...i->...", xy, kx)
    p = np.einsum("...i,...i->...", xy, kkx)
    return xy, kx, kkx, q, p


def _root_or_nan(values: np.ndarray) -> np.ndarray:
    """sqrt where ``values >= 0``, NaN elsewhere (outside the shape's domain), without a warning."""
    with np.errstate(invalid="ignore"):
        return np.sqrt(values)


def matrix_sag_mm(curvature_per_mm, xy_mm) -> np.ndarray:
    """Sag ``x^T K x / (1 + sqrt(1 - x^T K^2 x))`` in mm at points ``xy_mm`` (..., 2); NaN beyond the hemisphere."""
    _, _, _, q, p = _quadratic_forms(curvature_per_mm, xy_mm)
    return q / (1.0 + _root_or_nan(1.0 - p))


def matrix_sag_gradient(curvature_per_mm, xy_mm) -> np.ndarray:
    """Analytic gradient (d sag/dx, d sag/dy), dimensionless, at points ``xy_mm`` (..., 2)."""
    _, kx, kkx, q, p = _quadratic_forms(curvature_per_mm, xy_mm)
    w = _root_or_nan(1.0 - p)
    one_w = 1.0 + w
    with np.errstate(divide="ignore", invalid="ignore"):
        return 2.0 * kx / one_w[..., None] + (q / (one_w**2 * w))[..., None] * kkx


@dataclass(frozen=True, eq=False)
class MatrixSag:
    """A surface of symmetric curvature matrix ``curvature_per_mm`` (2x2, 1/mm)."""

    curvature_per_mm: np.ndarray

    def sag_mm(self, xy_mm):
        return matrix_sag_mm(self.curvature_per_mm, xy_mm)

    def sag_gradient(self, xy_mm):
        return matrix_sag_gradient(self.curvature_per_mm, xy_mm)


def _curvature_per_mm(radius_mm, what: str) -> float:
    radius = float(radius_mm)
    if math.isnan(radius) or radius == 0.0:
        raise VissimInputError(f"{what} radius must be non-zero mm (inf for flat), got {radius_mm!r}")
    return 0.0 if math.isinf(radius) else 1.0 / radius


def _finite(value, what: str) -> float:
    number = float(value)
    if not math.isfinite(number):
        raise VissimInputError(f"{what} must be a finite number, got {value!r}")
    return number


@dataclass(frozen=True)
class Conic:
    """A conic of revolution: vertex radius ``radius_mm`` (inf: flat) and conic constant ``conic`` (Q)."""

    radius_mm: float
    conic: float = 0.0

    def __post_init__(self) -> None:
        _curvature_per_mm(self.radius_mm, "conic surface")
        _finite(self.conic, "conic constant Q")

    def sag_mm(self, xy_mm):
        c = _curvature_per_mm(self.radius_mm, "conic surface")
        r2 = np.sum(np.asarray(xy_mm, dtype=float) ** 2, axis=-1)
        return c * r2 / (1.0 + _root_or_nan(1.0 - (1.0 + self.conic) * c * c * r2))

    def ray_distance_mm(self, points_mm: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """Closed-form distance along rays (local frame: z the sag direction, d_z > 0) to the vertex branch.

        The conic is ``c r^2 - 2 z + (1 + Q) c z^2 = 0``; a ray ``p + s d`` meets it where
        ``A s^2 + B s + C = 0``, and the root that tends to the plane's ``-z/d_z`` as c -> 0 is
        ``2 C / (-B + sqrt(B^2 - 4 A C))``.  NaN where the ray misses the conic.
        """
        c = _curvature_per_mm(self.radius_mm, "conic surface")
        k = (1.0 + self.conic) * c
        (x, y, z), (dx, dy, dz) = points_mm.T, directions.T
        a = c * (dx * dx + dy * dy) + k * dz * dz
        b = 2.0 * (c * (x * dx + y * dy) - dz + k * z * dz)
        q = c * (x * x + y * y) - 2.0 * z + k * z * z
        with np.errstate(divide="ignore", invalid="ignore"):
            return 2.0 * q / (-b + np.sqrt(b * b - 4.0 * a * q))

    def sag_gradient(self, xy_mm):
        """``c (x, y) / sqrt(1 - (1 + Q) c^2 r^2)``: d sag/dr = c r / w."""
        c = _curvature_per_mm(self.radius_mm, "conic surface")
        xy = np.asarray(xy_mm, dtype=float)
        w = _root_or_nan(1.0 - (1.0 + self.conic) * c * c * np.sum(xy**2, axis=-1))
        with np.errstate(divide="ignore", invalid="ignore"):
            return (c / w)[..., None] * xy


@dataclass(frozen=True)
class Biconic:
    """Radii ``radius_x_mm``, ``radius_y_mm`` and conic constants along the axes x', y' turned by ``axis_deg``."""

    radius_x_mm: float
    radius_y_mm: float
    conic_x: float = 0.0
    conic_y: float = 0.0
    axis_deg: float = 0.0

    def __post_init__(self) -> None:
        _curvature_per_mm(self.radius_x_mm, "biconic x")
        _curvature_per_mm(self.radius_y_mm, "biconic y")
        for value, what in ((self.conic_x, "conic constant Qx"), (self.conic_y, "conic constant Qy"),
                            (self.axis_deg, "biconic axis (deg)")):
            _finite(value, what)

    def _local(self, xy_mm) -> tuple[np.ndarray, np.ndarray, float, float]:
        xy = np.asarray(xy_mm, dtype=float)
        cos_a, sin_a = math.cos(math.radians(self.axis_deg)), math.sin(math.radians(self.axis_deg))
        return xy[..., 0] * cos_a + xy[..., 1] * sin_a, -xy[..., 0] * sin_a + xy[..., 1] * cos_a, cos_a, sin_a

    def _terms(self, xy_mm):
        x, y, cos_a, sin_a = self._local(xy_mm)
        cx = _curvature_per_mm(self.radius_x_mm, "biconic x")
        cy = _curvature_per_mm(self.radius_y_mm, "biconic y")
        ax, ay = (1.0 + self.conic_x) * cx * cx, (1.0 + self.conic_y) * cy * cy
        w = _root_or_nan(1.0 - ax * x * x - ay * y * y)
        return x, y, cx, cy, ax, ay, w, cos_a, sin_a

    def sag_mm(self, xy_mm):
        x, y, cx, cy, _, _, w, _, _ = self._terms(xy_mm)
        return (cx * x * x + cy * y * y) / (1.0 + w)

    def sag_gradient(self, xy_mm):
        """d sag/dx' = 2 cx x'/(1+w) + N ax x'/(w (1+w)^2), N the numerator; turned back to (x, y)."""
        x, y, cx, cy, ax, ay, w, cos_a, sin_a = self._terms(xy_mm)
        one_w = 1.0 + w
        numerator = cx * x * x + cy * y * y
        with np.errstate(divide="ignore", invalid="ignore"):
            common = numerator / (w * one_w * one_w)
            gx = 2.0 * cx * x / one_w + common * ax * x
            gy = 2.0 * cy * y / one_w + common * ay * y
        return np.stack([gx * cos_a - gy * sin_a, gx * sin_a + gy * cos_a], axis=-1)


@dataclass(frozen=True)
class Plane:
    """A flat surface."""

    def sag_mm(self, xy_mm):
        return np.zeros(np.shape(xy_mm)[:-1])

    def sag_gradient(self, xy_mm):
        return np.zeros(np.shape(xy_mm))
