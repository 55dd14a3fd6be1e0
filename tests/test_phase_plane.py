"""The phase plane (`vissim.optics.raytrace.phase`) and a measured eye's (`vissim.optics.eyes.measured.phase_plane`).

Oracles:
* A phase plane φ = −r² / (2 f) is a thin lens: by the grating equation a ray at height h leaves at
  sin θ = −h / f, so on the plane f beyond it it lands at h − f tan(asin(h / f)) (exact, 1e-12 mm).
* Virtual or real, the plane turns a ray the same way: a ray carried back to its own z lies on the line
  through the plane's hit point along its new direction (1e-12).
* The base eye traced through a measured eye's phase plane (the numpy exact trace and its reference-sphere
  OPD, `vissim.optics.eyes.traced_wavefront`) has the measured front over its entrance pupil: the data's
  coefficients (`measured_eye.measured_trace`), piston and tilt aside (the plane moves the chief ray, to which
  the traced front is referred).  Measured: 0.3-1.1e-3 um RMS on the axis, up to 7.9e-3 um at 30 deg in the
  most aberrated fronts (a few um of uncorrected defocus and astigmatism: the thin plane's second-order
  error).  Tolerance: lambda / 50 at 550 nm (0.011 um) everywhere, 2e-3 um on the axis.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import vissim
from vissim.errors import VissimInputError
from vissim.optics.eyes.measured.measured_eye import measured_front
from vissim.optics.eyes.measured.phase_plane import measured_phase_plane
from vissim.optics.eyes.traced_wavefront import trace_eye_wavefront
from vissim.optics.raytrace import PhasePlane, trace_rays
from vissim.optics.raytrace.phase import through_phase_plane

FOCAL_MM = 100.0


def _thin_lens(z_mm: float) -> PhasePlane:
    a = -1.0 / (2.0 * FOCAL_MM)
    return PhasePlane(z_mm, (0.0, 0.0), 1.0, ((2, 0, a), (0, 2, a)))


def test_a_quadratic_phase_plane_focuses_as_the_grating_equation_says():
    heights = np.array([0.5, 2.0, 5.0, 10.0])
    start = np.column_stack([heights, np.zeros(4), np.full(4, -10.0)])
    along = np.tile([0.0, 0.0, 1.0], (4, 1))
    bundle = trace_rays((_thin_lens(0.0),), start, along, stop_z_mm=FOCAL_MM)
    theta = np.arcsin(-heights / FOCAL_MM)
    assert np.abs(bundle.points_mm[:, 0] - (heights + FOCAL_MM * np.tan(theta))).max() < 1e-12
    assert np.abs(bundle.directions[:, 0] - np.sin(theta)).max() < 1e-15


def test_a_virtual_plane_turns_a_ray_by_the_hand_worked_gradient_and_carries_it_back():
    """φ = a u² + b u v + c v³ + e u, u = (x − 0.1) / 2, v = (y + 0.2) / 2 (mm), differentiated by hand here; rays
    in air start at z = 0, the plane stands at z = 3 (virtual: beyond where they are handed back). Oracle: the new
    direction is (d_x + ∂φ/∂x, d_y + ∂φ/∂y, +√(1 − …)); the ray handed back at z = 0 lies on the line through
    the hit point along it; the path gained is the signed lengths to the plane and back plus φ (1e-12)."""
    a, b, c, e = 1e-3, -2e-3, 5e-4, 1e-4
    rng = np.random.default_rng(3)
    points = np.column_stack([rng.uniform(-2, 2, (20, 2)), np.zeros(20)])
    d = np.column_stack([rng.uniform(-0.2, 0.2, (20, 2)), np.ones(20)])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    plane = PhasePlane(3.0, (0.1, -0.2), 2.0, ((2, 0, a), (1, 1, b), (0, 3, c), (1, 0, e)))
    moved, turned, path = through_phase_plane(plane, points, d, 1.0)
    s = 3.0 / d[:, 2]
    hit = points + s[:, None] * d
    u, v = (hit[:, 0] - 0.1) / 2.0, (hit[:, 1] + 0.2) / 2.0
    gx, gy = (2 * a * u + b * v + e) / 2.0, (b * u + 3 * c * v ** 2) / 2.0
    tx, ty = d[:, 0] + gx, d[:, 1] + gy
    wanted = np.column_stack([tx, ty, np.sqrt(1.0 - tx ** 2 - ty ** 2)])
    assert np.abs(turned - wanted).max() < 1e-12
    back = -3.0 / wanted[:, 2]
    assert np.abs(moved - (hit + back[:, None] * wanted)).max() < 1e-12
    phi = a * u ** 2 + b * u * v + c * v ** 3 + e * u
    assert np.abs(path - (s + back + phi)).max() < 1e-12


@pytest.mark.parametrize("name, field_deg", [("jaeken-artal-2012:92:right", (0.0, 0.0)),
                                             ("jaeken-artal-2012:92:right", (-20.0, 0.0)),
                                             ("jaeken-artal-2012:44:right", (30.0, 0.0)),
                                             ("polans-2015:3", (0.0, 0.0)), ("polans-2015:3", (-30.0, 0.0))])
def test_the_base_eye_through_its_phase_plane_has_the_measured_front(name, field_deg):
    eye = vissim.build_eye(name, pupil_diameter_mm=4.0)
    phase = measured_phase_plane(eye, field_deg, 550.0)
    base = trace_eye_wavefront(eye.optics, 550.0, field_deg, pupil_mm=4.0)
    wanted = measured_front(base, eye.measured, eye.optics, traced=(base,))
    seen = trace_eye_wavefront(eye.optics, 550.0, field_deg, pupil_mm=4.0, phase=phase.plane)
    inside = base.inside()
    difference = (seen.opd_um - wanted.opd_um)[inside]
    plane = np.column_stack([np.ones(inside.sum()), base.x_mm[inside], base.y_mm[inside]])
    difference -= plane @ np.linalg.lstsq(plane, difference, rcond=None)[0]
    rms = math.sqrt(np.mean(difference ** 2))
    assert rms < (2e-3 if field_deg == (0.0, 0.0) else 0.55 / 50.0)
    assert phase.fit_residual_um < 1e-5  # the polynomial holds the difference (the base eye's is smooth)


def test_a_phase_plane_needs_a_positive_radius():
    with pytest.raises(VissimInputError, match="radius"):
        PhasePlane(0.0, (0.0, 0.0), 0.0, ())
