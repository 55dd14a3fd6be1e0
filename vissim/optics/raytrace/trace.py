"""The exact real-ray trace: rays through a sequence of surfaces, with their optical path lengths.

Surfaces, intersection, normals and Snell's law: `vissim.optics.raytrace.surface`; media:
`vissim.optics.raytrace.media`; gradient-index media: `vissim.optics.raytrace.grin`.  Between
two surfaces a ray runs straight in a homogeneous medium (path n s) and along the integrated
ray equation in a GRIN one.  Path lengths are in mm (float64).  Pure numpy, vectorised over rays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vissim.errors import VissimInputError
from vissim.optics.raytrace.grin import propagate_grin
from vissim.optics.raytrace.media import GradientIndex, Medium, resolve_medium
from vissim.optics.raytrace.phase import PhasePlane, through_phase_plane
from vissim.optics.raytrace.surface import check_aperture, intersect, refract, unit_normals

__all__ = ["RayBundle", "trace_rays", "travel_sign"]


@dataclass(frozen=True, eq=False)
class RayBundle:
    """Traced rays: positions (N, 3) mm, unit directions (N, 3), optical path lengths (N,) mm from
    the start points, and ``final_index``, the (homogeneous) index of the medium they end in: a number, or one
    per ray for a trace of many wavelengths (`trace_rays`)."""

    points_mm: np.ndarray
    directions: np.ndarray
    opl_mm: np.ndarray
    final_index: float | np.ndarray = 1.0

    def rows(self, which) -> RayBundle:
        """The rays ``which`` (a slice, indices or a mask); a per-ray index follows them, one shared index is
        returned as a number."""
        index = self.final_index
        if np.ndim(index):
            index = index[which]
            index = float(index[0]) if np.all(index == index[0]) else index
        return RayBundle(self.points_mm[which], self.directions[which], self.opl_mm[which], index)


def travel_sign(surfaces, directions: np.ndarray) -> int:
    """+1 or -1: the sign of z along which every ray travels; every surface must agree."""
    d_z = directions[:, 2]
    if len(d_z) and np.all(d_z > 0.0):
        travel = 1
    elif len(d_z) and np.all(d_z < 0.0):
        travel = -1
    else:
        raise VissimInputError("rays must all travel one way along the axis (direction z all > 0 or all < 0)")
    wrong = [s.name for s in surfaces if s.travel_z != travel]
    if wrong:
        raise VissimInputError(f"rays travel towards {'+' if travel > 0 else '-'}z but the {wrong[0]} faces the "
                               "other way")
    return travel


def trace_rays(surfaces, points_mm, directions, stop_z_mm: float | None = 0.0, *, apertured=None,
               wavelength_nm: float | None = None, index_before: Medium = 1.0) -> RayBundle:
    """Trace rays (N, 3) from ``points_mm`` along ``directions`` through ``surfaces`` to the plane ``stop_z_mm``.

    ``stop_z_mm=None``: the rays end on the last surface (after refracting into its medium).
    Returns the landing points, the directions after the last surface and the optical path
    lengths from the start points (mm).  A ray outside a surface's clear aperture raises,
    except rays where the boolean mask ``apertured`` (N,) is False: they follow the analytic
    surfaces beyond the rim (the smooth continuation of a map outside the pupil).  Media that
    are callables are evaluated at ``wavelength_nm``: one number, or one per ray (N,), which traces many
    wavelengths in one pass, the rays' paths differing only through the media's indices; ``index_before``
    is the medium the rays start in (homogeneous; a number or one per ray).
    """
    p = np.array(points_mm, dtype=float).reshape(-1, 3)
    d = np.array(directions, dtype=float).reshape(-1, 3)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    travel_sign(surfaces, d)
    checked = np.broadcast_to(np.ones(1, bool) if apertured is None else np.asarray(apertured, bool), (len(p),))
    opl = np.zeros(len(p))
    medium = resolve_medium(index_before, wavelength_nm, "medium before the first surface")
    if isinstance(medium, GradientIndex):
        raise VissimInputError("rays must start in a homogeneous medium")
    for surface in surfaces:
        if isinstance(surface, PhasePlane):
            if isinstance(medium, GradientIndex):
                raise VissimInputError(f"the {surface.name} must lie in a homogeneous medium")
            p, d, path = through_phase_plane(surface, p, d, medium)
            opl += path
            continue
        if isinstance(medium, GradientIndex):
            p, d, path = propagate_grin(medium, surface, p, d)
            opl += path
            n_before = medium.index(p)
        else:
            s = intersect(surface, p, d)
            p = p + s[:, None] * d
            opl += medium * s
            n_before = medium
        check_aperture(surface, p, checked)
        medium = resolve_medium(surface.medium_after, wavelength_nm, f"medium after the {surface.name}")
        n_after = medium.index(p) if isinstance(medium, GradientIndex) else medium
        d = refract(d, unit_normals(surface, p), n_before, n_after, surface.name)
    if stop_z_mm is None:
        if isinstance(medium, GradientIndex):
            raise VissimInputError("the trace cannot end inside a gradient-index medium")
        return RayBundle(p, d, opl, medium)
    if isinstance(medium, GradientIndex):
        raise VissimInputError("the stop plane cannot lie inside a gradient-index medium")
    s = (stop_z_mm - p[:, 2]) / d[:, 2]
    return RayBundle(p + s[:, None] * d, d, opl + medium * s, medium)
