"""The wavefront of a traced bundle against a reference sphere about its image point.

A bundle traced to the image surface (a retina) ends in a homogeneous medium of index n'.  Each
ray's final straight line is followed back (virtually, where it runs back through earlier
surfaces) to the reference sphere centred on the chief ray's image point and passing through
the chief ray's crossing of the exit-pupil plane; the optical path there is the path at the
image point minus n' times that distance.  The wavefront error is

    W = L(chief) - L        (µm; OSA sign: W > 0 is phase advance, as the bench's W = L_ref - L)

so a wave that focuses before the image point (a myopic eye) has W > 0 at the pupil's rim:
``n' dz (1 - cos u)`` for a focus dz before it, u the ray's angle to the chief ray (the exact
longitudinal focal-shift term; Welford, Aberrations of Optical Systems, 1986).
"""

from __future__ import annotations

import numpy as np

from vissim.checks import counted
from vissim.errors import VissimInputError
from vissim.optics.raytrace.trace import RayBundle

__all__ = ["opl_to_sphere_mm", "wavefront_on_reference_sphere_um"]


def opl_to_sphere_mm(bundle: RayBundle, centre_mm, radius_mm: float) -> np.ndarray:
    """Each ray's optical path (mm) where its final line meets the sphere on its way towards ``centre_mm``."""
    rel = bundle.points_mm - np.asarray(centre_mm, dtype=float).reshape(1, 3)
    b = np.einsum("ij,ij->i", rel, bundle.directions)
    c = np.einsum("ij,ij->i", rel, rel) - float(radius_mm) ** 2
    disc = b * b - c
    if np.any(disc < 0.0):
        never = int(np.sum(disc < 0.0))
        raise VissimInputError(f"{counted(never, 'ray')} never {'meets' if never == 1 else 'meet'} the {radius_mm:g} mm "
                               "reference sphere")
    t = -b - np.sqrt(disc)  # the crossing before the ray's closest approach to the centre
    return bundle.opl_mm + bundle.final_index * t


def wavefront_on_reference_sphere_um(bundle: RayBundle, chief_ray: int, exit_pupil_z_mm: float) -> np.ndarray:
    """W (µm, module doc) of every ray of ``bundle`` (on the image surface); ``chief_ray`` its index."""
    image = bundle.points_mm[chief_ray]
    d = bundle.directions[chief_ray]
    pupil = image + (exit_pupil_z_mm - image[2]) / d[2] * d
    radius = float(np.linalg.norm(image - pupil))
    opl = opl_to_sphere_mm(bundle, image, radius)
    return 1000.0 * (opl[chief_ray] - opl)  # mm -> µm
