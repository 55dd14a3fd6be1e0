"""Mitsuba sensor ``vissim_schematic_eye``: a schematic eye's retina seen through its traced optics.

Each film pixel is a visual direction: its field angle, OSA's frame as every vissim ``--field-deg``
(x the examiner's right, the observer's left: `vissim.units.osa_xy_to_image_colrow`; y up), is
``(field_x_deg - (u - 1/2) W a, field_y_deg + (1/2 - v) H a)`` (u, v the film position in [0, 1], row
0 at the top, columns to the observer's right; a = ``arcmin_per_px`` / 60; W x H the film's size),
and its direction is the one the traced wavefront gives that field angle
(`vissim.optics.eyes.traced_wavefront.field_direction`: (tan x, tan y, 1), from the visual axis for a model
that has one), so a pixel of the render and a pixel of a simulation at the same field angle look
the same way.  That direction's chief ray **at the model's reference wavelength**
lands on the curved retina at the radius r(θ) of a table traced at init (`vissim.render.schematic_eye_tables`:
the eye's distortion is in it), opposite its azimuth (the retinal image is inverted).  From
that retinal point a ray is aimed at a point sampled uniformly in the box that bounds, on the lens's
back surface, the rays that pass the iris (pbrt-v4's exit-pupil bounds), and traced out through
the eye (`vissim.render.schematic_eye_trace`, Dr.Jit, at the ray's wavelength).  Rays stopped by
the iris or lost at a surface get weight 0; the fraction that gets through is tabulated at init
(`pass_fraction`, logged).

**Normalisation**: weight = ``cos θ_r |d_z| A_box / (dist² Ω(r, ψ))``, the projected-solid-angle
estimator divided by its own integral Ω over the passing rays (tabulated at init), so that a
uniform radiance L gives every pixel the value L, as Mitsuba's ``thinlens`` does for any pupil
(the factor a thin lens leaves out, and that this sensor states, is the retinal irradiance per
unit radiance, ``n_vitreous² Ω``: `retinal_irradiance_factor`).

**Wavelength**: ``wavelength_nm`` set: every wavelength is that one (monochromatic; in a mono or
RGB variant it is the wavelength the optics are traced at, default the model's reference; in a
spectral variant the weight is divided by the film's luminance response at that wavelength, so
a white scene still develops its radiance).  In
a spectral variant without it, the sampled wavelengths' first (the hero) is traced, the others'
weights are zeroed and the hero's multiplied by their count, so the film's average over them
keeps its expectation (Mitsuba's spectral film develops Y with CIE ȳ = V(λ): photopic).

Frame: local +z forward (into the scene), +y up, +x the observer's left (Mitsuba's camera
frame); the eye's frame (z towards the retina, x the examiner's right: the subject's left) maps
to it by z -> -z; the local origin is the corneal vertex.  Properties: ``eye_key``, the `vissim.optics.eyes.eye.Eye`
handed over by `vissim.bench.eye.sensor_eyes.register_sensor_eye` (its optics: the model at its accommodation, its surfaces as
altered, made ametropic when it has a prescription; the tables are traced in its x meridian, so a
cylinder's distortion is the x meridian's; its pupil, entrance pupil or iris) and, for a measured eye, the
phase plane registered with it (`vissim.optics.eyes.measured.phase_plane`: crossed by every ray as it leaves
the cornea; the tables, the film's map and Ω are the base eye's, which the plane does not change:
it lies outside the iris), ``wavelength_nm``,
``arcmin_per_px``, ``field_x_deg``, ``field_y_deg``, ``far_clip`` (mm), ``to_world``, ``film``,
``sampler``.  The pupil is converted by real rays at ``wavelength_nm`` or the model's reference
(`vissim.optics.eyes.traced_wavefront`).  Register with `register_schematic_eye_sensor` (idempotent).
"""

from __future__ import annotations

import functools
import logging
import math

import numpy as np

from vissim.bench.eye.scene import SENSOR_TYPE
from vissim.bench.eye.sensor_eyes import sensor_eye, sensor_phase
from vissim.checks import number_within
from vissim.optics.eyes.defaults import DEFAULT_EYE_ARCMIN_PER_PX
from vissim.optics.eyes.traced_wavefront import image_reach_deg, pupils_mm
from vissim.units import ARCMIN_PER_DEG
from vissim.render.plugins import register_once
from vissim.optics.eyes.retina_map import chief_ray_radii_mm
from vissim.render.schematic_eye_tables import EyeTables, eye_tables, table_theta_deg
from vissim.checks import CIE_YBAR_RANGE_NM, EYE_RENDER_MAX_THETA_DEG, EYE_RENDER_WAVELENGTH_RANGE_NM
from vissim.checks import arcmin_per_px as checked_arcmin_per_px
from vissim.render.schematic_eye_trace import SchematicEyeTracer

__all__ = ["SCHEMATIC_EYE_SENSOR", "register_schematic_eye_sensor", "sensor_tables"]

log = logging.getLogger(__name__)

#: The tables' reach is rounded up to a multiple of this (deg), so nearby films and fields share them.
TABLE_REACH_STEP_DEG = 5.0
#: Plugin name.
SCHEMATIC_EYE_SENSOR = SENSOR_TYPE  # the scene names it so (vissim.bench.eye.scene)


@functools.lru_cache(maxsize=16)
def sensor_tables(optics, iris_mm: float, wavelength_nm: float, max_theta_deg: float) -> EyeTables:
    """`eye_tables` of the traced `SchematicEye` ``optics``, cached (a scene reloaded with the same eye reuses them)."""
    return eye_tables(optics, iris_mm, wavelength_nm, max_theta_deg)


@functools.lru_cache(maxsize=16)
def sensor_map_radii_mm(optics, wavelength_nm: float, max_theta_deg: float) -> np.ndarray:
    """The film's map r(θ) at ``wavelength_nm`` on the tables' θ grid (`chief_ray_radii_mm`), cached."""
    return chief_ray_radii_mm(optics, table_theta_deg(max_theta_deg), wavelength_nm)


class _Lookup:
    """Linear interpolation in a table on a uniform grid ``x0 + i dx``, in Dr.Jit arrays or numbers."""

    def __init__(self, x0: float, dx: float, values):
        self.x0, self.dx, self.values = x0, dx, np.asarray(values, dtype=float)
        self._arrays = {}

    def at(self, dr, index):
        """The value at a whole-number ``index`` (a Dr.Jit array or a number): no interpolation."""
        if not dr.is_array_v(index):
            return float(self.values[int(index)])
        kind = type(index)
        if kind not in self._arrays:
            self._arrays[kind] = kind(self.values)
        return dr.gather(kind, self._arrays[kind], dr.uint32_array_t(kind)(index))

    def __call__(self, dr, x):
        last = len(self.values) - 1
        if not dr.is_array_v(x):
            return float(np.interp(x, self.x0 + self.dx * np.arange(last + 1), self.values))
        kind = type(x)
        if kind not in self._arrays:
            self._arrays[kind] = kind(self.values)
        u = dr.clip((x - self.x0) / self.dx, 0.0, last - 1e-4)
        i = dr.floor(u)
        index = dr.uint32_array_t(kind)(i)
        low = dr.gather(kind, self._arrays[kind], index)
        high = dr.gather(kind, self._arrays[kind], index + 1)
        return low + (u - i) * (high - low)


def _make_class(mi, dr):
    spectral = mi.is_spectral

    class SchematicEyeSensor(mi.Sensor):
        """See the module docstring."""

        def __init__(self, props):
            mi.Sensor.__init__(self, props)
            the_eye = sensor_eye(str(props.get("eye_key", "")))
            self.phase = sensor_phase(str(props.get("eye_key", "")))
            eye = the_eye.optics
            self.model = the_eye.model
            fixed = props.get("wavelength_nm", None)
            self.fixed_wavelength_nm = None if fixed is None else number_within(fixed, "wavelength", "nm",
                                                                                EYE_RENDER_WAVELENGTH_RANGE_NM)
            if spectral and self.fixed_wavelength_nm is not None:  # CIE ȳ must be tabulated there
                number_within(self.fixed_wavelength_nm, "a monochromatic spectral render's wavelength", "nm",
                              CIE_YBAR_RANGE_NM)
            if spectral and self.fixed_wavelength_nm is not None:
                # the film develops Y = ȳ(λ) L MI_CIE_Y_NORMALIZATION: divide it out
                y_bar = mi.cie1931_y(mi.Float(self.fixed_wavelength_nm))
                y_bar = float(y_bar[0] if dr.is_array_v(y_bar) else y_bar)
                self.mono_scale = 1.0 / (y_bar * mi.MI_CIE_Y_NORMALIZATION)
            self.wavelength_nm = self.fixed_wavelength_nm or eye.reference_wavelength_nm
            self.pupil_mm, self.iris_mm = pupils_mm(eye, self.wavelength_nm, the_eye.pupil_diameter_mm, the_eye.iris_mm)
            self.arcmin_per_px = checked_arcmin_per_px(float(props.get("arcmin_per_px", DEFAULT_EYE_ARCMIN_PER_PX)))
            self.field_deg = (float(props.get("field_x_deg", 0.0)), float(props.get("field_y_deg", 0.0)))
            self.far_clip = float(props.get("far_clip", 1.0e7))
            width, height = self.film().size()
            self.span_deg = (width * self.arcmin_per_px / ARCMIN_PER_DEG,
                             height * self.arcmin_per_px / ARCMIN_PER_DEG)
            self.visual_axis_rad = math.radians(eye.visual_axis_deg)
            reach = image_reach_deg(eye, (height, width), self.arcmin_per_px, self.field_deg)
            if reach <= EYE_RENDER_MAX_THETA_DEG:  # beyond it the tables refuse the image, naming its reach
                reach = min(math.ceil(reach / TABLE_REACH_STEP_DEG) * TABLE_REACH_STEP_DEG, EYE_RENDER_MAX_THETA_DEG)
            self.tables = sensor_tables(eye, self.iris_mm, self.wavelength_nm, reach)
            # the film's map: where the chief ray lands at the model's reference wavelength, as every simulation
            # places its PSFs (`vissim.optics.eyes.psf_wavefront`): at another wavelength the image shifts by the
            # transverse chromatic aberration, as the eye's does
            reference = eye.reference_wavelength_nm
            self.map_radius_mm = self.tables.radius_mm if self.wavelength_nm == reference else sensor_map_radii_mm(
                eye, reference, reach)
            self._init_lookups(eye)
            self.m_needs_sample_3 = True
            centre, edge = self.tables.pass_fraction[0], self.tables.pass_fraction[-1]
            log.info("schematic-eye sensor %s: %.1f %% of pupil samples pass the iris at the fovea, %.1f %% at "
                     "%.3g mm", self.model, 100 * centre, 100 * edge, self.tables.r_edges_mm[-1])

        def _direction(self, x_deg, y_deg):
            """`vissim.optics.eyes.traced_wavefront.field_direction` (the one rule) in Dr.Jit: (tan x, tan y, 1)
            normalised, turned from the visual axis to the optical axis by the model's ``visual_axis_deg``."""
            tx, ty = dr.tan(x_deg * (math.pi / 180.0)), dr.tan(y_deg * (math.pi / 180.0))
            norm = dr.rsqrt(tx * tx + ty * ty + 1.0)
            ox, oy, oz = tx * norm, ty * norm, norm
            c, s = math.cos(self.visual_axis_rad), math.sin(self.visual_axis_rad)
            return ox * c + oz * s, oy, -ox * s + oz * c

        def _init_lookups(self, eye):
            t = self.tables
            self.tracer = SchematicEyeTracer(eye, self.iris_mm, phase=self.phase)
            self.radius_of = _Lookup(0.0, float(t.theta_deg[1] - t.theta_deg[0]), self.map_radius_mm)
            self.bin_mm = float(t.r_edges_mm[1] - t.r_edges_mm[0])
            self.bins, self.azimuth_count = t.boxes.shape[:2]
            self.box = [_Lookup(0.0, 1.0, t.boxes[:, :, j].ravel()) for j in range(4)]
            self.omega = [_Lookup(0.0, self.bin_mm, t.omega_sr[:, j]) for j in range(self.azimuth_count)]
            self.azimuth_step = 2.0 * math.pi / self.azimuth_count

        def pass_fraction(self) -> np.ndarray:
            """Per retinal radius edge: the fraction of samples in the box that pass the iris."""
            return self.tables.pass_fraction

        def retinal_irradiance_factor(self, radius_mm: float, azimuth_rad: float = 0.0) -> float:
            """Retinal irradiance per unit scene radiance (sr; module doc)."""
            return self.tables.retinal_irradiance_factor(radius_mm, azimuth_rad)

        def _wavelengths(self, wavelength_sample, active):
            if not spectral:
                wavelengths, weight = self.sample_wavelengths(dr.zeros(mi.SurfaceInteraction3f), wavelength_sample,
                                                              active)
                return wavelengths, weight, self.wavelength_nm
            if self.fixed_wavelength_nm is not None:
                return mi.Spectrum(self.fixed_wavelength_nm), mi.Spectrum(self.mono_scale), self.fixed_wavelength_nm
            wavelengths, weight = self.sample_wavelengths(dr.zeros(mi.SurfaceInteraction3f), wavelength_sample,
                                                          active)
            count = dr.size_v(mi.Spectrum)
            hero_only = mi.Spectrum([float(count)] + [0.0] * (count - 1))
            return wavelengths, weight * hero_only, wavelengths[0]

        def _box(self, r, sector):
            """The sampling box (a0, a1, b0, b1) of the sector: the radius bin holding ``r`` (mm), ``sector``."""
            k = dr.minimum(dr.floor(r / self.bin_mm), self.bins - 1)
            return [lookup.at(dr, k * self.azimuth_count + sector) for lookup in self.box]

        def _azimuth(self, cos_psi, sin_psi):
            """(the sector index, the position between its two azimuth nodes in [0, 1))."""
            if self.azimuth_count == 1:
                return 0.0 * cos_psi, 0.0 * cos_psi
            psi = dr.atan2(sin_psi, cos_psi)
            u = dr.select(psi < 0.0, psi + 2.0 * math.pi, psi) / self.azimuth_step
            sector = dr.minimum(dr.floor(u), self.azimuth_count - 1)
            return sector, u - sector

        def _omega(self, r, sector, frac):
            """Ω at retinal radius r, linear in r and (for a decentred iris) between the sector's azimuths."""
            count = self.azimuth_count
            if count == 1:
                return self.omega[0](dr, r)
            total = 0.0 * r
            for index, lookup in enumerate(self.omega):
                value = lookup(dr, r)
                total = total + dr.select(sector == index, (1.0 - frac) * value, 0.0)
                total = total + dr.select(sector == (index - 1) % count, frac * value, 0.0)
            return total

        def sample_ray(self, time, wavelength_sample, position_sample, aperture_sample, active=True):
            wavelengths, weight, wavelength_nm = self._wavelengths(wavelength_sample, active)
            # the pixel's field angle, OSA's frame (columns run to the observer's right: -x)
            x_deg = self.field_deg[0] - (position_sample.x - 0.5) * self.span_deg[0]
            y_deg = self.field_deg[1] + (0.5 - position_sample.y) * self.span_deg[1]
            ox, oy, oz = self._direction(x_deg, y_deg)
            rho = dr.sqrt(ox * ox + oy * oy)
            theta = dr.atan2(rho, oz) * (180.0 / math.pi)
            on_axis = rho <= 1e-12
            inv = dr.select(on_axis, 0.0, 1.0 / dr.maximum(rho, 1e-12))
            cos_psi = dr.select(on_axis, 1.0, -ox * inv)  # the landing point's azimuth in the eye's x, y (inverted)
            sin_psi = dr.select(on_axis, 0.0, -oy * inv)
            r = self.radius_of(dr, theta)
            p = self.tracer.retina_point(r * cos_psi, r * sin_psi)
            sector, frac = self._azimuth(cos_psi, sin_psi)
            a0, a1, b0, b1 = self._box(r, sector)
            a = a0 + (a1 - a0) * aperture_sample.x
            b = b0 + (b1 - b0) * aperture_sample.y
            q = self.tracer.surface_point(len(self.tracer.shapes) - 2, a * cos_psi - b * sin_psi,
                                          a * sin_psi + b * cos_psi)
            d = (q[0] - p[0], q[1] - p[1], q[2] - p[2])
            out = self.tracer.trace_out(p, d, wavelength_nm)
            w = self.tracer.projected_solid_angle_weight(p, d) * (a1 - a0) * (b1 - b0) / self._omega(r, sector, frac)
            w = dr.select(out.valid & active, w, 0.0)
            to_world = self.world_transform()
            origin = mi.Point3f(out.points[0], out.points[1], -out.points[2])
            direction = mi.Vector3f(out.directions[0], out.directions[1], -out.directions[2])
            ray = mi.Ray3f(to_world @ origin, dr.normalize(to_world @ direction), time, wavelengths)
            ray.maxt = self.far_clip
            return ray, weight * w

        def sample_ray_differential(self, time, wavelength_sample, position_sample, aperture_sample, active=True):
            ray, weight = self.sample_ray(time, wavelength_sample, position_sample, aperture_sample, active)
            return mi.RayDifferential3f(ray), weight

        def traverse(self, callback):
            pass

        def to_string(self):
            return (f"SchematicEyeSensor[model={self.model}, pupil={self.pupil_mm:.4g} mm (iris {self.iris_mm:.4g} "
                    f"mm), {self.arcmin_per_px:g} arcmin/px, field=({self.field_deg[0]:g}, {self.field_deg[1]:g}) deg]")

    return SchematicEyeSensor


def register_schematic_eye_sensor(mi) -> None:
    """Register `SCHEMATIC_EYE_SENSOR` with the current Mitsuba variant (once per variant)."""
    register_once(mi, SCHEMATIC_EYE_SENSOR, "sensor", _make_class)
