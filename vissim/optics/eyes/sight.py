"""Lines of sight: where a schematic eye's film sees a point at a finite distance.

The eye bench's film (`vissim.render.schematic_eye_sensor`) and every traced wavefront name a retinal
point by the field angle of the collimated beam whose chief ray (through the iris centre, at the
model's reference wavelength) lands there.  That chief ray's line in object space passes through
the entrance pupil, not the corneal vertex: a point ``d`` away at a field angle θ from the vertex is
seen from the pupil, ``e`` mm behind the vertex, nearer the axis by about e · sin θ / d (0.6 arcmin
for Navarro's 3.04 mm at 20° and 6 m).  This module is the one place that parallax is worked out.

Frames: the trace's (`vissim.optics.eyes.traced_wavefront`): x, y OSA's, z from the corneal vertex towards
the retina, mm.
"""

from __future__ import annotations

import math

import numpy as np

from vissim.optics.eyes.models import SchematicEye
from vissim.optics.eyes.traced_wavefront import (CHIEF_RAY_SAMPLES, field_direction, field_of_direction,
                                                 trace_eye_wavefront)

__all__ = ["chief_pupil_point_mm", "film_field_deg", "eye_to_world_rotation"]


def chief_pupil_point_mm(eye: SchematicEye, field_deg, pupil_mm: float) -> np.ndarray:
    """Where the chief ray of the collimated beam at ``field_deg`` (the model's reference wavelength) crosses the
    paraxial entrance-pupil plane: (x, y, z) mm in the trace's frame (module doc)."""
    traced = trace_eye_wavefront(eye, eye.reference_wavelength_nm, tuple(float(v) for v in field_deg),
                                 pupil_mm=pupil_mm, samples=CHIEF_RAY_SAMPLES, max_order=2)
    x, y = traced.chief_entrance_pupil_mm
    return np.array([x, y, traced.entrance_pupil_position_mm])


def film_field_deg(eye: SchematicEye, object_point_mm, pupil_mm: float) -> np.ndarray:
    """The field angle (x, y), degrees, at which the film sees the point ``object_point_mm`` (the trace's frame):
    the direction from the chief ray's entrance-pupil point (`chief_pupil_point_mm`, at the point's field
    angle from the vertex) to the point."""
    point = np.asarray(object_point_mm, dtype=float)
    towards = np.array([point[0], point[1], -point[2]])
    from_vertex = field_of_direction(eye, towards / np.linalg.norm(towards))
    pupil = chief_pupil_point_mm(eye, from_vertex, pupil_mm)
    line = np.array([point[0] - pupil[0], point[1] - pupil[1], pupil[2] - point[2]])
    return field_of_direction(eye, line / np.linalg.norm(line))


def eye_to_world_rotation(eye: SchematicEye, field_deg) -> np.ndarray:
    """The 3 x 3 rotation that turns the eye so that the world's +z (a chart's centre) lies at the field angle
    ``field_deg`` = (x, y) degrees, OSA's frame: the field direction (`field_direction`, the trace's rule, from the
    visual axis for a model that has one) taken onto +z about ``d x z`` (Rodrigues). The eye's local frame has +x
    to the observer's left (OSA's x), +y up, +z along the optical axis, the corneal vertex at the origin."""
    d = np.asarray(field_direction(eye, field_deg), dtype=float)
    if np.allclose(d, [0.0, 0.0, 1.0], rtol=0.0, atol=1e-15):
        return np.eye(3)
    theta = math.acos(min(1.0, float(d[2])))
    axis = np.cross(d, [0.0, 0.0, 1.0])
    axis /= np.linalg.norm(axis)
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(theta) * k + (1.0 - math.cos(theta)) * (k @ k)
