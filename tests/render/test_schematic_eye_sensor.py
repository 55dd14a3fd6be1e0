"""The schematic-eye Mitsuba sensor: flat field, hero-wavelength weights, conservative pupil bounds,
orientation and the distortion table.  Renders are 16 x 16 px on the llvm variants (or scalar)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vissim.optics.eyes.models import eye_model
from vissim.optics.eyes.paraxial import retinal_mm_per_deg
from vissim.render.backend import find_libllvm, mitsuba

needs_llvm = pytest.mark.skipif(find_libllvm() is None, reason="no usable libLLVM: llvm variants unavailable")
SIZE = 16


def eye_sensor(model="navarro-1985", spp=64, arcmin_per_px=60.0, pixel_format="luminance", **extra):
    from vissim.optics.eyes.eye import build_eye
    from vissim.bench.eye.sensor_eyes import register_sensor_eye

    key = register_sensor_eye(build_eye(model, pupil_diameter_mm=3.0))
    return {"type": "vissim_schematic_eye", "eye_key": key, "arcmin_per_px": arcmin_per_px,
            "film": {"type": "hdrfilm", "width": SIZE, "height": SIZE, "rfilter": {"type": "box"},
                     "pixel_format": pixel_format},
            "sampler": {"type": "independent", "sample_count": spp}, **extra}


def render(mi, sensor, emitter, seed=1, spp=None):
    from vissim.render.schematic_eye_sensor import register_schematic_eye_sensor

    register_schematic_eye_sensor(mi)
    scene = mi.load_dict({"type": "scene", "integrator": {"type": "path", "max_depth": 2}, "emitter": emitter,
                          "sensor": sensor})
    return np.asarray(mi.render(scene, seed=seed, spp=spp or 0), dtype=float), scene


@needs_llvm
@pytest.mark.parametrize("model", ["navarro-1985", pytest.param("liou-brennan-1997", marks=pytest.mark.slow)])
def test_uniform_radiance_fills_the_frame_with_that_radiance(model):
    """Normalisation (module doc): a constant environment of radiance 1 gives every pixel 1.

    Per-pixel noise at 256 spp is about sqrt((1 - p)/p)/16 (p the pass fraction, 0.3-0.5): the
    image mean (256 px) is within 1.5 % of 1 and the inner and outer halves of the 16 deg field
    within 3 % of each other (4-5 sigma, plus the 0.3 % quadrature bias of the tables' Ω).
    """
    mi = mitsuba("mono")
    image, _ = render(mi, eye_sensor(model, spp=256), {"type": "constant", "radiance": 1.0})
    image = image[..., 0]
    assert abs(image.mean() - 1.0) < 0.015
    rows, cols = np.mgrid[:SIZE, :SIZE] - (SIZE - 1) / 2
    inner = np.hypot(rows, cols) < SIZE / 2 / math.sqrt(2)
    assert abs(image[inner].mean() - image[~inner].mean()) < 0.03


@needs_llvm
def test_spectral_hero_wavelength_keeps_the_films_mean():
    """White light through the dispersive eye (hero wavelength traced, the others zeroed, the hero x4)
    develops the same luminance as Mitsuba's own thinlens camera (no hero trick) in the same scene."""
    mi = mitsuba("spectral")
    emitter = {"type": "constant", "radiance": {"type": "uniform", "value": 1.0}}
    eye, _ = render(mi, eye_sensor(spp=256, pixel_format="luminance"), emitter)
    lens = {"type": "thinlens", "fov": 16.0, "aperture_radius": 1.5, "focus_distance": 1000.0,
            "film": eye_sensor(pixel_format="luminance")["film"],
            "sampler": {"type": "independent", "sample_count": 64}}
    reference, _ = render(mi, lens, emitter)
    assert abs(reference.mean() - 1.0) < 0.01  # Mitsuba: white of radiance 1 develops Y = 1
    assert abs(eye.mean() - reference.mean()) < 0.03  # hero x4 over 256 spp: ~4x the mono noise


@needs_llvm
@pytest.mark.parametrize("model, min_pass", [("navarro-1985", 0.65),
                                             pytest.param("liou-brennan-1997", 0.5, marks=pytest.mark.slow)])
def test_pupil_bounds_hold_every_ray_that_passes_the_iris(model, min_pass):
    """Rays from retinal points across a few sectors (radius bin x azimuth step) to a dense grid over the
    whole lens back, in each point's own frame: every one that gets out lands inside its sector's box
    (the bounds are conservative), and the boxes are tight enough that most samples pass."""
    mitsuba("mono")
    from drjit.llvm import Float64

    from vissim.render.schematic_eye_tables import GRID_RADIUS_MM, eye_tables
    from vissim.render.schematic_eye_trace import SchematicEyeTracer

    eye = eye_model(model)
    tables = eye_tables(eye, 3.0, 589.3, 10.0)
    tracer = SchematicEyeTracer(eye, 3.0)
    axis = np.linspace(-GRID_RADIUS_MM, GRID_RADIUS_MM, 401)  # 0.025 mm: as fine as the tables' fine grid
    a, b = (v.ravel() for v in np.meshgrid(axis, axis))
    count = len(tables.azimuths_rad)
    step = 2 * math.pi / count
    for k in (0, 7, len(tables.boxes) - 1):
        for z in sorted({0, count // 2, count - 1}):
            for r in np.linspace(tables.r_edges_mm[k], tables.r_edges_mm[k + 1], 3):
                for psi in (z + np.array([0.0, 0.4, 0.999])) * step if count > 1 else (0.0, 1.0, 2.5):
                    c, s = math.cos(psi), math.sin(psi)
                    p = tracer.retina_point(Float64(np.full(a.size, r * c)), Float64(np.full(a.size, r * s)))
                    q = tracer.surface_point(len(tracer.shapes) - 2, Float64(a * c - b * s), Float64(a * s + b * c))
                    valid = np.array(tracer.trace_out(p, tuple(qi - pi for qi, pi in zip(q, p)), 589.3).valid, bool)
                    a0, a1, b0, b1 = tables.boxes[k, z]
                    assert valid.sum() > 500
                    inside = (a[valid] >= a0) & (a[valid] <= a1) & (b[valid] >= b0) & (b[valid] <= b1)
                    assert inside.all(), (k, z, r, psi)
    assert np.all(tables.pass_fraction > min_pass)


def test_distortion_table_starts_at_the_paraxial_retinal_scale():
    """r(θ) near the axis: the paraxial chief ray's mm per degree (`optics.eyes.paraxial`) within 0.5 %."""
    from vissim.optics.eyes.retina_map import chief_ray_radii_mm

    eye = eye_model("escudero-sanz-1999")
    radii = chief_ray_radii_mm(eye, np.array([0.0, 0.5, 1.0]), 543.0)
    assert radii[0] < 1e-9
    np.testing.assert_allclose(radii[1:] / np.array([0.5, 1.0]), retinal_mm_per_deg(eye, 543.0), rtol=5e-3)


@needs_llvm
def test_a_light_to_the_observers_right_and_up_appears_right_and_up():
    """Orientation (docs/conventions.md): columns grow to the observer's right, rows grow downward.
    The camera frame's +x is the observer's left, so a light at world -x, +y is to the right and up."""
    mi = mitsuba("mono")
    light = {"type": "rectangle", "to_world": mi.ScalarTransform4f().translate([-70.0, 50.0, 1000.0])
             @ mi.ScalarTransform4f().scale(15.0) @ mi.ScalarTransform4f().rotate([0, 1, 0], 180),
             "emitter": {"type": "area", "radiance": 1.0}}
    from vissim.render.schematic_eye_sensor import register_schematic_eye_sensor

    register_schematic_eye_sensor(mi)
    scene = mi.load_dict({"type": "scene", "integrator": {"type": "path", "max_depth": 2}, "light": light,
                          "sensor": eye_sensor(spp=16)})
    image = np.asarray(mi.render(scene, seed=1), dtype=float)[..., 0]
    rows, cols = np.mgrid[:SIZE, :SIZE]
    total = image.sum()
    # the light's centre is 4.00 deg right and 2.86 deg up (atan(70/1000), atan(50/1000)); at 1 deg per px
    # and pixel centres at index + 1/2 it falls on column 8 + 4.00 - 0.5 and row 8 - 2.86 - 0.5
    assert abs((cols * image).sum() / total - 11.50) < 0.3
    assert abs((rows * image).sum() / total - 4.64) < 0.3


@needs_llvm
def test_a_distant_point_appears_at_its_chief_ray_plus_the_wavefronts_mean_slope():
    """Independent oracle: the numpy traced wavefront (`optics.eyes.traced_wavefront`, over the 3 mm entrance
    pupil, referenced to the chief ray's retinal point).  A geometric image's centroid lies off the
    chief ray by the wavefront's mean slope over the pupil (the G-tilt): for OSA Zernikes
    sum_n c(n, 1) sqrt(2 (n + 1)) / R, the tilt's and the comas' (each Z(n, 1) is 1 on the rim).
    Navarro at 5 deg, 589.3 nm: -0.500 arcmin (towards the axis); the render must put a distant disc's
    centroid there (with 0.009 arcmin of parallax) within 0.03 arcmin.  Measured, seeds 1-3: -0.498, -0.509,
    -0.503 against -0.509."""
    from vissim.optics.eyes.traced_wavefront import trace_eye_wavefront
    from vissim.units import image_colrow_to_osa_xy

    field_deg, step_arcmin, distance_mm, size = 5.0, 0.25, 1.0e5, 24
    wavefront = trace_eye_wavefront(eye_model("navarro-1985"), 589.3, (field_deg, 0.0), pupil_mm=3.0)
    radius_mm = 1.5
    g_tilt_arcmin = math.degrees(sum(c * math.sqrt(2 * (n + 1)) for (n, m), c in wavefront.zernike_um.items()
                                     if m == 1) / radius_mm * 1e-3) * 60
    assert -0.51 < g_tilt_arcmin < -0.49
    # the disc is centred at field_deg seen from the corneal vertex; the entrance pupil, 3.04 mm behind it,
    # sees it 3.04 tan(5 deg) / distance nearer the axis
    parallax_arcmin = math.degrees(3.04 * math.tan(math.radians(field_deg)) / distance_mm) * 60
    mi = mitsuba("mono")
    x = math.tan(math.radians(field_deg)) * distance_mm  # OSA x: the sensor's local +x
    light = {"type": "disk", "to_world": mi.ScalarTransform4f().translate([x, 0.0, distance_mm])
             @ mi.ScalarTransform4f().scale(20.0) @ mi.ScalarTransform4f().rotate([0, 1, 0], 180),
             "emitter": {"type": "area", "radiance": 1.0}}
    sensor = eye_sensor(spp=256, arcmin_per_px=step_arcmin, field_x_deg=field_deg)
    sensor["film"].update(width=size, height=size)
    from vissim.render.schematic_eye_sensor import register_schematic_eye_sensor

    register_schematic_eye_sensor(mi)
    scene = mi.load_dict({"type": "scene", "integrator": {"type": "path", "max_depth": 2}, "light": light,
                          "sensor": sensor})
    image = np.asarray(mi.render(scene, seed=1), dtype=float)[..., 0]
    cols = np.arange(size)[None, :]
    centroid_col_arcmin = ((cols * image).sum() / image.sum() - (size - 1) / 2) * step_arcmin
    centroid_x_arcmin = image_colrow_to_osa_xy(centroid_col_arcmin, 0.0)[0]  # columns run to the observer's right
    assert abs(centroid_x_arcmin - (g_tilt_arcmin - parallax_arcmin)) < 0.03


@needs_llvm  # the tables are traced on Dr.Jit's LLVM backend whatever the render's variant
def test_scalar_variant_renders_the_same_flat_field():
    """scalar_rgb calls the sensor with Python numbers, one sample at a time: same code, same normalisation.
    8 x 8 px x 16 spp: the mean's noise is about 0.03; within 0.1 of 1."""
    mi = mitsuba("rgb", "scalar_rgb")
    sensor = eye_sensor(spp=16, pixel_format="rgb")
    sensor["film"].update(width=8, height=8)
    image, _ = render(mi, sensor, {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}})
    assert mi.variant() == "scalar_rgb"
    assert abs(image.mean() - 1.0) < 0.1


@needs_llvm
@pytest.mark.parametrize("wavelength_nm", [450.0, 650.0])
def test_monochromatic_spectral_render_of_white_gives_its_radiance(wavelength_nm):
    """wavelength_nm in a spectral variant: every wavelength that one, the film's ȳ(λ) response divided
    out, so white of radiance 1 develops 1 (8 x 8 px x 256 spp: noise of the mean about 0.005)."""
    mi = mitsuba("spectral")
    sensor = eye_sensor(spp=256, wavelength_nm=wavelength_nm)
    sensor["film"].update(width=8, height=8)
    image, _ = render(mi, sensor, {"type": "constant", "radiance": {"type": "uniform", "value": 1.0}})
    assert abs(image.mean() - 1.0) < 0.02


@needs_llvm
@pytest.mark.parametrize("model", ["navarro-1985", pytest.param("liou-brennan-1997", marks=pytest.mark.slow)])
def test_a_pixel_looks_along_the_direction_the_trace_gives_its_field_angle(model):
    """The sensor's Dr.Jit copy of the field-angle rule equals `traced_wavefront.field_direction` (the numpy
    original: (tan x, tan y, 1), from Liou-Brennan's visual axis), within float32 round-off (2e-7)."""
    from vissim.optics.eyes.traced_wavefront import field_direction
    from vissim.render.schematic_eye_sensor import register_schematic_eye_sensor

    mi = mitsuba("mono")
    register_schematic_eye_sensor(mi)
    sensor = mi.load_dict(eye_sensor(model, spp=1))
    fields = [(0.0, 0.0), (10.0, 0.0), (-20.0, 15.0), (3.0, -30.0)]
    got = sensor._direction(mi.Float([f[0] for f in fields]), mi.Float([f[1] for f in fields]))
    got = np.stack([np.asarray(c, dtype=float) for c in got], axis=1)
    expected = np.array([field_direction(eye_model(model), f) for f in fields])
    np.testing.assert_allclose(got, expected, atol=2e-7)
