"""Where a visual direction lands on a schematic eye's retina: the radius r(θ) of its chief ray.

The film's map of the schematic-eye sensor (`vissim.render.schematic_eye_tables`) and the eye
bench's ray self-check (`vissim.validation.eye.rays`) read this one table: the chief ray of a
direction at angle θ from the optical axis, a collimated ray aimed at the centre of the iris
plane's axial point and traced on to the retina by the numpy exact tracer
(`vissim.optics.raytrace`), lands at the radius r(θ) (mm, measured in x, y).  For a decentred iris
(Liou–Brennan) the ray still passes the axial point of the iris plane, so that the map is radially
symmetric: the image's centre is where the optical axis meets the retina.
"""

from __future__ import annotations

import math

import numpy as np

from vissim.optics.eyes.models import SchematicEye
from vissim.optics.eyes.surfaces import split_at_stop
from vissim.optics.raytrace import aim_collimated, trace_rays

__all__ = ["chief_ray_radii_mm", "START_BEFORE_MM"]

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
