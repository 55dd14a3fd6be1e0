"""The Dr.Jit retina-outward trace of a schematic eye against the numpy exact tracer (separate code).

Oracle: `vissim.optics.raytrace.trace_rays` (numpy, float64) traces rays from a plane 3 mm in
front of the cornea into the eye onto the retina; the Dr.Jit trace starts from those retinal
points with the reversed directions and must come back out along the same rays (reversibility of
Snell's law and of the ray equation).  Tolerances: positions 1e-9 mm and directions 1e-10 for
homogeneous eyes (both sides exact to rounding: 1e-15 measured); the GRIN lens is integrated by
RK4 from opposite ends by the two tracers (O(h^4) each: 3e-12 mm measured), same limits.
float32 (a render's arrays): positions within 1e-5 mm, directions within 1e-6 (1.7e-6 and 2.4e-7
measured through the GRIN lens).
"""

from __future__ import annotations

import numpy as np
import pytest

from vissim.optics.eyes.models import eye_model
from vissim.optics.eyes.surfaces import eye_surfaces
from vissim.optics.raytrace import trace_rays
from vissim.render.backend import find_libllvm, mitsuba

needs_llvm = pytest.mark.skipif(find_libllvm() is None, reason="no usable libLLVM: llvm arrays unavailable")
START_Z_MM = -3.0


def inward_rays(count: int, field_deg: float, pupil_mm: float, seed: int = 1):
    """Random rays on the plane START_Z_MM: positions within the pupil, directions within +-field."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform(-0.5 * pupil_mm, 0.5 * pupil_mm, (count, 2))
    tangents = np.tan(np.radians(rng.uniform(-field_deg, field_deg, (count, 2))))
    d = np.concatenate([tangents, np.ones((count, 1))], axis=1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.concatenate([xy, np.full((count, 1), START_Z_MM)], axis=1), d


def traced_out(eye, points, directions, wavelength, array_type, iris_mm=None, phase=None):
    from vissim.render.schematic_eye_trace import SchematicEyeTracer

    tracer = SchematicEyeTracer(eye, iris_mm, phase=phase)
    p = tuple(array_type(points[:, i]) for i in range(3))
    d = tuple(array_type(-directions[:, i]) for i in range(3))
    result = tracer.trace_out(p, d, wavelength)
    out_p = np.stack([np.array(v, dtype=float) for v in result.points], axis=1)
    out_d = np.stack([np.array(v, dtype=float) for v in result.directions], axis=1)
    s = (START_Z_MM - out_p[:, 2]) / out_d[:, 2]
    return out_p + s[:, None] * out_d, out_d, np.array(result.valid, bool), np.array(result.stopped, bool)


@needs_llvm
@pytest.mark.parametrize("model, wavelength_nm, field_deg, per_ray_wavelength", [
    *[(m, w, f, r) for m in ("navarro-1985",) for w in (450.0, 632.8) for f in (0.0, 25.0) for r in (False, True)],
    ("liou-brennan-1997", 450.0, 25.0, True),
    *[pytest.param("liou-brennan-1997", w, f, r, marks=pytest.mark.slow)
      for w in (450.0, 632.8) for f in (0.0, 25.0) for r in (False, True) if (w, f, r) != (450.0, 25.0, True)],
])
def test_retina_outward_trace_reverses_the_numpy_trace(model, wavelength_nm, field_deg, per_ray_wavelength):
    mitsuba("mono")
    from drjit.llvm import Float64

    eye = eye_model(model)
    start, d = inward_rays(40, field_deg, 3.0)
    bundle = trace_rays(eye_surfaces(eye), start, d, stop_z_mm=None, wavelength_nm=wavelength_nm)
    wavelength = Float64(np.full(40, wavelength_nm)) if per_ray_wavelength else wavelength_nm
    back, back_d, valid, stopped = traced_out(eye, bundle.points_mm, bundle.directions, wavelength, Float64)
    assert valid.all() and not stopped.any()
    assert np.abs(back - start).max() < 1e-9
    assert np.abs(back_d + d).max() < 1e-10


@needs_llvm
@pytest.mark.parametrize("field_deg", [0.0, 25.0])
def test_a_measured_eyes_phase_plane_reverses_the_numpy_trace(field_deg):
    """The phase plane (virtual, at the entrance pupil) crossed last on the way out, first on the way in."""
    mitsuba("mono")
    from drjit.llvm import Float64

    from vissim.optics.eyes.eye import build_eye
    from vissim.optics.eyes.measured.phase_plane import measured_phase_plane

    measured = build_eye("jaeken-artal-2012:92:right", pupil_diameter_mm=4.0)
    plane = measured_phase_plane(measured, (-20.0, 0.0), 550.0).plane
    eye = measured.optics
    start, d = inward_rays(40, field_deg, 3.0)
    bundle = trace_rays((plane,) + eye_surfaces(eye), start, d, stop_z_mm=None, wavelength_nm=550.0)
    back, back_d, valid, _ = traced_out(eye, bundle.points_mm, bundle.directions, 550.0, Float64, phase=plane)
    assert valid.all()
    assert np.abs(back - start).max() < 1e-9
    assert np.abs(back_d + d).max() < 1e-10


@needs_llvm
def test_float32_trace_is_within_render_tolerance():
    mitsuba("mono")
    from drjit.llvm import Float

    eye = eye_model("liou-brennan-1997")
    start, d = inward_rays(40, 20.0, 3.0)
    bundle = trace_rays(eye_surfaces(eye), start, d, stop_z_mm=None, wavelength_nm=555.0)
    back, back_d, valid, _ = traced_out(eye, bundle.points_mm, bundle.directions, 555.0, Float)
    assert valid.all()
    assert np.abs(back - start).max() < 1e-5
    assert np.abs(back_d + d).max() < 1e-6


@needs_llvm
@pytest.mark.parametrize("model", ["navarro-1985", "liou-brennan-1997"])
def test_iris_stops_exactly_the_rays_outside_it(model):
    """The numpy trace to the iris plane says which rays cross it outside the (decentred) iris."""
    mitsuba("mono")
    from drjit.llvm import Float64

    eye, iris_mm = eye_model(model), 3.0
    start, d = inward_rays(200, 5.0, 5.0, seed=4)
    surfaces = eye_surfaces(eye)
    at_iris = trace_rays(surfaces[:eye.stop_index], start, d, stop_z_mm=surfaces[eye.stop_index].vertex_z_mm,
                         wavelength_nm=555.0)
    outside = np.hypot(at_iris.points_mm[:, 0] - eye.stop_decentre_nasal_mm, at_iris.points_mm[:, 1]) > 0.5 * iris_mm
    assert 20 < outside.sum() < 180  # both kinds present
    bundle = trace_rays(surfaces, start, d, stop_z_mm=None, wavelength_nm=555.0)
    _, _, valid, stopped = traced_out(eye, bundle.points_mm, bundle.directions, 555.0, Float64, iris_mm)
    np.testing.assert_array_equal(stopped, outside)
    np.testing.assert_array_equal(valid, ~outside)


@needs_llvm
def test_rays_that_miss_or_reflect_totally_are_dropped():
    """A ray from the retina's rim at a grazing angle cannot leave the eye; axial rays all do."""
    mitsuba("mono")
    from drjit.llvm import Float64

    from vissim.render.schematic_eye_trace import SchematicEyeTracer

    tracer = SchematicEyeTracer(eye_model("navarro-1985"), None)
    p = tracer.retina_point(Float64([0.0, 0.0]), Float64([0.0, 0.0]))
    result = tracer.trace_out(p, (Float64([0.0, 0.95]), Float64([0.0, 0.0]), Float64([-1.0, -0.3])), 589.3)
    assert np.array(result.valid).tolist() == [True, False]


def test_scalar_numbers_trace_as_arrays_do():
    """Python floats (Mitsuba's scalar variants) follow the same code: one GRIN ray against numpy."""
    from vissim.render.schematic_eye_trace import SchematicEyeTracer

    eye = eye_model("liou-brennan-1997")
    start, d = inward_rays(1, 15.0, 3.0, seed=7)
    bundle = trace_rays(eye_surfaces(eye), start, d, stop_z_mm=None, wavelength_nm=600.0)
    result = SchematicEyeTracer(eye, None).trace_out(tuple(map(float, bundle.points_mm[0])),
                                                                tuple(map(float, -bundle.directions[0])), 600.0)
    out_p, out_d = np.array(result.points), np.array(result.directions)
    assert result.valid is True or bool(result.valid)
    back = out_p + (START_Z_MM - out_p[2]) / out_d[2] * out_d
    assert np.abs(back - start[0]).max() < 1e-9
    assert np.abs(out_d + d[0]).max() < 1e-10


@needs_llvm
def test_toric_cornea_biconic_reverses_the_numpy_trace():
    """A biconic surface: the cornea front of an eye with -1.00 -2.00 x 30 (`optics.eyes.ametropia`),
    its two radii along TABO 30 and 120 deg; both tracers' Newton iterations to rounding."""
    mitsuba("mono")
    from drjit.llvm import Float64

    from vissim.optics.eyes.fixation import ametropic_eye
    from vissim.optics.rx.prescription import Prescription

    eye = ametropic_eye(eye_model("navarro-1985"), Prescription.parse("-1.00 -2.00 x 30"))
    assert eye.surfaces[0].is_toric
    start, d = inward_rays(40, 20.0, 4.0, seed=3)
    bundle = trace_rays(eye_surfaces(eye), start, d, stop_z_mm=None, wavelength_nm=555.0)
    back, back_d, valid, _ = traced_out(eye, bundle.points_mm, bundle.directions, 555.0, Float64)
    assert valid.all()
    assert np.abs(back - start).max() < 1e-9
    assert np.abs(back_d + d).max() < 1e-10
