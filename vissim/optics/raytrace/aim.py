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
from vissim.optics.raytrace.surface import MAX_NEWTON
from vissim.optics.raytrace.trace import RayBundle, trace_rays

__all__ = ["aim_rays", "launch_directions", "AIM_TOL_MM", "AIM_STEP_MM"]

#: Aiming tolerance on the landing point, and the finite-difference step of the Jacobian, mm.
AIM_TOL_MM = 1e-10
AIM_STEP_MM = 1e-6


def launch_directions(object_point: np.ndarray, aim_xy: np.ndarray, stop_z_mm: float) -> np.ndarray:
    """Unit directions from the object point towards the aim points on the stop plane."""
    d = np.concatenate([aim_xy, np.full((len(aim_xy), 1), stop_z_mm)], axis=1) - object_point
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def aim_rays(surfaces, object_point_mm, targets_xy_mm, stop_z_mm: float = 0.0, *, apertured=None,
             wavelength_nm: float | None = None) -> tuple[RayBundle, np.ndarray]:
    """Rays from one object point through ``surfaces`` that land on ``targets_xy_mm`` (N, 2) of the plane ``stop_z_mm``.

    Newton's method on the landing error, the launch direction parametrised by where the
    undeviated ray would cross the stop plane; Jacobian by finite differences.  Returns the
    bundle (its ``opl_mm`` corrected to first order to the exact targets, by the ray slope times
    the final index) and the launch directions.  Converges to `AIM_TOL_MM` in 3-5 steps for trial
    lenses.  ``apertured`` and ``wavelength_nm`` as in `trace_rays`.
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

    aim = targets.copy()
    for _ in range(MAX_NEWTON):
        bundle = trace(aim, apertured)
        error = bundle.points_mm[:, :2] - targets
        if np.max(np.abs(error), initial=0.0) < AIM_TOL_MM:
            break
        jac = np.empty((len(targets), 2, 2))
        for axis in range(2):
            shifted = aim.copy()
            shifted[:, axis] += AIM_STEP_MM
            moved = trace(shifted, False)
            jac[:, :, axis] = (moved.points_mm[:, :2] - bundle.points_mm[:, :2]) / AIM_STEP_MM
        aim = aim - np.linalg.solve(jac, error[..., None])[..., 0]
    else:
        raise VissimInputError(f"ray aiming did not converge (landing error {np.max(np.abs(error)):.3g} mm)")
    # First-order move of each path length onto its exact target: dOPL = n d_xy . dx.
    opl = bundle.opl_mm - bundle.final_index * np.einsum("ij,ij->i", bundle.directions[:, :2], error)
    points = bundle.points_mm.copy()
    points[:, :2] = targets
    return RayBundle(points, bundle.directions, opl, bundle.final_index), launch_directions(origin, aim, stop_z_mm)
