"""The refraction of a schematic eye from its traced wavefront: paraxial and minimum RMS.

Both read the OSA Zernike coefficients (µm) over the **entrance pupil** (radius R, mm), as
`vissim.optics.eyes.traced_wavefront.EyeWavefront` holds them, and give the **correcting lens** (a
`Prescription`: negative sphere for a myope), as `vissim.optics.pupil.wavefront.zernike_um_to_prescription`:

* minimum RMS: from c(2,−2), c(2,0), c(2,2) only, M = −4√3 c(2,0)/R², J0 = −2√6 c(2,2)/R²,
  J45 = −2√6 c(2,−2)/R² (Thibos, Hong, Bradley & Applegate 2004, J. Vision 4:329);
* paraxial: the wavefront's curvature at the pupil centre, every order's ρ² term: with W ≈ a0 ρ² +
  a2 ρ² cos 2θ + a−2 ρ² sin 2θ near the centre, (M, J0, J45) = −2 (a0, a2, a−2)/R². For orders
  2, 4, 6 this is Thibos et al.'s M = (−4√3 c20 + 12√5 c40 − 24√7 c60)/R², J0 = (−2√6 c22 +
  6√10 c42 − 12√14 c62)/R² (J45 alike with m = −2); orders 8 and up add their own ρ² terms.

Plane: the entrance pupil lies in object space (air), so these are vergences at the
entrance-pupil plane, ``entrance_pupil_position_mm`` behind the corneal vertex. Each is carried
once to the plane asked for -- the corneal vertex, or a spectacle plane ``vertex_distance_mm`` in
front of it -- through air by the vergence transfer of power matrices, F' = F (I + d F)⁻¹, d the
distance in metres from that plane to the entrance pupil.

Pupil: **the entrance pupil seen along the chief ray** (`PUPIL_DEFINITION`), as a peripheral
refractometer sees it, and as the Sturm interval of real tangential and sagittal fans about the
chief ray (Coddington) measures it. The coefficients' coordinates p = (x, y) lie in the
entrance-pupil plane, normal to the optical axis; off axis the beam crosses that plane obliquely. A
ray at p lies s = S p from the chief ray in the plane normal to it, o the unit chief-ray direction
(`traced_wavefront.field_direction`, optical-axis frame): |s|² = pᵀ (I − o⊥ o⊥ᵀ) p, o⊥ = (o_x, o_y), so
S = (I − o⊥ o⊥ᵀ)^½, cos θ along o⊥ (the tangential meridian, θ the chief ray's angle to the optical
axis) and 1 across it (`chief_ray_stretch` is S⁻¹; S, symmetric, keeps the x and y axes that
the tilt about the sagittal line carries into the beam's plane, so the TABO axis keeps its meaning).
A front W(p) = W'(S p) has the Hessian S H' S, so the power matrix over the pupil seen along the
chief ray is F' = S⁻¹ F S⁻¹: the tangential power ÷ cos²θ, the sagittal unchanged, the cross term
÷ cos θ. Both refractions are so transformed at the entrance pupil, then carried to their plane
along the chief ray, over the distance d / cos θ between the planes' crossings (`along_chief_ray`).
The paraxial refraction (the curvature at the pupil centre) so becomes the oblique beam's own; the
minimum-RMS one is over the same rays, the entrance-pupil disc seen along the chief ray (an ellipse
D × D cos θ across the beam). On the optical axis of a model with no visual axis S = I, and both
come back bit for bit as before. ES1999 at 40° (1 mm, 543 nm, paraxial, corneal vertex): cylinder
3.40 D over the entrance-pupil plane, 3.85 D seen along the chief ray, as optiland's real-ray
tangential and sagittal foci give it (`tests/test_eye_oblique_refraction.py`). visisipy 0.5's
3.91 D is another quantity: optiland's OPD over the axis-centred entrance pupil divided by the
exit pupil's radius squared, an image-space vergence ((3.40 / 3.12)² = 1.18 times the object-space one).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vissim.checks import vertex_distance_mm as checked_vertex_distance_mm
from vissim.optics.rx.prescription import Prescription
from vissim.optics.rx.trial_lens import vergence_after_distance
from vissim.optics.pupil.wavefront import zernike_um_to_prescription
from vissim.optics.pupil.zernike import zernike_norm
from vissim.units import mm_to_m

__all__ = ["paraxial_rho2_coefficient", "paraxial_prescription", "minimum_rms_prescription", "transfer_prescription",
           "chief_ray_stretch", "along_chief_ray", "PUPIL_DEFINITION", "BEAM_PLANE", "EyeRefraction", "eye_refraction"]

#: The pupil the refraction is over (module doc).
PUPIL_DEFINITION = "entrance pupil seen along the chief ray"
#: An `EyeWavefront`'s ``pupil_plane`` when its coefficients are already over the plane normal to the chief ray
#: (a measured eye's: the wavefront sensor's), not over the entrance pupil's plane.
BEAM_PLANE = "normal to the chief ray"
#: An `EyeWavefront`'s ``pupil_plane`` when its coefficients are over the entrance pupil's plane (normal to the
#: optical axis: a traced schematic eye's).
ENTRANCE_PUPIL_PLANE = "entrance pupil"


def paraxial_rho2_coefficient(n: int, m: int) -> float:
    """The coefficient of ρ² in Z(n, m) (OSA, unit RMS) for m = 0 or ±2, n ≥ |m| even; its radial
    polynomial's last term times the norm: (−1)^k (n/2 + 1)(n/2) / (1 + δ_|m|2), k = n/2 − 1."""
    if abs(m) not in (0, 2) or n < 2 or (n - m) % 2:
        return 0.0
    k = n // 2 - 1
    radial = (-1) ** k * (n // 2 + 1) * (n // 2) / (2.0 if abs(m) == 2 else 1.0)
    return zernike_norm(n, m) * radial


def paraxial_prescription(zernike_um, pupil_diameter_mm: float) -> Prescription:
    """The correcting lens (at the pupil's plane) from the wavefront's curvature at the pupil centre (module doc)."""
    a = {0: 0.0, 2: 0.0, -2: 0.0}
    for (n, m), c in zernike_um.items():
        if m in a:
            a[m] += float(c) * paraxial_rho2_coefficient(n, m)
    radius_sq = (0.5 * pupil_diameter_mm) ** 2
    return Prescription.from_power_vector(-2.0 * a[0] / radius_sq, -2.0 * a[2] / radius_sq, -2.0 * a[-2] / radius_sq)


def minimum_rms_prescription(zernike_um, pupil_diameter_mm: float) -> Prescription:
    """The correcting lens (at the pupil's plane) from the second-order terms alone."""
    return zernike_um_to_prescription(zernike_um, pupil_diameter_mm)


def transfer_prescription(rx: Prescription, distance_mm: float) -> Prescription:
    """``rx`` (a far point's vergence at a plane) at the plane ``distance_mm`` in front of it, through air."""
    return Prescription.from_power_matrix(vergence_after_distance(rx.power_matrix(), -mm_to_m(distance_mm)))


def chief_ray_stretch(direction) -> np.ndarray:
    """S⁻¹ (2 x 2; module doc): I + (1/cos θ − 1) n nᵀ, n the unit transverse part of the unit chief-ray
    ``direction`` (x, y, z; z along the optical axis), θ its angle to the axis; exactly I on the axis."""
    o = np.asarray(direction, dtype=float)
    sin_sq = float(o[0] ** 2 + o[1] ** 2)
    if sin_sq == 0.0:
        return np.eye(2)
    n = o[:2] / math.sqrt(sin_sq)
    return np.eye(2) + (1.0 / abs(float(o[2])) - 1.0) * np.outer(n, n)


def along_chief_ray(rx: Prescription, direction, distance_mm: float) -> Prescription:
    """``rx`` (at the entrance pupil, over its plane) over the pupil seen along the chief ray ``direction``,
    carried to the plane ``distance_mm`` in front of the entrance pupil, along the chief ray (module doc)."""
    o = np.asarray(direction, dtype=float)
    if o[0] == 0.0 and o[1] == 0.0:
        return transfer_prescription(rx, distance_mm)
    stretch = chief_ray_stretch(o)
    seen = Prescription.from_power_matrix(stretch @ np.asarray(rx.power_matrix(), dtype=float) @ stretch)
    return transfer_prescription(seen, distance_mm / abs(float(o[2])))


@dataclass(frozen=True)
class EyeRefraction:
    """The paraxial and minimum-RMS refractions of a traced wavefront at ``plane``:
    ``"corneal vertex"`` or ``"spectacle plane"`` ``vertex_distance_mm`` in front of it, over the pupil
    ``pupil_definition`` (module doc)."""

    plane: str
    vertex_distance_mm: float
    pupil_diameter_mm: float
    paraxial: Prescription
    minimum_rms: Prescription
    pupil_definition: str = PUPIL_DEFINITION

    def as_json(self) -> dict:
        def entry(rx: Prescription) -> dict:
            m, j0, j45 = rx.power_vector()
            return {"sphere_diopters": rx.sphere_diopters, "cylinder_diopters": rx.cylinder_diopters,
                    "axis_deg": rx.axis_deg, "M": m, "J0": j0, "J45": j45}

        return {"refraction_plane": self.plane, "vertex_distance_mm": self.vertex_distance_mm,
                "pupil_definition": self.pupil_definition,
                "paraxial": entry(self.paraxial), "minimum_rms": entry(self.minimum_rms)}


def eye_refraction(wavefront, vertex_distance_mm: float | None = None) -> EyeRefraction:
    """The refraction of an `EyeWavefront` at the corneal vertex (``vertex_distance_mm`` None) or at
    a spectacle plane that far in front of it, over the entrance pupil seen along the chief ray (module doc)."""
    vertex = 0.0 if vertex_distance_mm is None else checked_vertex_distance_mm(vertex_distance_mm)
    plane = "corneal vertex" if vertex_distance_mm is None else "spectacle plane"
    distance = wavefront.entrance_pupil_position_mm + vertex
    pupil, chief = wavefront.entrance_pupil_mm, wavefront.chief_direction
    if wavefront.pupil_plane == BEAM_PLANE:  # already seen along the chief ray: carried along it only
        def seen(rx):
            return transfer_prescription(rx, distance / abs(float(chief[2])))
    else:
        def seen(rx):
            return along_chief_ray(rx, chief, distance)
    return EyeRefraction(plane, vertex, pupil, seen(paraxial_prescription(wavefront.zernike_um, pupil)),
                         seen(minimum_rms_prescription(wavefront.zernike_um, pupil)))
