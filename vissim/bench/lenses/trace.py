"""The bench's trial lenses as surfaces for the exact trace (`vissim.optics.raytrace`).

The surfaces are the analytic ones `vissim.bench.lenses.mesh` meshes, not the facets: in the
bench's world frame (`vissim.bench.dslr.bench`; mm, x the examiner's right, y up, +z from the
camera towards the chart, light travelling towards -z, so ``travel_z = -1``) a surface of
curvature matrix K with its vertex at ``z_v`` is ``z = z_v - sag(K, x)``.  Lens i's back vertex
is at ``DslrBench.lens_back_vertex_z_mm()[i]``, its front vertex ``t`` further towards the chart.

The glass index comes from `vissim.optics.rx.glass` at the traced wavelength (the bench's lenses
keep the shape they were built with at n_d, as real glass does).  Air is n = 1, as in
Mitsuba's ``vissim_refract``.  Rays are aimed from a chart point onto the entrance-pupil plane
z = 0 (the ``thinlens`` aperture) by `vissim.optics.raytrace.aim_rays`.

Path lengths are in mm (float64: ~1e-13 mm of round-off on a 914 mm path).  Nothing here
imports Mitsuba.
"""

from __future__ import annotations

import math

import numpy as np

from vissim.optics.rx.trial_lens import lens_surface_curvatures_per_mm
from vissim.errors import VissimInputError
from vissim.optics.rx.glass import D_LINE_NM, glass_like_crown
from vissim.optics.raytrace import MatrixSag, Surface

__all__ = ["BENCH_TRAVEL_Z", "bench_surfaces", "object_point_mm"]

#: Light crosses the bench from the chart (far, +z) to the camera (z = 0).
BENCH_TRAVEL_Z = -1


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
        surfaces.append(Surface(MatrixSag(front), z_back + lens.center_thickness_mm, index, radius,
                                f"lens {i} front", BENCH_TRAVEL_Z))
        surfaces.append(Surface(MatrixSag(back), z_back, 1.0, radius, f"lens {i} back", BENCH_TRAVEL_Z))
    return tuple(surfaces)


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
