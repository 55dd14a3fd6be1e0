"""Where rays land on a schematic eye's retina: the chief rays' radius r(θ), and a chart point's ray PSF.

**The film's map** (`chief_ray_radii_mm`), read by the schematic-eye sensor
(`vissim.render.schematic_eye_tables`) and by the ray PSF below: the chief ray of a direction at angle θ
from the optical axis, a collimated ray aimed at the iris plane's axial point and traced on to the retina
by the numpy exact tracer (`vissim.optics.raytrace`), lands at the radius r(θ) (mm, measured in x, y).
For a decentred iris (Liou–Brennan) the ray still passes the axial point of the iris plane, so that the
map is radially symmetric: the image's centre is where the optical axis meets the retina.

**The ray PSF** (`ray_psf`), the eye bench's geometric self-check: the numpy trace's own PSF of the
rendered scene.  The eye is the rendered one, the same `Eye` object the sensor is handed: the model at its
accommodation, its surfaces as altered, made to need its prescription at its spectacle plane.  Rays leave
the chart's centre (at the chart distance from the corneal vertex, along the line of sight), pass the
trial lens (thick, as rendered) and the eye's surfaces (aimed at a jittered grid filling the iris) and land
on the retina.  Each landing point is turned into a field angle as the eye sensor reads its retina: its
distance from the axis through the inverse of r(θ) (of that eye, no lens, at the model's reference
wavelength, as the sensor's film), the direction opposite its azimuth, the field angle of that direction by
the models' rule (`field_direction`).  The offsets from the field angle at which the film sees the chart
centre (from the entrance pupil, `vissim.optics.eyes.sight.film_field_deg`, as the simulations draw the
chart) are histogrammed on a grid ``oversample`` times finer than the image's pixels.  The trial lens's
spectacle magnification is measured by the same trace (chief rays from chart points off the centre, with
the lens over without it).  Photopic light: every wavelength of the photopic spectrum in one trace, weighted by
V(λ) (the render's film develops luminance).

The renderer traces the other way (retina to scene, Dr.Jit, the lens as a mesh): this trace shares none of
its ray code; only the film's map r(θ), the same numpy table both read.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vissim.optics.eyes.defaults import DEFAULT_EYE_ARCMIN_PER_PX, DEFAULT_EYE_LIGHT_NM, DEFAULT_SPECTACLE_VERTEX_MM
from vissim.optics.eyes.models import SchematicEye
from vissim.optics.eyes.sight import film_field_deg
from vissim.optics.eyes.surfaces import split_at_stop
from vissim.optics.eyes.traced_wavefront import (field_direction, field_of_direction, iris_from_entrance_pupil_mm,
                                                 trace_to_retina)
from vissim.optics.pupil.rays import histogram_on_edges
from vissim.optics.raytrace import aim_collimated, trace_rays
from vissim.optics.rx.trial_lens import TrialLensSetup
from vissim.units import osa_xy_to_image_colrow

__all__ = ["chief_ray_radii_mm", "START_BEFORE_MM", "RayPsf", "ray_psf", "RAYS_ACROSS_IRIS", "MAGNIFICATION_STEP_DEG",
           "RADIUS_STEP_DEG", "RADIUS_SPAN_DEG"]

#: The chief rays start this far in front of the cornea's vertex, mm.
START_BEFORE_MM = 5.0


def chief_ray_radii_mm(eye: SchematicEye, theta_deg: np.ndarray, wavelength_nm: float) -> np.ndarray:
    """r(θ): where a collimated ray at θ from the axis through the iris plane's axial point meets the retina."""
    front, stop_z, back = split_at_stop(eye)
    radii = []
    for theta in theta_deg:
        t = math.radians(float(theta))
        direction = [math.sin(t), 0.0, math.cos(t)]
        at_iris, _ = aim_collimated(front, direction, [[0.0, 0.0]], stop_z, front[0].vertex_z_mm - START_BEFORE_MM,
                                    wavelength_nm=wavelength_nm)
        on_retina = trace_rays(back, at_iris.points_mm, at_iris.directions, None, wavelength_nm=wavelength_nm,
                               index_before=at_iris.final_index)
        radii.append(float(np.hypot(*on_retina.points_mm[0, :2])))
    return np.array(radii)

#: Rays across the iris's diameter (a jittered square grid; ~0.785 x its square inside).
RAYS_ACROSS_IRIS = 161
#: Offset (deg) of the chart points whose chief rays measure the spectacle magnification.
MAGNIFICATION_STEP_DEG = 0.5
#: The chief-ray radius table r(θ) that maps the retina to field angles: its step and reach about the image, deg.
RADIUS_STEP_DEG, RADIUS_SPAN_DEG = 0.05, 2.0


@dataclass(frozen=True)
class RayPsf:
    """The ray PSF on a grid of ``step_arcmin`` (rows down, columns to the observer's right), its centre
    the image centre; ``magnification``: the lens's 2 x 2 (x, y) spectacle magnification; ``rays``: landed."""

    psf: np.ndarray
    step_arcmin: float
    magnification: np.ndarray
    rays: int


def _object_point_mm(eye, field_deg, distance_mm: float) -> np.ndarray:
    """The point ``distance_mm`` from the corneal vertex at field angle ``field_deg`` (OSA, the models' rule
    `field_direction`), in the eye's frame (z towards the retina)."""
    o = field_direction(eye, field_deg)
    return distance_mm * np.array([o[0], o[1], -o[2]])


def _iris_targets(eye, iris_mm: float, rays_across: int, seed: int) -> np.ndarray:
    step = iris_mm / rays_across
    axis = step * (np.arange(rays_across) - (rays_across - 1) / 2.0)
    x, y = np.meshgrid(axis, axis)
    jitter = np.random.default_rng(seed).uniform(-0.5, 0.5, (2,) + x.shape) * step
    x, y = x + jitter[0], y + jitter[1]
    inside = np.hypot(x, y) < 0.5 * iris_mm
    return np.stack([x[inside] + eye.stop_decentre_nasal_mm, y[inside]], axis=1)


def _land(eye, lens_setup, point_mm, targets, wavelength_nm, phase=None) -> np.ndarray:
    """Retinal landing points (N, 2) of rays from ``point_mm`` aimed at iris ``targets`` at ``wavelength_nm`` (one,
    or one per target) (``phase``: a phase plane)."""
    bundle, _ = trace_to_retina(eye, targets, wavelength_nm, object_point_mm=point_mm, lenses=lens_setup, phase=phase)
    return bundle.points_mm[:, :2]


class _Retina:
    """Retinal point -> field angle (OSA deg), as the eye sensor maps its pixels: the radius through the
    inverse of r(θ) (chief rays every `RADIUS_STEP_DEG` within `RADIUS_SPAN_DEG` of the image's θ), the
    direction opposite the point's azimuth, its field angle by the inverse of `field_direction`."""

    def __init__(self, eye, wavelength_nm: float, field_deg):
        o = field_direction(eye, field_deg)
        centre = math.degrees(math.atan2(math.hypot(o[0], o[1]), o[2]))
        low = max(0.0, centre - RADIUS_SPAN_DEG)
        self.theta = np.arange(low, centre + RADIUS_SPAN_DEG + 1e-9, RADIUS_STEP_DEG)
        self.radius = chief_ray_radii_mm(eye, self.theta, wavelength_nm)
        self.eye = eye

    def field_deg(self, points_mm: np.ndarray) -> np.ndarray:
        rho = np.hypot(points_mm[:, 0], points_mm[:, 1])
        theta = np.radians(np.interp(rho, self.radius, self.theta))
        safe = np.maximum(rho, 1e-300)
        ox, oy = -np.sin(theta) * points_mm[:, 0] / safe, -np.sin(theta) * points_mm[:, 1] / safe
        return field_of_direction(self.eye, np.stack([ox, oy, np.cos(theta)], axis=1))


def _magnification(eye, lens_setup, retina: _Retina, field_deg, distance_mm: float, wavelength_nm: float) -> np.ndarray:
    """d(field angle with the lens) / d(without it), 2 x 2 over (x, y): chief rays of chart points off the centre."""
    if lens_setup is None:
        return np.eye(2)
    chief = np.array([[eye.stop_decentre_nasal_mm, 0.0]])
    columns = []
    for axis in (0, 1):
        seen = []
        for setup in (lens_setup, None):
            ends = []
            for sign in (-1.0, 1.0):
                field = [float(v) for v in field_deg]
                field[axis] += sign * MAGNIFICATION_STEP_DEG
                point = _object_point_mm(eye, field, distance_mm)
                ends.append(retina.field_deg(_land(eye, setup, point, chief, wavelength_nm))[0])
            seen.append(ends[1] - ends[0])
        columns.append(seen[0] / seen[1][axis])
    return np.stack(columns, axis=1)


def ray_psf(the_eye, *, field_deg, chart_distance_m: float, lens=None, vertex_mm: float = DEFAULT_SPECTACLE_VERTEX_MM,
            wavelengths_nm=(DEFAULT_EYE_LIGHT_NM,), weights=(1.0,), sensor_wavelength_nm: float | None = None,
            arcmin_per_px: float = DEFAULT_EYE_ARCMIN_PER_PX, oversample: int = 4, rays_across: int = RAYS_ACROSS_IRIS,
            seed: int = 0, phase=None) -> RayPsf:
    """The ray PSF (module doc) of the rendered `Eye` ``the_eye`` (its optics: ametropic when it has a
    prescription; its entrance pupil): ``lens`` a thick `TrialLens` (as rendered) or None, its back vertex
    ``vertex_mm`` in front of the cornea, ``field_deg`` the chart centre's field angle (OSA) as
    `vissim.render.eye_render.EyeRender` has it; ``phase``: a measured eye's phase plane before the cornea
    (`vissim.bench.eye.bench.EyeBench.phase_plane`)."""
    eye, pupil_mm = the_eye.optics, the_eye.pupil_diameter_mm
    sensor_nm = eye.reference_wavelength_nm if sensor_wavelength_nm is None else float(sensor_wavelength_nm)
    iris_mm = iris_from_entrance_pupil_mm(eye, pupil_mm, sensor_nm)
    field = tuple(float(v) for v in field_deg)
    distance_mm = 1000.0 * chart_distance_m
    lens_setup = None if lens is None else TrialLensSetup((lens,), vertex_mm, chart_distance_m)
    retina = _Retina(eye, eye.reference_wavelength_nm, field)  # the film's map: the sensor's, at the reference
    point = _object_point_mm(eye, field, distance_mm)
    targets = _iris_targets(eye, iris_mm, rays_across, seed)
    step_deg = arcmin_per_px / oversample / 60.0
    seen = film_field_deg(eye, point, pupil_mm)  # the chart centre as the film sees it: the image's origin
    wavelengths = np.asarray(wavelengths_nm, dtype=float)  # every wavelength's rays in one trace (one index per ray)
    landed = _land(eye, lens_setup, point, np.tile(targets, (len(wavelengths), 1)), np.repeat(wavelengths, len(targets)),
                   phase)
    angles = retina.field_deg(landed) - seen
    ray_weights = np.repeat(np.asarray(weights, dtype=float) / len(targets), len(targets))
    cols, rows = osa_xy_to_image_colrow(angles[:, 0] / step_deg, angles[:, 1] / step_deg)
    half = int(math.ceil(max(np.abs(cols).max(), np.abs(rows).max()))) + 2
    edges = np.arange(-half - 0.5, half + 1.0)
    psf = histogram_on_edges(rows, cols, edges, ray_weights)
    magnification = _magnification(eye, lens_setup, retina, field, distance_mm, sensor_nm)
    return RayPsf(psf / psf.sum(), arcmin_per_px / oversample, magnification, len(angles))
