"""Aiming: the rays from one object point that land on given points of a stop plane.

Rays from one object point are aimed at a regular grid on a plane (an entrance pupil, a stop)
by Newton's method on the 2-D landing error.  Aimed, not traced as a fan and interpolated: a
PSF core wants the path length *at its own grid points*; interpolating scattered landings would
add an error of order h^2 W'' and leave the rim unevenly covered, while aiming costs a few
vectorised traces and puts every sample exactly where it belongs.
"""

from __future__ import annotations

import numpy as np

from vissim.errors import VissimInputError
from vissim.optics.raytrace.media import resolve_medium
from vissim.optics.raytrace.surface import MAX_NEWTON
from vissim.optics.raytrace.trace import RayBundle, trace_rays

__all__ = ["aim_rays", "aim_collimated", "launch_directions", "AIM_TOL_MM", "AIM_STEP_MM"]

#: Aiming tolerance on the landing point, and the finite-difference step of the Jacobian, mm.
AIM_TOL_MM = 1e-10
AIM_STEP_MM = 1e-6


def launch_directions(object_point: np.ndarray, aim_xy: np.ndarray, stop_z_mm: float) -> np.ndarray:
    """Unit directions from the object point towards the aim points on the stop plane."""
    d = np.concatenate([aim_xy, np.full((len(aim_xy), 1), stop_z_mm)], axis=1) - object_point
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _solve_2x2(jac: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """``jac[k]^-1 rhs[k]`` for each (2, 2) ``jac[k]``, by Cramer's rule (a batched LU costs ten times as much)."""
    (a, b), (c, d) = jac[:, 0].T, jac[:, 1].T
    det = a * d - b * c
    if np.any(det == 0.0):
        raise VissimInputError("ray aiming met a singular landing Jacobian (a ray whose landing point does not move "
                               "with its start): the rays graze a surface")
    return np.stack([d * rhs[:, 0] - b * rhs[:, 1], a * rhs[:, 1] - c * rhs[:, 0]], axis=1) / det[:, None]


def _solve_aim(trace, aim, targets, apertured):
    """Newton's method on the landing error ``trace(aim, mask).points - targets``; Jacobian by finite differences."""
    for _ in range(MAX_NEWTON):
        bundle = trace(aim, apertured)
        error = bundle.points_mm[:, :2] - targets
        if np.max(np.abs(error), initial=0.0) < AIM_TOL_MM:
            return bundle, error, aim
        jac = np.empty((len(targets), 2, 2))
        for axis in range(2):
            shifted = aim.copy()
            shifted[:, axis] += AIM_STEP_MM
            moved = trace(shifted, False)
            jac[:, :, axis] = (moved.points_mm[:, :2] - bundle.points_mm[:, :2]) / AIM_STEP_MM
        aim = aim - _solve_2x2(jac, error)
    raise VissimInputError(f"ray aiming did not converge (landing error {np.max(np.abs(error)):.3g} mm)")


def _on_targets(bundle: RayBundle, error: np.ndarray, targets: np.ndarray, extra_opl_mm=0.0) -> RayBundle:
    """The bundle moved onto its exact targets: dOPL = n d_xy . dx to first order."""
    opl = bundle.opl_mm - bundle.final_index * np.einsum("ij,ij->i", bundle.directions[:, :2], error)
    points = bundle.points_mm.copy()
    points[:, :2] = targets
    return RayBundle(points, bundle.directions, opl + extra_opl_mm, bundle.final_index)


def aim_rays(surfaces, object_point_mm, targets_xy_mm, stop_z_mm: float = 0.0, *, apertured=None,
             wavelength_nm: float | None = None) -> tuple[RayBundle, np.ndarray]:
    """Rays from one object point through ``surfaces`` that land on ``targets_xy_mm`` (N, 2) of the plane ``stop_z_mm``.

    Newton's method on the landing error, the launch direction parametrised by where the
    undeviated ray would cross the stop plane; Jacobian by finite differences.  Returns the
    bundle (its ``opl_mm`` corrected to first order to the exact targets, by the ray slope times
    the final index) and the launch directions.  Converges to `AIM_TOL_MM` in 3-5 steps for trial
    lenses.  ``apertured`` and ``wavelength_nm`` as in `trace_rays`.  A stop inside a system:
    aim through the surfaces before it, then trace on from the bundle (``index_before`` its
    ``final_index``) and add the path lengths.
    """
    origin = np.asarray(object_point_mm, dtype=float).reshape(3)
    targets = np.asarray(targets_xy_mm, dtype=float).reshape(-1, 2)
    travel = surfaces[0].travel_z if len(surfaces) else (1 if stop_z_mm > origin[2] else -1)
    if not travel * (stop_z_mm - origin[2]) > 0.0:
        raise VissimInputError(f"the object point must lie before the stop plane (z {'<' if travel > 0 else '>'} "
                               f"{stop_z_mm:g} mm)")
    starts = np.broadcast_to(origin, (len(targets), 3))

    def trace(aim, mask):
        return trace_rays(surfaces, starts, launch_directions(origin, aim, stop_z_mm), stop_z_mm, apertured=mask,
                          wavelength_nm=wavelength_nm)

    bundle, error, aim = _solve_aim(trace, targets.copy(), targets, apertured)
    return _on_targets(bundle, error, targets), launch_directions(origin, aim, stop_z_mm)


def aim_collimated(surfaces, direction, targets_xy_mm, stop_z_mm: float, start_z_mm: float, *, apertured=None,
                   wavelength_nm: float | None = None, index_before=1.0) -> tuple[RayBundle, np.ndarray]:
    """Rays of one collimated beam (an object at infinity) that land on ``targets_xy_mm`` of the plane ``stop_z_mm``.

    The rays start on the plane ``start_z_mm`` (before the first surface) along the unit
    ``direction``; Newton's method on their start points.  The path lengths are measured from
    the incoming plane wavefront through ``(0, 0, start_z_mm)``.  Returns the bundle and the
    start points (N, 3).
    """
    d = np.asarray(direction, dtype=float).reshape(3)
    d = d / np.linalg.norm(d)
    targets = np.asarray(targets_xy_mm, dtype=float).reshape(-1, 2)
    if not d[2] * (stop_z_mm - start_z_mm) > 0.0:
        raise VissimInputError(f"the beam must travel from the start plane z = {start_z_mm:g} mm to the stop plane "
                               f"z = {stop_z_mm:g} mm")
    directions = np.broadcast_to(d, (len(targets), 3))

    def starts(xy):
        return np.concatenate([xy, np.full((len(xy), 1), float(start_z_mm))], axis=1)

    def trace(xy, mask):
        return trace_rays(surfaces, starts(xy), directions, stop_z_mm, apertured=mask, wavelength_nm=wavelength_nm,
                          index_before=index_before)

    undeviated = targets - d[:2] / d[2] * (stop_z_mm - start_z_mm)
    bundle, error, xy = _solve_aim(trace, undeviated, targets, apertured)
    n0 = resolve_medium(index_before, wavelength_nm, "medium before the first surface")
    return _on_targets(bundle, error, targets, n0 * (xy @ d[:2])), starts(xy)
