"""Exact ray trace through the bench's trial lenses, for optical path length (pure numpy).

The surfaces are the analytic ones `vissim.bench.lenses.mesh` meshes, not the facets: in the
bench's world frame (`vissim.bench.dslr.bench`; mm, x the examiner's right, y up, +z from the
camera towards the chart, light travelling towards -z) a surface of curvature matrix K with
its vertex at ``z_v`` is ``z = z_v - sag(K, x)``.  Lens i's back vertex is at
``DslrBench.lens_back_vertex_z_mm()[i]``, its front vertex ``t`` further towards the chart.

* **Intersection**: Newton's method on ``f(s) = p_z + s d_z - z_v + sag(p_xy + s d_xy)`` from the
  vertex plane, to 1e-12 mm.
* **Refraction**: vector Snell's law with the exact normal ``(d sag/dx, d sag/dy, 1)``; the glass
  index comes from `vissim.optics.glass` at the traced wavelength (the bench's lenses keep
  the shape they were built with at n_d, as real glass does).  Air is n = 1, as in Mitsuba's
  ``vissim_refract``.
* **Aiming**: rays from one object point are aimed at a regular grid on the entrance-pupil
  plane z = 0 (the ``thinlens`` aperture) by Newton's method on the 2-D landing error.  Aimed,
  not traced as a fan and interpolated: the PSF core wants the path length *at its own grid
  points*; interpolating scattered landings would add an error of order h² W'' (a sizeable
  fraction of a nanometre-scale budget on steep lenses) and leave the rim unevenly covered,
  while aiming costs a few vectorised traces and puts every sample exactly where it belongs.

Path lengths are in mm (float64: ~1e-13 mm of round-off on a 914 mm path).  Nothing here
imports Mitsuba.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vissim.bench.lenses.mesh import lens_surface_curvatures_per_mm, sag_gradient, sag_mm
from vissim.errors import VissimInputError
from vissim.optics.glass import D_LINE_NM, glass_like_crown

__all__ = ["Surface", "RayBundle", "bench_surfaces", "trace_rays", "aim_rays", "object_point_mm"]

#: Intersection and aiming tolerances, mm.
INTERSECT_TOL_MM = 1e-12
AIM_TOL_MM = 1e-10
_MAX_NEWTON = 50
_AIM_STEP_MM = 1e-6


@dataclass(frozen=True, eq=False)
class Surface:
    """One refracting surface in world mm: ``z = vertex_z_mm - sag(curvature_per_mm, (x, y))``.

    ``index_after`` is the index of the medium the light enters (on the camera side);
    ``clear_radius_mm`` the half-aperture a ray must pass within.
    """

    curvature_per_mm: np.ndarray
    vertex_z_mm: float
    index_after: float
    clear_radius_mm: float
    name: str = "surface"


@dataclass(frozen=True, eq=False)
class RayBundle:
    """Rays on the plane ``z = stop_z_mm``: positions (N, 3) mm, unit directions (N, 3), path lengths (N,) mm."""

    points_mm: np.ndarray
    directions: np.ndarray
    opl_mm: np.ndarray


def bench_surfaces(bench, wavelength_nm: float = D_LINE_NM) -> tuple[Surface, ...]:
    """The surfaces of ``bench.physical_lenses`` in the order light meets them (chart to camera).

    Each lens is glass of its own n_d with crown's Abbe number (`glass_like_crown`),
    so at `D_LINE_NM` the index is exactly the rendered ``int_ior``.
    """
    radius = 0.5 * bench.clear_aperture()
    surfaces: list[Surface] = []
    for i, (lens, z_back) in enumerate(zip(bench.physical_lenses, bench.lens_back_vertex_z_mm())):
        front, back = lens_surface_curvatures_per_mm(lens)
        index = glass_like_crown(lens.refractive_index).index(wavelength_nm)
        surfaces.append(Surface(front, z_back + lens.center_thickness_mm, index, radius, f"lens {i} front"))
        surfaces.append(Surface(back, z_back, 1.0, radius, f"lens {i} back"))
    return tuple(surfaces)


def _intersect(surface: Surface, points: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Distance along each ray to ``surface`` (Newton on the sag, module doc)."""
    k = surface.curvature_per_mm
    s = (surface.vertex_z_mm - points[:, 2]) / directions[:, 2]
    for _ in range(_MAX_NEWTON):
        xy = points[:, :2] + s[:, None] * directions[:, :2]
        f = points[:, 2] + s * directions[:, 2] - surface.vertex_z_mm + sag_mm(k, xy)
        df = directions[:, 2] + np.einsum("ij,ij->i", sag_gradient(k, xy), directions[:, :2])
        step = f / df
        s = s - step
        if np.max(np.abs(step), initial=0.0) < INTERSECT_TOL_MM:
            return s
    raise VissimInputError(f"rays did not converge onto the {surface.name} (grazing incidence?)")  # pragma: no cover


def _refract(directions: np.ndarray, normals: np.ndarray, n1: float, n2: float, name: str) -> np.ndarray:
    """Vector Snell's law; ``normals`` unit, facing the incoming light (n . d < 0)."""
    mu = n1 / n2
    cos_i = -np.einsum("ij,ij->i", normals, directions)
    sin2_t = mu * mu * (1.0 - cos_i * cos_i)
    if np.any(sin2_t >= 1.0):
        raise VissimInputError(f"total internal reflection at the {name}")
    cos_t = np.sqrt(1.0 - sin2_t)
    out = mu * directions + (mu * cos_i - cos_t)[:, None] * normals
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def trace_rays(surfaces, points_mm, directions, stop_z_mm: float = 0.0, *, apertured=None) -> RayBundle:
    """Trace rays (N, 3) from ``points_mm`` along unit ``directions`` (d_z < 0) to the plane ``stop_z_mm``.

    Returns the landing points, the directions after the last surface and the optical path
    lengths from the start points (mm).  A ray outside a surface's clear aperture raises,
    except rays where the boolean mask ``apertured`` (N,) is False: they follow the analytic
    surfaces beyond the rim (the smooth continuation of a map outside the pupil).
    """
    p = np.array(points_mm, dtype=float).reshape(-1, 3)
    d = np.array(directions, dtype=float).reshape(-1, 3)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    if np.any(d[:, 2] >= 0.0):
        raise VissimInputError("rays must travel towards the camera (direction z < 0)")
    checked = np.broadcast_to(np.ones(1, bool) if apertured is None else np.asarray(apertured, bool), (len(p),))
    opl = np.zeros(len(p))
    index = 1.0
    for surface in surfaces:
        s = _intersect(surface, p, d)
        p = p + s[:, None] * d
        opl += index * s
        outside = checked & (np.hypot(p[:, 0], p[:, 1]) > surface.clear_radius_mm)
        if np.any(outside):
            raise VissimInputError(
                f"{int(outside.sum())} of the rays to the pupil pass outside the {2 * surface.clear_radius_mm:g} mm "
                f"clear aperture of the {surface.name}")
        g = sag_gradient(surface.curvature_per_mm, p[:, :2])
        normal = np.concatenate([g, np.ones((len(p), 1))], axis=1)
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)  # +z side: faces light going to -z
        d = _refract(d, normal, index, surface.index_after, surface.name)
        index = surface.index_after
    s = (stop_z_mm - p[:, 2]) / d[:, 2]
    return RayBundle(p + s[:, None] * d, d, opl + index * s)


def _launch(object_point: np.ndarray, aim_xy: np.ndarray, stop_z_mm: float) -> np.ndarray:
    """Unit directions from the object point towards the aim points on the stop plane."""
    d = np.concatenate([aim_xy, np.full((len(aim_xy), 1), stop_z_mm)], axis=1) - object_point
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def aim_rays(surfaces, object_point_mm, targets_xy_mm, stop_z_mm: float = 0.0, *,
             apertured=None) -> tuple[RayBundle, np.ndarray]:
    """Rays from one object point that land on ``targets_xy_mm`` (N, 2) of the plane ``stop_z_mm``.

    Newton's method on the landing error, the launch direction parametrised by where the
    undeviated ray would cross the stop plane; Jacobian by finite differences.  Returns the
    bundle (its ``opl_mm`` corrected to first order to the exact targets, by the ray slope) and
    the launch directions.  Converges to `AIM_TOL_MM` in 3-5 steps for trial lenses.
    ``apertured`` as in `trace_rays`.
    """
    origin = np.asarray(object_point_mm, dtype=float).reshape(3)
    targets = np.asarray(targets_xy_mm, dtype=float).reshape(-1, 2)
    if not origin[2] > stop_z_mm:
        raise VissimInputError(f"the object point must lie beyond the stop plane (z > {stop_z_mm:g} mm)")
    starts = np.broadcast_to(origin, (len(targets), 3))
    aim = targets.copy()
    for _ in range(_MAX_NEWTON):
        bundle = trace_rays(surfaces, starts, _launch(origin, aim, stop_z_mm), stop_z_mm, apertured=apertured)
        error = bundle.points_mm[:, :2] - targets
        if np.max(np.abs(error), initial=0.0) < AIM_TOL_MM:
            break
        jac = np.empty((len(targets), 2, 2))
        for axis in range(2):
            shifted = aim.copy()
            shifted[:, axis] += _AIM_STEP_MM
            moved = trace_rays(surfaces, starts, _launch(origin, shifted, stop_z_mm), stop_z_mm, apertured=False)
            jac[:, :, axis] = (moved.points_mm[:, :2] - bundle.points_mm[:, :2]) / _AIM_STEP_MM
        aim = aim - np.linalg.solve(jac, error[..., None])[..., 0]
    else:  # pragma: no cover - trial lenses converge in a few steps
        raise VissimInputError(f"ray aiming did not converge (landing error {np.max(np.abs(error)):.3g} mm)")
    # First-order move of each path length onto its exact target: dOPL = n d_xy . dx (n = 1 in air).
    opl = bundle.opl_mm - np.einsum("ij,ij->i", bundle.directions[:, :2], error)
    points = bundle.points_mm.copy()
    points[:, :2] = targets
    return RayBundle(points, bundle.directions, opl), _launch(origin, aim, stop_z_mm)


def object_point_mm(chart_distance_mm: float, field_deg=(0.0, 0.0)) -> np.ndarray:
    """The chart point seen at ``field_deg`` (x, y) from the pupil centre: ``(s tan x, s tan y, s)``.

    Field angles are in the world / TABO frame (x towards the examiner's right, i.e. the
    camera's left; y up); the camera's pixels are uniform in tan(angle) along each axis.
    """
    fx, fy = (float(v) for v in field_deg)
    if not all(math.isfinite(v) and abs(v) < 45.0 for v in (fx, fy)):
        raise VissimInputError(f"field angles must be finite degrees within +-45, got {field_deg!r}")
    s = float(chart_distance_mm)
    return np.array([s * math.tan(math.radians(fx)), s * math.tan(math.radians(fy)), s])
