"""The schematic-eye sensor's tables, made once per eye: where each visual direction lands, and the pupil bounds.

* **Distortion**: the chief ray of a visual direction at angle θ from the optical axis, traced by the
  numpy exact tracer (`vissim.optics.eyes.retina_map.chief_ray_radii_mm`: a collimated ray aimed at
  the centre of the iris plane's axial point, then on to the retina), lands at the radius r(θ) on
  the retina (mm, measured in x, y).  Tabulated every `THETA_STEP_DEG` up to the widest angle the image needs; the sensor
  interpolates it linearly.  For a decentred iris (Liou–Brennan) the table still uses the ray
  through the axial point of the iris plane, so that it is radially symmetric: the image's
  centre is where the optical axis meets the retina.
* **Pupil bounds** (as pbrt-v4's RealisticCamera bounds its exit pupil): for retinal points at
  radii ``r_edges`` (and, for a decentred iris, at `AZIMUTHS_DECENTRED` azimuths) a grid of
  `COARSE_GRID` x `COARSE_GRID` points on the lens's back surface (its x, y within
  `GRID_RADIUS_MM`) is traced out by the Dr.Jit tracer (float64); the rays that get out bound, in
  the frame turned so the retinal point lies on +x, a box at each (radius, azimuth) node, widened
  by `BOX_MARGIN_CELLS` cells; a `GRID` x `GRID` grid over each radius's box bounds the nodes again,
  finer; a sector (radius bin by azimuth step) samples the union of its four corners' boxes.  The sensor
  samples only inside that box.  The tables are made at one wavelength; the pupil's image on the
  lens moves far less than the margin between 400 and 700 nm, and Ω changes by < 0.5 %
  (Navarro, 3 mm pupil: +0.48 % at 400 nm, -0.1 % at 700 nm, against 589.3 nm).
* **Normalisation**: a `GRID` x `GRID` grid over each edge's box is a quadrature of the projected
  solid angle of the rays that get out, ``Ω(r, ψ) = ∫ cos θ_r dω``, θ_r the angle from the
  retina's normal (sr; a 0.1-0.3 % quadrature error: the spread of Ω at r = 0 over azimuths);
  the sensor divides its weight by it (interpolated in r and in the azimuth ψ), so a uniform
  radiance fills the image with that radiance.  The retinal irradiance is then
  ``n_vitreous² Ω L`` (`retinal_irradiance_factor`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vissim.checks import EYE_RENDER_MAX_THETA_DEG
from vissim.errors import VissimInputError
from vissim.optics.eyes.models import SchematicEye
from vissim.optics.eyes.retina_map import chief_ray_radii_mm
from vissim.render.schematic_eye_trace import SchematicEyeTracer

__all__ = ["EyeTables", "eye_tables", "THETA_STEP_DEG", "GRID", "GRID_RADIUS_MM", "BOX_MARGIN_CELLS",
           "AZIMUTHS_DECENTRED", "RADIUS_BINS", "COARSE_GRID", "table_theta_deg"]

THETA_STEP_DEG = 0.25
GRID = 128
COARSE_GRID = 64
GRID_RADIUS_MM = 5.0
BOX_MARGIN_CELLS = 2
AZIMUTHS_DECENTRED = 8
RADIUS_BINS = 24


@dataclass(frozen=True, eq=False)
class EyeTables:
    """``theta_deg``/``radius_mm``: the distortion table; ``r_edges_mm`` (B + 1); ``boxes`` (B, Z, 4): each
    sector's (radius bin k, azimuths ``azimuths_rad[z]`` to the next) (a0, a1, b0, b1) on the lens back in
    the retinal point's frame (mm); ``omega_sr`` (B + 1, Z): Ω at each edge and azimuth (Z = 1 for a
    centred iris); ``pass_fraction`` (B + 1,): the fraction of the sampling box's area whose rays get
    out, at each edge (mean over azimuths); ``n_vitreous``."""

    theta_deg: np.ndarray
    radius_mm: np.ndarray
    r_edges_mm: np.ndarray
    boxes: np.ndarray
    omega_sr: np.ndarray
    azimuths_rad: np.ndarray
    pass_fraction: np.ndarray
    n_vitreous: float

    def retinal_irradiance_factor(self, radius_mm: float, azimuth_rad: float = 0.0) -> float:
        """Retinal irradiance per unit scene radiance at a retinal point: ``n_vitreous² Ω`` (sr)."""
        omega = [np.interp(radius_mm, self.r_edges_mm, self.omega_sr[:, j]) for j in range(len(self.azimuths_rad))]
        if len(omega) == 1:
            return float(self.n_vitreous ** 2 * omega[0])
        period = np.append(self.azimuths_rad, 2 * math.pi)
        return float(self.n_vitreous ** 2 * np.interp(azimuth_rad % (2 * math.pi), period, omega + omega[:1]))


def _double_array_type():
    """Dr.Jit's float64 array of a JIT backend that works here (LLVM, else CUDA): the tables trace ~10^5-10^6 rays."""
    import os

    from vissim.render.backend import find_libllvm

    path = os.environ.get("DRJIT_LIBLLVM_PATH") or find_libllvm()
    if path:
        os.environ.setdefault("DRJIT_LIBLLVM_PATH", path)  # before Dr.Jit's LLVM backend starts
        from drjit.llvm import Float64
        return Float64
    try:
        from drjit.cuda import Float64

        Float64([1.0])
        return Float64
    except Exception:  # no CUDA device either
        raise VissimInputError("the schematic-eye sensor needs Dr.Jit's LLVM or CUDA backend to trace its tables "
                               "(install LLVM >= 16, e.g. Debian's libllvm19)") from None


def _grid_rays(tracer: SchematicEyeTracer, r_edges, azimuths, boxes, grid: int, wavelength_nm: float):
    """Trace a ``grid`` x ``grid`` grid over each edge's box (E, 4) on the lens back from every (edge,
    azimuth) retinal point; returns (valid, the quadrature weights of Ω) as (E, Z, grid, grid), and
    each edge's cell centres (E, grid) in a and b and cell area (E,)."""
    Float64 = _double_array_type()
    boxes = np.asarray(boxes, dtype=float)
    u = (np.arange(grid) + 0.5) / grid
    a_axis = boxes[:, :1] + (boxes[:, 1:2] - boxes[:, :1]) * u
    b_axis = boxes[:, 2:3] + (boxes[:, 3:4] - boxes[:, 2:3]) * u
    cell = (boxes[:, 1] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 2]) / grid ** 2
    shape = (len(r_edges), len(azimuths), grid, grid)
    a = np.broadcast_to(a_axis[:, None, :, None], shape).ravel()
    b = np.broadcast_to(b_axis[:, None, None, :], shape).ravel()
    psi = np.broadcast_to(azimuths[None, :, None, None], shape).ravel()
    r = np.broadcast_to(r_edges[:, None, None, None], shape).ravel()
    cos_p, sin_p = np.cos(psi), np.sin(psi)
    lens_back = len(tracer.shapes) - 2
    p = tracer.retina_point(Float64(r * cos_p), Float64(r * sin_p))
    q = tracer.surface_point(lens_back, Float64(a * cos_p - b * sin_p), Float64(a * sin_p + b * cos_p))
    d = tuple(qi - pi for qi, pi in zip(q, p))
    result = tracer.trace_out(p, d, wavelength_nm)
    valid = np.array(result.valid, bool).reshape(shape)
    weight = np.nan_to_num(np.array(tracer.projected_solid_angle_weight(p, d), float)).reshape(shape)
    return valid, np.where(valid, weight, 0.0) * cell[:, None, None, None], a_axis, b_axis, cell


def _box_around(passing, a_axis, b_axis):
    """The box (a0, a1, b0, b1) around the passing cells of one (G, G) grid (cell centres ``a_axis``,
    ``b_axis``), widened by `BOX_MARGIN_CELLS` and a half cell; None if none pass."""
    rows, cols = np.flatnonzero(passing.any(axis=1)), np.flatnonzero(passing.any(axis=0))
    if len(rows) == 0:
        return None
    ma, mb = ((BOX_MARGIN_CELLS + 0.5) * (axis[1] - axis[0]) for axis in (a_axis, b_axis))
    return a_axis[rows[0]] - ma, a_axis[rows[-1]] + ma, b_axis[cols[0]] - mb, b_axis[cols[-1]] + mb


def _union(boxes):
    kept = [bx for bx in boxes if bx is not None]
    if not kept:
        return (0.0, 0.0, 0.0, 0.0)
    return (min(bx[0] for bx in kept), max(bx[1] for bx in kept), min(bx[2] for bx in kept),
            max(bx[3] for bx in kept))


def _sector_boxes(node_boxes, bins: int, count: int) -> np.ndarray:
    """(B, Z, 4): the union of the boxes at the four corners (two radius edges, two azimuths) of each sector."""
    boxes = np.zeros((bins, count, 4))
    for k in range(bins):
        for z in range(count):
            corners = [node_boxes[e][(z + dz) % count] for e in (k, k + 1) for dz in (0, 1)]
            boxes[k, z] = _union(corners)
    return boxes


def table_theta_deg(max_theta_deg: float) -> np.ndarray:
    """The tables' field angles from the axis, deg: every `THETA_STEP_DEG` past ``max_theta_deg``."""
    return np.arange(0.0, max_theta_deg + 2 * THETA_STEP_DEG, THETA_STEP_DEG)


def eye_tables(eye: SchematicEye, iris_mm: float, wavelength_nm: float, max_theta_deg: float) -> EyeTables:
    """The tables of the module doc for ``eye`` with an iris ``iris_mm`` across, at ``wavelength_nm``,
    covering visual angles up to ``max_theta_deg``."""
    if not 0.0 <= max_theta_deg <= EYE_RENDER_MAX_THETA_DEG:
        raise VissimInputError(f"the image reaches {max_theta_deg:.3g} deg from the eye's optical axis; the schematic-eye "
                               f"sensor renders up to {EYE_RENDER_MAX_THETA_DEG:g} deg")
    theta = table_theta_deg(max_theta_deg)
    radius = chief_ray_radii_mm(eye, theta, wavelength_nm)
    tracer = SchematicEyeTracer(eye, iris_mm)
    r_edges = np.linspace(0.0, 1.02 * radius[-1], RADIUS_BINS + 1)
    count = AZIMUTHS_DECENTRED if eye.stop_decentre_nasal_mm else 1
    azimuths = 2.0 * math.pi * np.arange(count) / count
    edges = len(r_edges)
    full = np.tile([-GRID_RADIUS_MM, GRID_RADIUS_MM, -GRID_RADIUS_MM, GRID_RADIUS_MM], (edges, 1))
    valid, _, a_axis, b_axis, _ = _grid_rays(tracer, r_edges, azimuths, full, COARSE_GRID, wavelength_nm)
    coarse = [[_box_around(valid[e, z], a_axis[e], b_axis[e]) for z in range(count)] for e in range(edges)]
    if all(bx is None for bx in coarse[0]):
        raise VissimInputError(f"no ray from the fovea passes the {iris_mm:g} mm iris of the {eye.name} eye")
    fine_boxes = np.array([_union(row) if any(bx is not None for bx in row) else (0.0, 1e-3, 0.0, 1e-3)
                           for row in coarse])
    valid, w, a_axis, b_axis, cell = _grid_rays(tracer, r_edges, azimuths, fine_boxes, GRID, wavelength_nm)
    omega = w.sum(axis=(2, 3))
    # the fine grid, inside the coarse boxes' margins, bounds each node again, more tightly
    node_boxes = [[_box_around(valid[e, z], a_axis[e], b_axis[e]) for z in range(count)] for e in range(edges)]
    boxes = _sector_boxes(node_boxes, RADIUS_BINS, count)
    areas = (boxes[..., 1] - boxes[..., 0]) * (boxes[..., 3] - boxes[..., 2])  # (B, Z)
    passing_area = valid.sum(axis=(2, 3)) * cell[:, None]  # (E, Z)
    sector_area = areas[np.minimum(np.arange(edges), RADIUS_BINS - 1)]
    with np.errstate(divide="ignore", invalid="ignore"):
        passed = np.nan_to_num(passing_area / sector_area).mean(axis=1)
    n_vitreous = eye.surfaces[-2].medium_after.index(wavelength_nm)
    return EyeTables(theta, radius, r_edges, boxes, omega, azimuths, passed, n_vitreous)
