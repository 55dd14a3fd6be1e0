"""The exact real-ray trace (`vissim.optics.raytrace`): surfaces, media, GRIN, aiming.

Oracles, none sharing code with the tracer:

* Snell's law at a plane, written out (n1 sin i = n2 sin t, the transverse direction scaled);
* the aplanatic points of a refracting sphere (Born & Wolf, Principles of Optics): rays
  converging on the point (n2/n1) R beyond the centre meet exactly at (n1/n2) R beyond it, every
  optical path from a sphere around the first point being the same;
* the Cartesian ellipsoid (Q = -(n1/n2)^2, the Cartesian oval of a point at infinity): a collimated beam focuses
  perfectly at n2 R / (n2 - n1) from the vertex;
* the skew invariant n (x d_y - y d_x) of a rotationally symmetric system (Welford, Aberrations of
  Optical Systems), conserved through surfaces and a GRIN medium alike;
* a plane wave through flat surfaces stays plane: its path to a plane is linear in position;
* a wave focused dz before the reference point: W = n' dz (1 - cos u) to first order in dz,
  and exactly n' (tau - tau_chief), tau the distance from the focus back to the sphere;
* a medium with a linear axial gradient n = a0 + a1 z: the invariant beta = n sin(theta) gives the
  path and the optical path in closed form (x = (beta/a1) ln(n + sqrt(n^2 - beta^2)) + c).
  Its small-angle limit is the textbook circular arc; the closed form is exact.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from vissim.errors import VissimInputError
from vissim.optics.raytrace import (Biconic, Conic, GradientIndex, Plane, Surface, aim_collimated, aim_rays, trace_rays,
                                    wavefront_on_reference_sphere_um)


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _distance_to_lines(points, directions, target):
    rel = target - points
    return np.linalg.norm(rel - np.sum(rel * directions, axis=1, keepdims=True) * directions, axis=1)


# ------------------------------------------------------------------ homogeneous surfaces


def test_snell_at_a_flat_surface_holds_exactly_at_every_wavelength():
    incidence = np.radians(np.array([0.0, 5.0, 20.0, 45.0, 70.0]))
    azimuth = np.radians(np.array([0.0, 30.0, 100.0, 200.0, 315.0]))
    d = np.stack([np.sin(incidence) * np.cos(azimuth), np.sin(incidence) * np.sin(azimuth), np.cos(incidence)], 1)
    starts = np.tile([0.3, -0.2, -10.0], (len(d), 1))
    for wavelength_nm, n2 in ((450.0, 1.53), (650.0, 1.51)):
        glass = Surface(Plane(), 0.0, lambda w: 1.53 if w < 500.0 else 1.51, name="window")
        bundle = trace_rays((glass,), starts, d, 5.0, wavelength_nm=wavelength_nm)
        sin_t = np.sin(incidence) / n2
        expected = np.concatenate([d[:, :2] / n2, np.sqrt(1.0 - sin_t**2)[:, None]], axis=1)
        assert np.abs(bundle.directions - expected).max() < 4e-16
        cos_i, cos_t = np.cos(incidence), np.sqrt(1.0 - sin_t**2)
        assert bundle.opl_mm == pytest.approx(10.0 / cos_i + n2 * 5.0 / cos_t, rel=1e-15, abs=0)


def test_rays_aimed_at_a_spheres_aplanatic_point_image_stigmatically():
    radius, n1, n2 = 10.0, 1.0, 1.5
    sphere = Surface(Conic(radius), 0.0, n2, name="sphere")
    centre = np.array([0.0, 0.0, radius])
    virtual_object = centre + np.array([0.0, 0.0, n2 / n1 * radius])  # z = 25
    image = centre + np.array([0.0, 0.0, n1 / n2 * radius])  # z = 16.67
    rng = np.random.default_rng(3)
    vertex_plane_xy = rng.uniform(-6.0, 6.0, (40, 2))
    d = _unit(virtual_object - np.concatenate([vertex_plane_xy, np.zeros((40, 1))], axis=1))
    starts = virtual_object - 45.0 * d  # on a sphere of 45 mm around the virtual object
    bundle = trace_rays((sphere,), starts, d, 30.0)
    assert _distance_to_lines(bundle.points_mm, bundle.directions, image).max() < 1e-12
    # OPL to the image point: n1 45 - n1 |P - hit| + n2 |hit - P'|, and n2 |hit - P'| = n1 |hit - P| for
    # every point of the sphere, so every path is 45 mm (the axial ray: n2 16.67 - n1 25 = 0).
    opl = bundle.opl_mm - n2 * np.sum((bundle.points_mm - image) * bundle.directions, axis=1)
    assert np.abs(opl - 45.0).max() < 1e-11


def test_the_cartesian_ellipsoid_focuses_a_collimated_beam_perfectly():
    radius, n1, n2 = 10.0, 1.0, 1.5
    ellipsoid = Surface(Conic(radius, -(n1 / n2) ** 2), 0.0, n2, name="ellipsoid")
    focus = np.array([0.0, 0.0, n2 * radius / (n2 - n1)])  # 30 mm
    x, y = np.meshgrid(np.linspace(-6.0, 6.0, 13), np.linspace(-6.0, 6.0, 13))
    keep = np.hypot(x, y) <= 6.0
    starts = np.stack([x[keep], y[keep], np.full(keep.sum(), -5.0)], axis=1)
    bundle = trace_rays((ellipsoid,), starts, np.tile([0.0, 0.0, 1.0], (len(starts), 1)), 40.0)
    assert _distance_to_lines(bundle.points_mm, bundle.directions, focus).max() < 1e-9
    opd = bundle.opl_mm - n2 * np.sum((bundle.points_mm - focus) * bundle.directions, axis=1) - (5.0 * n1 + 30.0 * n2)
    assert np.abs(opd).max() < 1e-9  # mm
    # A sphere of the same vertex radius is not stigmatic: the ellipsoid's zero is the conic's doing.
    sphere = trace_rays((Surface(Conic(radius), 0.0, n2),), starts, np.tile([0.0, 0.0, 1.0], (len(starts), 1)), 40.0)
    assert _distance_to_lines(sphere.points_mm, sphere.directions, focus).max() > 1e-2


def test_a_biconic_with_equal_meridians_is_the_conic_and_its_gradient_is_the_sags_slope():
    rng = np.random.default_rng(7)
    xy = rng.uniform(-4.0, 4.0, (200, 2))
    conic, biconic = Conic(7.72, -0.26), Biconic(7.72, 7.72, -0.26, -0.26, axis_deg=37.0)
    assert np.abs(biconic.sag_mm(xy) - conic.sag_mm(xy)).max() < 1e-15
    assert np.abs(biconic.sag_gradient(xy) - conic.sag_gradient(xy)).max() < 1e-15
    toric = Biconic(7.6, 7.9, -0.3, -0.1, axis_deg=25.0)
    h = 1e-6
    for shape in (conic, toric):
        fd = np.stack([(shape.sag_mm(xy + [h, 0]) - shape.sag_mm(xy - [h, 0])) / (2 * h),
                       (shape.sag_mm(xy + [0, h]) - shape.sag_mm(xy - [0, h])) / (2 * h)], axis=1)
        assert np.abs(shape.sag_gradient(xy) - fd).max() < 1e-8
    # Along its own x' meridian (25 deg) the biconic is the conic of radius Rx and constant Qx.
    t = np.linspace(-4.0, 4.0, 9)
    meridian = np.stack([t * math.cos(math.radians(25.0)), t * math.sin(math.radians(25.0))], axis=1)
    assert np.abs(toric.sag_mm(meridian) - Conic(7.6, -0.3).sag_mm(np.stack([t, 0 * t], 1))).max() < 1e-14
    starts = np.concatenate([rng.uniform(-3.0, 3.0, (50, 2)), np.full((50, 1), -5.0)], axis=1)
    d = _unit(np.concatenate([rng.uniform(-0.2, 0.2, (50, 2)), np.ones((50, 1))], axis=1))
    a, b = (trace_rays((Surface(s, 0.0, 1.376),), starts, d, 3.0) for s in (conic, biconic))
    assert np.abs(a.points_mm - b.points_mm).max() < 1e-13 and np.abs(a.opl_mm - b.opl_mm).max() < 1e-13


def test_rays_end_on_a_curved_retina():
    retina = Surface(Conic(-12.0), 20.0, 1.336, name="retina")
    # The last ray, at 60 deg from z = 10, crosses the vertex plane 17 mm off axis, beyond the sphere.
    starts = np.array([[0.0, 0.0, 0.0], [1.0, -2.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 10.0]])
    d = _unit([[0.0, 0.0, 1.0], [0.1, 0.2, 1.0], [0.35, -0.3, 1.0], [math.sqrt(3.0), 0.0, 1.0]])
    bundle = trace_rays((retina,), starts, d, None, index_before=1.336)
    centre = np.array([0.0, 0.0, 8.0])
    assert np.abs(np.linalg.norm(bundle.points_mm - centre, axis=1) - 12.0).max() < 1e-12
    assert bundle.opl_mm == pytest.approx(1.336 * np.linalg.norm(bundle.points_mm - starts, axis=1), rel=1e-15)


def test_aiming_lands_rays_on_a_stop_inside_the_glass_in_the_eyes_frame():
    surfaces = (Surface(Conic(7.72, -0.26), 0.0, 1.376, name="cornea"),)
    targets = np.array([[0.0, 0.0], [1.5, 0.0], [-1.0, 1.2], [0.4, -1.9]])
    bundle, launch = aim_rays(surfaces, [5.0, -3.0, -200.0], targets, 3.0)
    assert np.abs(bundle.points_mm[:, :2] - targets).max() < 1e-9
    assert np.all(launch[:, 2] > 0.0) and bundle.final_index == 1.376


def test_a_collimated_beam_is_aimed_onto_a_stop_and_stays_a_plane_wave_through_flat_surfaces():
    surfaces = (Surface(Plane(), 0.0, 1.376, name="front"), Surface(Plane(), 0.55, 1.336, name="back"))
    direction = [math.sin(math.radians(40.0)), 0.2, math.cos(math.radians(40.0))]  # 40 deg and a little y
    rng = np.random.default_rng(5)
    targets = rng.uniform(-2.0, 2.0, (30, 2))
    bundle, starts = aim_collimated(surfaces, direction, targets, 3.6, -2.0, index_before=1.0)
    assert np.abs(bundle.points_mm[:, :2] - targets).max() < 1e-9 and np.all(starts[:, 2] == -2.0)
    # The refracted plane wave: L(q) = L0 + n' q . d' on the stop plane (d' the common direction).
    d_out = bundle.directions[0]
    assert np.abs(bundle.directions - d_out).max() < 1e-14
    predicted = 1.336 * targets @ d_out[:2]
    assert np.abs((bundle.opl_mm - predicted) - (bundle.opl_mm - predicted).mean()).max() < 1e-12


def test_aiming_a_collimated_beam_through_a_cornea_at_forty_degrees_lands_on_the_iris_grid():
    cornea = (Surface(Conic(7.72, -0.26), 0.0, 1.3771, name="cornea front"),
              Surface(Conic(6.50), 0.55, 1.3374, name="cornea back"))
    axis = np.linspace(-1.5, 1.5, 7)
    x, y = np.meshgrid(axis, axis)
    targets = np.stack([x.ravel(), y.ravel()], axis=1)
    for field in ((40.0, 0.0), (0.0, -40.0), (28.0, 28.0)):
        tx, ty = (math.tan(math.radians(v)) for v in field)
        bundle, _ = aim_collimated(cornea, [tx, ty, 1.0], targets, 3.6, -5.0)
        assert np.abs(bundle.points_mm[:, :2] - targets).max() < 1e-9


def _focused_beam(defocus_mm):
    """The Cartesian ellipsoid's perfect focus (z = 30), traced to a flat 'retina' defocus_mm beyond it."""
    n2 = 1.5
    surfaces = (Surface(Conic(10.0, -(1.0 / n2) ** 2), 0.0, n2, name="ellipsoid"),
                Surface(Plane(), 30.0 + defocus_mm, n2, name="retina"))
    rho = np.linspace(0.0, 5.0, 11)
    starts = np.stack([rho * 0.6, rho * 0.8, np.full(11, -5.0)], axis=1)
    bundle = trace_rays(surfaces, starts, np.tile([0.0, 0.0, 1.0], (11, 1)), None)
    return bundle, n2


def test_the_wavefront_on_the_reference_sphere_is_zero_for_a_perfect_focus_and_defocus_for_a_shifted_one():
    bundle, _ = _focused_beam(0.0)
    assert np.abs(wavefront_on_reference_sphere_um(bundle, 0, 0.0)).max() < 1e-6  # µm
    dz = 1e-3  # the retina 1 µm beyond the focus: the wave focuses before it (myopic), W > 0 at the rim
    bundle, n2 = _focused_beam(dz)
    w_um = wavefront_on_reference_sphere_um(bundle, 0, 0.0)
    focus = np.array([0.0, 0.0, 30.0])
    u = -bundle.directions  # from the focus back towards the pupil
    cos_u = bundle.directions[:, 2]
    assert w_um[-1] > 0.0
    assert w_um == pytest.approx(1000.0 * n2 * dz * (1.0 - cos_u), rel=1e-4, abs=1e-9)
    centre = np.array([0.0, 0.0, 30.0 + dz])
    rho = 30.0 + dz  # the reference sphere passes through the exit pupil's centre, the vertex
    a = focus - centre
    ua = np.einsum("ij,j->i", u, a)  # |focus + tau u - centre| = rho, the root in front of the focus
    tau = -ua + np.sqrt(ua**2 - a @ a + rho**2)
    assert np.abs(w_um - 1000.0 * n2 * (tau - tau[0])).max() < 1e-6


def test_the_trace_reproduces_optilands_published_navarro_sample():
    # Issue 26's must-show, here as a check of the tracer and its aiming: the wide-angle Navarro eye
    # (Escudero-Sanz & Navarro 1999; the table of /work/shared/reference/schematic-eyes.md, written out
    # here; the model itself lives with the eye models) with 543 nm indices (visisipy's table) and a
    # 3 mm stop at the lens front: optiland PR #247 gives f' = 22.029 mm, the entrance pupil 3.04010 mm
    # behind the cornea and 3.40022 mm across (paraxial), each to be met within 0.1 %.
    # Measured: 22.02912, 3.040096, 3.400218.
    n_cornea, n_aqueous, n_lens, n_vitreous = 1.3777, 1.3391, 1.4222, 1.3377
    cornea = (Surface(Conic(7.72, -0.26), 0.0, n_cornea, name="cornea front"),
              Surface(Conic(6.50), 0.55, n_aqueous, name="cornea back"))
    lens = (Surface(Conic(10.2, -3.1316), 3.60, n_lens, name="lens front"),
            Surface(Conic(-6.0, -1.0), 7.60, n_vitreous, name="lens back"))
    h = 1e-4  # near the axis: real rays in the paraxial limit
    ray = trace_rays(cornea + lens, [[h, 0.0, -1.0]], [[0.0, 0.0, 1.0]], 30.0)
    assert h / -(ray.directions[0, 0] / ray.directions[0, 2]) == pytest.approx(22.029, rel=1e-3)
    _, marginal = aim_collimated(cornea, [0.0, 0.0, 1.0], [[h, 0.0]], 3.60, -1.0)
    assert 3.0 * marginal[0, 0] / h == pytest.approx(3.40022, rel=1e-3)
    slope = 1e-5
    _, chief = aim_collimated(cornea, [slope, 0.0, 1.0], [[0.0, 0.0]], 3.60, -1.0)
    assert -1.0 - chief[0, 0] / slope == pytest.approx(3.04010, rel=1e-3)


# ------------------------------------------------------------------ bad input


def test_a_ray_missing_a_surface_or_reflected_totally_names_the_surface():
    small = Surface(Conic(2.0), 0.0, 1.5, name="small sphere")
    with pytest.raises(VissimInputError, match="(misses|rays? miss) the small sphere"):
        trace_rays((small,), [[3.0, 0.0, -1.0]], [[0.0, 0.0, 1.0]], 5.0)
    exit_face = Surface(Plane(), 0.0, 1.0, name="glass-air face")
    with pytest.raises(VissimInputError, match="total internal reflection of 1 ray.* glass-air face"):
        trace_rays((exit_face,), [[0.0, 0.0, -1.0], [0.0, 0.0, -1.0]], _unit([[0.0, 0.0, 1.0], [1.0, 0.0, 1.0]]),
                   2.0, index_before=1.5)
    with pytest.raises(VissimInputError, match="clear aperture of the stop"):
        trace_rays((Surface(Plane(), 0.0, 1.0, 1.0, "stop"),), [[1.5, 0.0, -1.0]], [[0.0, 0.0, 1.0]], 2.0)
    with pytest.raises(VissimInputError, match="dispersive"):
        trace_rays((Surface(Plane(), 0.0, lambda w: 1.5),), [[0.0, 0.0, -1.0]], [[0.0, 0.0, 1.0]], 2.0)


def test_a_grin_ray_that_leaves_the_lens_is_refused():
    diverging = GradientIndex(1.4, b_per_mm2=0.05, name="lens core")  # n grows outward: rays bend out
    surfaces = (Surface(Plane(), 0.0, diverging, name="front"), Surface(Plane(), 20.0, 1.336, 3.0, "back"))
    with pytest.raises(VissimInputError, match="lens core .* back .*leave the lens"):
        trace_rays(surfaces, [[1.0, 0.0, -1.0]], [[0.0, 0.0, 1.0]], 25.0)


# ------------------------------------------------------------------ gradient index


def _lens(medium, after=1.336):
    return (Surface(Conic(10.2, -3.1316), 0.0, medium, 5.0, "lens front"),
            Surface(Conic(-6.0, -1.0), 4.0, after, 5.0, "lens back"))


def _fan(count=25, seed=11):
    rng = np.random.default_rng(seed)
    starts = np.concatenate([rng.uniform(-2.5, 2.5, (count, 2)), np.full((count, 1), -3.0)], axis=1)
    return starts, _unit(np.concatenate([rng.uniform(-0.15, 0.15, (count, 2)), np.ones((count, 1))], axis=1))


def test_a_grin_without_gradient_is_the_straight_trace():
    starts, d = _fan()
    straight = trace_rays(_lens(1.42), starts, d, 10.0, index_before=1.336)
    for step in (0.05, 0.37):
        grin = trace_rays(_lens(GradientIndex(1.42, step_mm=step)), starts, d, 10.0, index_before=1.336)
        assert np.abs(grin.points_mm - straight.points_mm).max() < 1e-12
        assert np.abs(grin.opl_mm - straight.opl_mm).max() < 1e-12
        assert np.abs(grin.directions - straight.directions).max() < 1e-13


def _linear_slab(a0, a1, thickness, step_mm):
    medium = GradientIndex(a0, a1_per_mm=a1, step_mm=step_mm, name="slab")
    return (Surface(Plane(), 0.0, medium, name="slab entrance"), Surface(Plane(), thickness, 1.0, name="slab exit"))


def _linear_slab_oracle(a0, a1, thickness, sin_in):
    """Exit height and OPL inside n = a0 + a1 z for a ray entering from air at sin_in (beta = sin_in)."""
    beta = sin_in
    n0, n1 = a0, a0 + a1 * thickness

    def log_term(n):
        return math.log(n + math.sqrt(n * n - beta * beta))

    def path_term(n):
        root = math.sqrt(n * n - beta * beta)
        return 0.5 * n * root + 0.5 * beta * beta * math.log(n + root)

    return beta / a1 * (log_term(n1) - log_term(n0)), (path_term(n1) - path_term(n0)) / a1


@pytest.mark.parametrize("a1", [0.06, -0.05])
def test_a_linear_gradient_slab_bends_rays_along_the_closed_form_path(a1):
    a0, thickness = 1.5, 4.0
    angles = np.radians([0.0, 10.0, 35.0, 60.0])
    d = np.stack([np.sin(angles), np.zeros(4), np.cos(angles)], axis=1)
    bundle = trace_rays(_linear_slab(a0, a1, thickness, 0.01), np.zeros((4, 3)), d, None)
    for ray, angle in enumerate(angles):
        x_exit, opl_inside = _linear_slab_oracle(a0, a1, thickness, math.sin(angle))
        assert bundle.points_mm[ray, 0] == pytest.approx(x_exit, abs=1e-11)
        assert bundle.opl_mm[ray] == pytest.approx(opl_inside, abs=1e-11)
        assert bundle.directions[ray, 0] == pytest.approx(math.sin(angle), abs=1e-13)  # beta leaves into air


def test_grin_optical_path_error_falls_as_the_fourth_power_of_the_step(capsys):
    a0, a1, thickness, angle = 1.5, 0.06, 4.0, math.radians(35.0)
    _, exact = _linear_slab_oracle(a0, a1, thickness, math.sin(angle))
    d = [[math.sin(angle), 0.0, math.cos(angle)]]
    steps = (0.4, 0.2, 0.1, 0.05)
    errors = [abs(trace_rays(_linear_slab(a0, a1, thickness, h), np.zeros((1, 3)), d, None).opl_mm[0] - exact)
              for h in steps]
    ratios = [errors[i] / errors[i + 1] for i in range(len(errors) - 1)]
    with capsys.disabled():
        print("\nGRIN step-halving (linear slab n = 1.5 + 0.06 z, 4 mm, 35 deg): h mm, |OPL error| mm, ratio")
        for i, (h, e) in enumerate(zip(steps, errors)):
            print(f"  {h:6.3f}  {e:.3e}  {'' if i == 0 else f'{ratios[i - 1]:.2f}'}")
    assert all(12.0 < r < 20.0 for r in ratios)  # 2^4 = 16
    assert errors[-1] < 1e-9


def _human_like_grin_lens(step_mm):
    """A lens shaped like Liou & Brennan's (1997; the reference page's recalled table): two GRIN halves."""
    front = GradientIndex(1.368, 0.049057, -0.015427, -0.001978, 0.0, step_mm, "front GRIN")
    back = GradientIndex(1.407, 0.0, -0.006605, -0.001978, 1.59, step_mm, "back GRIN")
    return (Surface(Conic(12.40, -0.94), 0.0, front, 4.5, "lens front"),
            Surface(Plane(), 1.59, back, 4.5, "equatorial plane"),
            Surface(Conic(-8.10, 0.96), 4.02, 1.336, 4.5, "lens back"))


def test_grin_lens_step_halving_and_the_skew_invariant(capsys):
    starts = np.array([[1.0, 0.5, -1.0], [2.0, -1.0, -1.0], [0.0, 2.5, -1.0]])
    d = _unit([[0.05, 0.1, 1.0], [-0.1, 0.08, 1.0], [0.0, -0.05, 1.0]])  # skew rays
    steps = (0.4, 0.2, 0.1, 0.05, 0.025)
    runs = [trace_rays(_human_like_grin_lens(h), starts, d, 6.0, index_before=1.336) for h in steps]
    reference = trace_rays(_human_like_grin_lens(0.003125), starts, d, 6.0, index_before=1.336)
    errors = [np.abs(r.opl_mm - reference.opl_mm).max() for r in runs]
    with capsys.disabled():
        print("\nGRIN step-halving (Liou-Brennan-like lens, 3 skew rays; reference h = 0.003125): h mm, "
              "max |OPL error| mm, ratio")
        for i, (h, e) in enumerate(zip(steps, errors)):
            print(f"  {h:6.3f}  {e:.3e}  {'' if i == 0 else f'{errors[i - 1] / e:.2f}'}")
    assert all(12.0 < errors[i] / errors[i + 1] < 20.0 for i in range(3))
    assert errors[3] < 1e-9  # the default step, 0.05 mm
    skew_in = 1.336 * (starts[:, 0] * d[:, 1] - starts[:, 1] * d[:, 0])
    p, out = reference.points_mm, reference.directions
    assert np.abs(1.336 * (p[:, 0] * out[:, 1] - p[:, 1] * out[:, 0]) - skew_in).max() < 1e-12
    bent = np.abs(out - d).max()
    assert bent > 1e-2  # the lens does bend them
