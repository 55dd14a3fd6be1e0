"""The off-axis refraction over the entrance pupil seen along the chief ray (`vissim.optics.eyes.refraction`).

Oracles, each independent of the code it checks:

* the pupil's projection written out here: a ray at p in the entrance-pupil plane lies (p − o(o·p))
  from the chief ray o, so a meridian's power over that plane becomes, seen along o, the tangential
  one ÷ cos²θ, the sagittal one unchanged, the cross term ÷ cos θ;
* optiland 0.6.3's real rays through its NavarroWideAngleEye (ES1999 at 543 nm; a peer, skipped when
  absent): Coddington's tangential and sagittal foci found by real rays, sharing no vissim code.
  Where the chief ray (through the iris centre) crosses the corneal-vertex plane, a far point at
  vergence V on that ray sends two rays at ±h (h = 0.01 mm, across the beam, in one meridian);
  the V at which they meet on the retina is that meridian's far-point vergence, the refraction's
  principal power there. Measured (D, tangential / sagittal): 10°: −0.0250 / +0.1783,
  20°: −0.1319 / +0.7089, 30°: −0.4218 / +1.5776, 40°: −1.0964 / +2.7528, an oblique astigmatism of
  0.2033 / 0.8408 / 1.9995 / 3.8492 D. vissim, 1 mm entrance pupil, paraxial: 0.2033 / 0.8408 /
  1.9993 / 3.8482 D (each principal power within 0.0012 D); before this mend, over the
  entrance-pupil plane, 0.2026 / 0.8257 / 1.8952 / 3.4012 D.

visisipy 0.5 (optiland backend, 1 mm stop) prints 0.239 / 0.967 / 2.197 / 3.909 D: optiland's OPD
over the axis-centred paraxial entrance pupil, divided by the **exit** pupil's radius squared, an
image-space vergence ((3.4002 / 3.1237)² = 1.185 times the object-space one over the entrance-pupil
plane), not an oblique beam's refraction; it is not used as an oracle.
"""

import math

import numpy as np
import pytest

from vissim.optics.eyes.models import escudero_sanz_1999
from vissim.optics.eyes.refraction import (PUPIL_DEFINITION, along_chief_ray, eye_refraction,
                                           minimum_rms_prescription, paraxial_prescription, transfer_prescription)
from vissim.optics.eyes.traced_wavefront import trace_eye_wavefront
from vissim.optics.rx.prescription import Prescription

#: optiland's 543 nm indices are typed into its sample, ours come from each medium's dispersion (on axis the
#: two far points differ by 0.002 D); with the fans' O(h²) error and our order-8 fit over 1 mm, each
#: principal power agrees to 0.0012 D (measured, 40°). 0.005 D is four times that and a quarter of the
#: 0.02 D step the issue allowed; the old rule's tangential power misses by 0.017 / 0.107 / 0.455 D at 20 / 30 / 40°.
PRINCIPAL_POWER_TOL_D = 0.005
_H_MM = 0.01
_START_Z_MM = -5.0


def test_the_pupil_seen_along_the_chief_ray_divides_the_tangential_power_by_cos_squared():
    """A chief ray 40° off the optical axis in the 30° meridian; a power matrix F over the entrance-pupil plane.
    Rotated into the (tangential, sagittal) frame, the result's entries are F's ÷ (cos²θ, 1, cos θ);
    with no distance to carry it the rest is that alone."""
    theta, meridian = math.radians(40.0), math.radians(30.0)
    direction = (math.sin(theta) * math.cos(meridian), math.sin(theta) * math.sin(meridian), math.cos(theta))
    rx = Prescription(-1.25, -2.0, 70.0)
    turn = np.array([[math.cos(meridian), -math.sin(meridian)], [math.sin(meridian), math.cos(meridian)]])
    before = turn.T @ np.asarray(rx.power_matrix()) @ turn
    after = turn.T @ np.asarray(along_chief_ray(rx, direction, 0.0).power_matrix()) @ turn
    expected = before / np.array([[math.cos(theta) ** 2, math.cos(theta)], [math.cos(theta), 1.0]])
    assert after == pytest.approx(expected, abs=1e-12)


def test_the_refraction_on_the_optical_axis_is_unchanged_bit_for_bit():
    """ES1999 on its optical axis (no visual axis), 4 mm: the refraction over the pupil seen along the chief ray
    is the one over the entrance-pupil plane carried to the cornea (the rule before), to the bit."""
    front = trace_eye_wavefront(escudero_sanz_1999(), 543.0, pupil_mm=4.0, samples=33)
    refraction = eye_refraction(front, 12.0)
    distance = front.entrance_pupil_position_mm + 12.0
    for got, rule in ((refraction.paraxial, paraxial_prescription), (refraction.minimum_rms, minimum_rms_prescription)):
        assert got == transfer_prescription(rule(front.zernike_um, front.entrance_pupil_mm), distance)
    assert refraction.as_json()["pupil_definition"] == PUPIL_DEFINITION


def _optiland_trace(surface_group, starts, directions):
    """optiland's real rays from ``starts`` along ``directions`` (N, 3) through the eye: (its points on each surface
    after the object, surface-major)."""
    from optiland.rays import RealRays

    d = directions / np.linalg.norm(directions, axis=1, keepdims=True)
    rays = RealRays(starts[:, 0], starts[:, 1], starts[:, 2], d[:, 0], d[:, 1], d[:, 2], np.ones(len(d)),
                    np.full(len(d), 0.543))
    surface_group.trace(rays, skip=1)
    return np.stack([np.asarray(surface_group.x), np.asarray(surface_group.y), np.asarray(surface_group.z)], -1)


def _secant(f, x0, x1, tol):
    f0, f1 = f(x0), f(x1)
    for _ in range(40):
        if abs(f1) < tol or f1 == f0:
            return x1
        x0, f0, x1 = x1, f1, x1 - f1 * (x1 - x0) / (f1 - f0)
        f1 = f(x1)
    raise AssertionError("the secant search did not converge")


def _optiland_far_point_vergences_d(field_deg):
    """(tangential, sagittal) far-point vergences, D, where optiland's chief ray crosses the corneal-vertex plane
    (module doc): a vertical field, the beam travelling along (0, −sin θ, cos θ)."""
    from optiland.samples import NavarroWideAngleEye

    group = NavarroWideAngleEye().surfaces
    theta = math.radians(field_deg)
    u = np.array([0.0, -math.sin(theta), math.cos(theta)])
    stop = 2  # the iris: the third surface after the object
    chief_y = _secant(lambda y: _optiland_trace(group, np.array([[0.0, y, _START_Z_MM]]), u[None])[stop, 0, 1],
                      7.0 * math.tan(theta), 8.0 * math.tan(theta), 1e-13)
    vertex_crossing = np.array([0.0, chief_y, _START_Z_MM]) + u * (0.0 - _START_Z_MM) / u[2]
    vergences = []
    for across, retina_axis in ((np.array([0.0, math.cos(theta), math.sin(theta)]), 1), (np.array([1.0, 0, 0]), 0)):
        def spread(vergence_d):
            offsets = np.array([[_H_MM], [-_H_MM]]) * across
            directions = u - 1e-3 * vergence_d * offsets
            on_plane = vertex_crossing + offsets
            starts = on_plane - directions * ((on_plane[:, 2:] - _START_Z_MM) / directions[:, 2:])
            retina = _optiland_trace(group, starts, directions)[-1]
            return retina[0, retina_axis] - retina[1, retina_axis]
        vergences.append(_secant(spread, 0.0, 1.0, 1e-15))
    return tuple(vergences)


@pytest.mark.parametrize("field_deg", [10.0, 20.0, 30.0, 40.0])
def test_oblique_astigmatism_matches_optilands_tangential_and_sagittal_foci(field_deg):
    """ES1999, 543 nm, 1 mm entrance pupil, horizontal field (the eye is rotationally symmetric: optiland's is
    vertical), paraxial refraction at the corneal vertex: its principal powers (sphere, sphere + cylinder: the
    sagittal and the tangential meridian) meet optiland's far-point vergences within `PRINCIPAL_POWER_TOL_D`."""
    pytest.importorskip("optiland", reason="optiland (the `peers` extra) is the independent ray tracer here")
    tangential, sagittal = _optiland_far_point_vergences_d(field_deg)
    front = trace_eye_wavefront(escudero_sanz_1999(), 543.0, (field_deg, 0.0), pupil_mm=1.0)
    rx = eye_refraction(front).paraxial
    print(f"{field_deg:g} deg: optiland tangential {tangential:+.4f} sagittal {sagittal:+.4f} D (astigmatism "
          f"{sagittal - tangential:.4f} D); vissim {rx.format(4)} (cylinder {-rx.cylinder_diopters:.4f} D)")
    assert rx.axis_deg == pytest.approx(90.0, abs=1e-6)  # minus cylinder x 90: the horizontal meridian more myopic
    assert rx.sphere_diopters == pytest.approx(sagittal, abs=PRINCIPAL_POWER_TOL_D)
    assert rx.sphere_diopters + rx.cylinder_diopters == pytest.approx(tangential, abs=PRINCIPAL_POWER_TOL_D)
