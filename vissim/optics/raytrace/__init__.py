"""The exact real-ray trace, one for trial lenses and schematic eyes alike (pure numpy).

* `shapes`: sag surfaces with analytic gradients -- curvature matrix (trial lenses), conic,
  biconic, plane.
* `media`: homogeneous (number or function of wavelength) and gradient-index media.
* `surface`: a placed surface, intersection, exact normals, vector Snell's law.
* `grin`: the ray equation through a GRIN medium (RK4 in Sharma's parameter).
* `trace`: `trace_rays` and the `RayBundle` it returns.
* `aim`: `aim_rays` (from one object point) and `aim_collimated` (an object at infinity): rays
  onto a grid of a stop plane.
* `reference_sphere`: the wavefront against the reference sphere about the chief ray's image point.
"""

from vissim.optics.raytrace.aim import aim_collimated, aim_rays, launch_directions
from vissim.optics.raytrace.media import GradientIndex, resolve_medium
from vissim.optics.raytrace.phase import PhasePlane
from vissim.optics.raytrace.reference_sphere import opl_to_sphere_mm, wavefront_on_reference_sphere_um
from vissim.optics.raytrace.shapes import Biconic, Conic, MatrixSag, Plane, SagShape
from vissim.optics.raytrace.surface import Surface
from vissim.optics.raytrace.trace import RayBundle, trace_rays

__all__ = ["PhasePlane", "aim_rays", "aim_collimated", "launch_directions", "opl_to_sphere_mm",
           "wavefront_on_reference_sphere_um", "GradientIndex", "resolve_medium", "Biconic", "Conic", "MatrixSag",
           "Plane", "SagShape", "Surface", "RayBundle", "trace_rays"]
