"""Rays through a gradient-index medium: the ray equation, integrated by RK4, to the exit surface.

The ray equation ``d/ds (n dr/ds) = grad n`` is written in Sharma's parameter t, ``dt = ds / n``
(A. Sharma, D. V. Kumar, A. K. Ghatak, Appl. Opt. 21, 984 (1982)), with the optical direction
vector ``T = n dr/ds`` (|T| = n):

    dr/dt = T,    dT/dt = n grad n = grad(n^2 / 2),    dL/dt = n^2     (L the optical path, mm)

and integrated by the classical fourth-order Runge-Kutta method with a fixed step h in t
(``GradientIndex.step_mm``; an arc length of about n h).  The straight line (grad n = 0) is
integrated exactly.  All rays advance together; a ray whose step would cross the exit surface
takes a last, shortened RK4 step from the start of that step, its length h' solved by Newton's
method on ``F(r(h')) = 0`` (F: `surface_excess_mm`, dF/dh' = grad F . T) to `INTERSECT_TOL_MM`,
so the ray ends exactly on the surface with the method's O(h^4) accuracy.

A ray that turns back, leaves the exit surface's clear aperture, or leaves its domain before
meeting it has left the lens: one `VissimInputError` names the medium and the surface.
"""

from __future__ import annotations

import numpy as np

from vissim.checks import counted
from vissim.errors import VissimInputError
from vissim.optics.raytrace.media import GradientIndex
from vissim.optics.raytrace.surface import INTERSECT_TOL_MM, MAX_NEWTON, Surface, surface_excess_mm

__all__ = ["propagate_grin", "rk4_step", "MAX_GRIN_STEPS"]

#: Steps a ray may take inside one GRIN medium before it is declared lost.
MAX_GRIN_STEPS = 200_000


def _derivatives(medium: GradientIndex, r: np.ndarray, t_vec: np.ndarray):
    n = medium.index(r)
    return t_vec, n[:, None] * medium.gradient_per_mm(r), n * n


def rk4_step(medium: GradientIndex, r, t_vec, opl, h):
    """One classical RK4 step of size ``h`` (a number or (N,)) in t for (r, T, L) (module doc)."""
    h = np.asarray(h, dtype=float)
    h_col = h[..., None] if h.ndim else h
    k1 = _derivatives(medium, r, t_vec)
    k2 = _derivatives(medium, r + 0.5 * h_col * k1[0], t_vec + 0.5 * h_col * k1[1])
    k3 = _derivatives(medium, r + 0.5 * h_col * k2[0], t_vec + 0.5 * h_col * k2[1])
    k4 = _derivatives(medium, r + h_col * k3[0], t_vec + h_col * k3[1])
    sixth = h_col / 6.0
    r_new = r + sixth * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
    t_new = t_vec + sixth * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1])
    opl_new = opl + (h / 6.0) * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2])
    return r_new, t_new, opl_new


def _left_lens(medium: GradientIndex, exit_surface: Surface, count: int, why: str) -> VissimInputError:
    return VissimInputError(f"rays in the {medium.name} {why} before reaching the {exit_surface.name} "
                            f"({counted(count, 'ray')}: they leave the lens)")


def _land(medium, exit_surface, r, t_vec, opl, h, excess_before, excess_after):
    """The shortened last step onto the exit surface, for rays whose full step ``h`` crosses it."""
    travel = exit_surface.travel_z
    h_try = h * excess_before / (excess_before - excess_after)  # the secant's first guess, in (0, h]
    for _ in range(MAX_NEWTON):
        r_new, t_new, opl_new = rk4_step(medium, r, t_vec, opl, h_try)
        f = surface_excess_mm(exit_surface, r_new)
        g = exit_surface.shape.sag_gradient(r_new[:, :2])
        df = travel * t_new[:, 2] - np.einsum("ij,ij->i", g, t_new[:, :2])
        step = f / df
        if not np.all(np.isfinite(step)):
            raise _left_lens(medium, exit_surface, int(np.sum(~np.isfinite(step))), "graze or miss the surface")
        h_try = h_try - step
        if np.max(np.abs(step) * np.linalg.norm(t_new, axis=1), initial=0.0) < INTERSECT_TOL_MM:
            return rk4_step(medium, r, t_vec, opl, h_try)
    raise _left_lens(medium, exit_surface, len(r), "did not settle onto the surface")  # pragma: no cover


def propagate_grin(medium: GradientIndex, exit_surface: Surface, points: np.ndarray, directions: np.ndarray):
    """Rays from ``points`` (on the entrance surface, unit ``directions`` inside the medium) to ``exit_surface``.

    Returns ``(points on the exit surface (N, 3), unit directions there (N, 3), optical path (N,) mm)``.
    """
    r = np.array(points, dtype=float)
    t_vec = medium.index(r)[:, None] * directions
    opl = np.zeros(len(r))
    excess = surface_excess_mm(exit_surface, r)
    if not np.all(excess < 0.0):
        raise _left_lens(medium, exit_surface, int(np.sum(~(excess < 0.0))), "start on or beyond the exit surface")
    active = np.ones(len(r), bool)
    h = float(medium.step_mm)
    for _ in range(MAX_GRIN_STEPS):
        if not active.any():
            return r, t_vec / np.linalg.norm(t_vec, axis=1, keepdims=True), opl
        idx = np.flatnonzero(active)
        moving = medium.rows(idx)
        r1, t1, l1 = rk4_step(moving, r[idx], t_vec[idx], opl[idx], h)
        e1 = surface_excess_mm(exit_surface, r1)
        _check_inside(moving, exit_surface, r1, t1, e1)
        crossed = e1 >= 0.0
        stay = idx[~crossed]
        r[stay], t_vec[stay], opl[stay], excess[stay] = r1[~crossed], t1[~crossed], l1[~crossed], e1[~crossed]
        if crossed.any():
            land = idx[crossed]
            r[land], t_vec[land], opl[land] = _land(medium.rows(land), exit_surface, r[land], t_vec[land], opl[land],
                                                    h, excess[land], e1[crossed])
            active[land] = False
    raise _left_lens(medium, exit_surface, int(active.sum()), f"took {MAX_GRIN_STEPS} steps")


def _check_inside(medium, exit_surface, r, t_vec, excess) -> None:
    """Rays that turn back, leave the exit surface's domain or pass outside its clear aperture have left."""
    turned = exit_surface.travel_z * t_vec[:, 2] <= 0.0
    if np.any(turned):
        raise _left_lens(medium, exit_surface, int(turned.sum()), "turn back")
    inside = ~(excess >= 0.0)  # a ray that crossed the surface in this step lands in _land, at its own radius
    lost = ~np.isfinite(excess) | (inside & (np.hypot(r[:, 0], r[:, 1]) > exit_surface.clear_radius_mm))
    if np.any(lost):
        raise _left_lens(medium, exit_surface, int(lost.sum()), "pass beyond the rim")
