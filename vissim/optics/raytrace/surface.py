"""A placed surface, the ray-surface intersection, the surface normal and vector Snell's law.

Frame: z is the optical axis and light crosses every surface towards ``travel_z`` (+1: +z, the
eye's frame, cornea first; -1: -z, the bench's world frame, chart first).  A surface is
``z = vertex_z_mm + travel_z * shape.sag_mm(x, y)``: its sag is measured the way light goes,
so a positive radius puts the centre of curvature beyond the surface in both frames.

* **Intersection** in a homogeneous medium: Newton's method on
  ``f(s) = p_z + s d_z - z_v - travel_z sag(p_xy + s d_xy)`` from the vertex plane (or the shape's
  closed-form distance, where it has one: `vissim.optics.raytrace.shapes`), to
  `INTERSECT_TOL_MM`.  A ray that leaves the shape's domain (NaN sag) or does not converge misses
  the surface: one `VissimInputError` names the surface.
* **Normal**: ``(grad sag, -travel_z)`` normalised, the exact normal, facing the incoming light.
* **Refraction**: vector Snell's law; total internal reflection raises, naming the surface.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vissim.checks import counted
from vissim.errors import VissimInputError
from vissim.optics.raytrace.media import Medium
from vissim.optics.raytrace.shapes import SagShape

__all__ = ["Surface", "INTERSECT_TOL_MM", "MAX_NEWTON", "intersect", "surface_excess_mm", "unit_normals",
           "refract", "check_aperture"]

#: Intersection tolerance (mm) and Newton's iteration cap.
INTERSECT_TOL_MM = 1e-12
MAX_NEWTON = 50


@dataclass(frozen=True, eq=False)
class Surface:
    """One refracting surface: ``shape`` with its vertex on the axis at ``vertex_z_mm``.

    ``medium_after``: the medium light enters (a number, a callable of wavelength in nm, or a
    `vissim.optics.raytrace.media.GradientIndex`); ``clear_radius_mm``: the half-aperture a
    ray must pass within (where the trace checks it); ``travel_z``: module doc.
    """

    shape: SagShape
    vertex_z_mm: float
    medium_after: Medium
    clear_radius_mm: float = math.inf
    name: str = "surface"
    travel_z: int = 1

    def __post_init__(self) -> None:
        if self.travel_z not in (1, -1):
            raise VissimInputError(f"travel_z of the {self.name} must be +1 or -1, got {self.travel_z!r}")


def surface_excess_mm(surface: Surface, points: np.ndarray) -> np.ndarray:
    """``travel_z (z - z_v) - sag(x, y)`` (mm): negative before the surface, positive beyond it."""
    return surface.travel_z * (points[:, 2] - surface.vertex_z_mm) - surface.shape.sag_mm(points[:, :2])


def _missed(surface: Surface, count: int) -> VissimInputError:
    return VissimInputError(f"{counted(count, 'ray')} {'misses' if count == 1 else 'miss'} the {surface.name} "
                            "(beyond its rim or its conic's domain, or grazing it)")


def intersect(surface: Surface, points: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Distance (mm) along each straight ray to ``surface`` (module doc)."""
    s = _first_guess(surface, points, directions)
    for _ in range(MAX_NEWTON):
        xy = points[:, :2] + s[:, None] * directions[:, :2]
        f = points[:, 2] + s * directions[:, 2] - surface.vertex_z_mm - surface.travel_z * surface.shape.sag_mm(xy)
        df = directions[:, 2] - surface.travel_z * np.einsum("ij,ij->i", surface.shape.sag_gradient(xy),
                                                               directions[:, :2])
        step = f / df
        lost = ~np.isfinite(step)
        if np.any(lost):
            raise _missed(surface, int(lost.sum()))
        s = s - step
        if np.max(np.abs(step), initial=0.0) < INTERSECT_TOL_MM:
            return s
    raise _missed(surface, int(np.sum(np.abs(step) >= INTERSECT_TOL_MM)))


def _first_guess(surface: Surface, points: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """The vertex plane's distance, or the shape's closed form where it has one (shapes module doc)."""
    plane = (surface.vertex_z_mm - points[:, 2]) / directions[:, 2]
    closed_form = getattr(surface.shape, "ray_distance_mm", None)
    if closed_form is None:
        return plane
    local = np.concatenate([points[:, :2], surface.travel_z * (points[:, 2:] - surface.vertex_z_mm)], axis=1)
    local_d = np.concatenate([directions[:, :2], surface.travel_z * directions[:, 2:]], axis=1)
    s = closed_form(local, local_d)
    return np.where(np.isfinite(s), s, plane)


def check_aperture(surface: Surface, points: np.ndarray, checked: np.ndarray) -> None:
    """Raise if a ray where ``checked`` (N,) is True lands outside the surface's clear aperture."""
    outside = checked & (np.hypot(points[:, 0], points[:, 1]) > surface.clear_radius_mm)
    if np.any(outside):
        raise VissimInputError(
            f"{int(outside.sum())} of the rays to the pupil pass outside the {2 * surface.clear_radius_mm:g} mm "
            f"clear aperture of the {surface.name}")


def unit_normals(surface: Surface, points: np.ndarray) -> np.ndarray:
    """Exact unit normals (N, 3) at points on ``surface``, facing the incoming light."""
    g = surface.shape.sag_gradient(points[:, :2])
    normal = np.concatenate([g, np.full((len(points), 1), -float(surface.travel_z))], axis=1)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    return normal


def refract(directions: np.ndarray, normals: np.ndarray, n1, n2, name: str) -> np.ndarray:
    """Vector Snell's law; ``normals`` unit, facing the incoming light (n . d < 0); n1, n2 numbers or (N,)."""
    mu = n1 / n2
    cos_i = -np.einsum("ij,ij->i", normals, directions)
    if np.any(cos_i <= 0.0):
        behind = int(np.sum(cos_i <= 0.0))
        raise VissimInputError(f"{counted(behind, 'ray')} {'meets' if behind == 1 else 'meet'} the {name} from behind")
    sin2_t = mu * mu * (1.0 - cos_i * cos_i)
    if np.any(sin2_t >= 1.0):
        raise VissimInputError(f"total internal reflection of {counted(int(np.sum(sin2_t >= 1.0)), 'ray')} at the {name}")
    cos_t = np.sqrt(1.0 - sin2_t)
    mu_rows = np.reshape(mu, (-1, 1)) if np.ndim(mu) else mu
    out = mu_rows * directions + np.reshape(mu * cos_i - cos_t, (-1, 1)) * normals
    return out / np.linalg.norm(out, axis=1, keepdims=True)
