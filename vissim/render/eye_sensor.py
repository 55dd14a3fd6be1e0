"""Mitsuba sensor ``vissim_eye``: the eye as an ideal (possibly astigmatic) thin lens at its pupil.

A reduced eye whose thin lens at the pupil (z = 0, looking along +z) focuses the vergence
matrix ``K`` (dioptres, TABO x/y: world x is the examiner's right): an object point at axial
distance ``z`` is sharp in the meridians where ``1/z = K``.  The ray of the pixel whose chief
ray has image tangent ``t`` (camera frame) through pupil point ``p`` leaves along

    d = (t - K p, 1)        (t dimensionless, p in mm, K in 1/mm)

and meets the plane z at ``z t + (I - z K) p``: a blur of ``p (K - I/z)`` in tangent, the
same at every field angle (flat focal surfaces).  With ``K = I/F`` this is Mitsuba's
``thinlens`` focused at F ray for ray (pinned by ``tests/render/test_depth_render.py``):
same film mapping (``fov`` horizontal, pixels uniform in tangent), same concentric disc
sampling of the aperture, near-clip handling and weight 1.  Unlike ``thinlens`` it takes any
symmetric K: negative (focus beyond infinity: a relaxed hyperope) and astigmatic.

Properties: ``fov`` (degrees, horizontal), ``aperture_radius`` (mm, 0 = pinhole),
``power_xx_diopters``, ``power_xy_diopters``, ``power_yy_diopters`` (K), ``near_clip``,
``far_clip`` (mm), ``to_world``, ``film``, ``sampler``.  Register with
`register_eye_sensor` (idempotent) before loading a scene that uses it.
"""

from __future__ import annotations

import logging
import math

from vissim.errors import VissimInputError
from vissim.render.plugins import register_once
from vissim.units import diopters_to_per_mm

__all__ = ["EYE_SENSOR", "register_eye_sensor"]

log = logging.getLogger(__name__)

#: Plugin name; equals `vissim.bench.depth.scene_dict.EYE_SENSOR`.
EYE_SENSOR = "vissim_eye"


def _make_class(mi, dr):
    class EyeSensor(mi.Sensor):
        """See the module docstring."""

        def __init__(self, props):
            mi.Sensor.__init__(self, props)
            fov = float(props.get("fov", 45.0))
            if not 0.0 < fov < 180.0:
                raise VissimInputError(f"eye sensor fov must lie in (0, 180) degrees, got {fov:g}")
            self.tan_half = math.tan(math.radians(fov) / 2.0)
            self.radius = float(props.get("aperture_radius", 0.0))
            if self.radius < 0.0:
                raise VissimInputError(f"eye sensor aperture radius must be >= 0 mm, got {self.radius:g}")
            # dioptres (1/m) -> 1/mm: the scene is in millimetres
            self.kxx = diopters_to_per_mm(float(props.get("power_xx_diopters", 0.0)))
            self.kxy = diopters_to_per_mm(float(props.get("power_xy_diopters", 0.0)))
            self.kyy = diopters_to_per_mm(float(props.get("power_yy_diopters", 0.0)))
            self.near_clip = float(props.get("near_clip", 1.0))
            self.far_clip = float(props.get("far_clip", 1.0e7))
            width, height = self.film().size()
            self.inv_aspect = float(height) / float(width)
            self.m_needs_sample_3 = self.radius > 0.0

        def sample_ray(self, time, wavelength_sample, position_sample, aperture_sample, active=True):
            wavelengths, weight = self.sample_wavelengths(dr.zeros(mi.SurfaceInteraction3f), wavelength_sample, active)
            # Camera frame: +x left, +y up, +z forward; film x grows to the right, y downward.
            tx = (1.0 - 2.0 * position_sample.x) * self.tan_half
            ty = (1.0 - 2.0 * position_sample.y) * self.tan_half * self.inv_aspect
            if self.radius > 0.0:
                p = mi.warp.square_to_uniform_disk_concentric(aperture_sample) * self.radius
            else:
                p = mi.Point2f(0.0, 0.0)
            d = dr.normalize(mi.Vector3f(tx - (self.kxx * p.x + self.kxy * p.y),
                                         ty - (self.kxy * p.x + self.kyy * p.y), 1.0))
            to_world = self.world_transform()
            ray = mi.Ray3f(to_world @ mi.Point3f(p.x, p.y, 0.0), to_world @ d, time, wavelengths)
            inv_z = dr.rcp(d.z)
            near_t, far_t = self.near_clip * inv_z, self.far_clip * inv_z
            ray.o += ray.d * near_t
            ray.maxt = far_t - near_t
            return ray, weight

        def sample_ray_differential(self, time, wavelength_sample, position_sample, aperture_sample, active=True):
            ray, weight = self.sample_ray(time, wavelength_sample, position_sample, aperture_sample, active)
            return mi.RayDifferential3f(ray), weight

        def traverse(self, callback):
            pass

        def to_string(self):
            return (f"EyeSensor[aperture_radius={self.radius} mm, K=({1000 * self.kxx:g}, {1000 * self.kxy:g}, "
                    f"{1000 * self.kyy:g}) D]")

    return EyeSensor


def register_eye_sensor(mi) -> None:
    """Register `EYE_SENSOR` with the current Mitsuba variant (once per variant)."""
    register_once(mi, EYE_SENSOR, "sensor", _make_class)
