"""A schematic eye as surfaces of the exact trace (`vissim.optics.raytrace`), in the eye's frame.

Frame: the corneal front vertex at the origin, light travelling along +z from the cornea to the
retina (``travel_z = +1``); x and y are OSA's pupil axes (x the examiner's right, y up, looking
at the eye), so a wavefront's (x, y) is OSA's. Each `EyeSurface` becomes a `Surface` at the sum
of the thicknesses before it: a `Conic` (R, Q), a `Plane` for an infinite radius (the iris, a
GRIN lens's equatorial boundary), or a `Biconic` for a toric surface (`EyeSurface.is_toric`: the
cornea front of `vissim.optics.eyes.fixation.ametropic_eye`): radius ``radius_mm`` along its x',
the TABO meridian ``axis_deg`` (counter-clockwise from +x, the examiner's right, as the examiner
faces the eye: this frame's x and y, so `Biconic`'s ``axis_deg`` is the TABO axis as it stands),
``radius_y_mm`` along y', both with the surface's conic Q. Homogeneous media are passed as their ``index(wavelength_nm)``,
so one list of surfaces serves every wavelength; a `GrinMedium` becomes a `GradientIndex` with its
z measured from its segment's front vertex and its dispersion shift in ``a0``.

`split_at_stop` cuts the list at the iris: the surfaces in front (the cornea, through which a
beam is aimed onto the iris with `aim_collimated`) and those behind (traced on to the retina).
"""

from __future__ import annotations

import math

from vissim.errors import VissimInputError
from vissim.optics.eyes.dispersion import GrinMedium
from vissim.optics.eyes.models import SchematicEye
from vissim.optics.raytrace import Biconic, Conic, GradientIndex, Plane, Surface

__all__ = ["vertex_positions_mm", "grin_index", "eye_surfaces", "split_at_stop"]


def vertex_positions_mm(eye: SchematicEye) -> tuple[float, ...]:
    """Each surface's vertex z (mm) behind the corneal front vertex."""
    positions, z = [], 0.0
    for surface in eye.surfaces:
        positions.append(z)
        z += surface.thickness_after_mm
    return tuple(positions)


def grin_index(medium: GrinMedium, front_z_mm: float) -> GradientIndex:
    """``medium`` (z from its front vertex at ``front_z_mm``) as the tracer's `GradientIndex`."""
    coefficients = tuple(medium.z_coefficients) + (0.0,) * (3 - len(medium.z_coefficients))
    if len(coefficients) > 3:
        raise VissimInputError(f"the {medium.name}'s index is of degree {len(coefficients) - 1} in z; "
                               "the trace takes up to 2")
    a0, a1, a2 = coefficients

    def axial_index(wavelength_nm: float) -> float:
        return a0 + medium.shift(wavelength_nm)

    return GradientIndex(axial_index, a1, a2, medium.r2_coefficient, front_z_mm, name=medium.name)


def _shape(surface):
    """The trace's shape of an `EyeSurface` (module doc)."""
    if surface.is_toric:
        return Biconic(surface.radius_mm, surface.radius_y_mm, surface.conic, surface.conic, surface.axis_deg)
    return Plane() if math.isinf(surface.radius_mm) else Conic(surface.radius_mm, surface.conic)


def eye_surfaces(eye: SchematicEye) -> tuple[Surface, ...]:
    """The eye's surfaces, cornea to retina, as `Surface` (module doc); no clear apertures."""
    surfaces = []
    for surface, z in zip(eye.surfaces, vertex_positions_mm(eye)):
        medium = surface.medium_after
        after = grin_index(medium, z) if isinstance(medium, GrinMedium) else medium.index
        surfaces.append(Surface(_shape(surface), z, after, name=surface.name))
    return tuple(surfaces)


def split_at_stop(eye: SchematicEye) -> tuple[tuple[Surface, ...], float, tuple[Surface, ...]]:
    """(the surfaces before the iris, the iris plane's z in mm, the surfaces after it to the retina)."""
    surfaces = eye_surfaces(eye)
    i = eye.stop_index
    return surfaces[:i], surfaces[i].vertex_z_mm, surfaces[i + 1:]
