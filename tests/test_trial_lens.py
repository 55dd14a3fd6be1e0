"""Trial lenses in front of a camera: added power and spectacle magnification by ray transfer.

Expected values come from the thesis (Krueger 2015, Table 4.1, Table 4.2), from ERRATA items 3-5
(/work/shared/reference/ERRATA.md), or from scalar paraxial traces written out in the tests
themselves, independent of the 4x4 matrices under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import LensPower
from vissim.optics.rx.trial_lens import (
    CROWN_GLASS_INDEX,
    TrialLens,
    TrialLensSetup,
    entrance_pupil_diameter_mm,
    thesis_eye_pupil_diameter_mm,
    thesis_table_4_2_power,
    trial_lens_effect,
)


def effect_of(*lenses: TrialLens, **setup):
    return trial_lens_effect(TrialLensSetup(lenses=lenses, **setup))


def thick(sphere, cylinder=0.0, axis=180.0, thickness_mm=3.0, back=0.0, index=CROWN_GLASS_INDEX):
    return TrialLens(sphere, cylinder, axis, refractive_index=index,
                     center_thickness_mm=thickness_mm, back_surface_diopters=back)


# -- added power -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("lens_diopters", "table_4_2_diopters"),
    # Krueger 2015, Table 4.2 (10 mm vertex distance, object at infinity).
    [(0.0, 0.0), (1.0, 1.0101), (2.0, 2.0408), (3.0, 3.0928), (4.0, 4.1667)],
)
def test_thin_lens_at_infinity_reproduces_thesis_table_4_2(lens_diopters, table_4_2_diopters):
    added = effect_of(TrialLens(lens_diopters)).added_power
    assert round(added.sphere_diopters, 4) == table_4_2_diopters
    assert added.cylinder_diopters == 0.0
    assert round(thesis_table_4_2_power(lens_diopters), 4) == table_4_2_diopters


def test_chart_at_914mm_gets_less_added_power_than_table_4_2():
    # ERRATA item 4: vergence trace object -> lens -> 10 mm -> camera, chart 914.4 mm from the
    # camera principal plane, i.e. 904.4 mm from the lens.
    at_lens = -1.0 / 0.9044 + 2.0
    at_camera = at_lens / (1.0 - 0.010 * at_lens)
    expected = at_camera - (-1.0 / 0.9144)  # = 1.995977653606... D
    added = effect_of(TrialLens(2.0), object_distance_m=0.9144).added_power
    assert added.sphere_diopters == pytest.approx(expected, abs=1e-12)
    assert round(added.sphere_diopters, 4) == 1.9960  # ERRATA item 4: "about 1.996 D"
    assert added.sphere_diopters < thesis_table_4_2_power(2.0) - 0.04


def test_plus_lens_makes_the_camera_myopic():
    effect = effect_of(TrialLens(2.0))
    assert effect.added_power.sphere_diopters > 0
    assert effect.camera_prescription.sphere_diopters < 0  # a myope's prescription is minus
    assert effect.camera_prescription.is_close(-effect.added_power)


def test_separated_lenses_match_a_step_by_step_vergence_trace():
    # +2 D, 5 mm air, -1 D, 10 mm to the camera; object 1 m from the camera principal plane.
    vergence = -1.0 / (1.0 - 0.015) + 2.0
    vergence = vergence / (1.0 - 0.005 * vergence) - 1.0
    vergence = vergence / (1.0 - 0.010 * vergence)
    expected = vergence + 1.0 / 1.0
    effect = effect_of(TrialLens(2.0), TrialLens(-1.0), lens_gap_mm=5.0, object_distance_m=1.0)
    assert effect.added_power.sphere_diopters == pytest.approx(expected, abs=1e-12)


def test_thin_lenses_in_contact_add_their_powers():
    # +1 D and +2 D in contact act as +3 D: Table 4.2 gives 3.0928 D.
    added = effect_of(TrialLens(1.0), TrialLens(2.0)).added_power
    assert round(added.sphere_diopters, 4) == 3.0928


def test_plus_cylinder_axis_90_adds_power_only_in_the_horizontal_meridian():
    effect = effect_of(TrialLens(0.0, 2.0, 90.0))
    # Power of +2 DC x 90 acts across its axis, in the 180 meridian: 2 / (1 - 0.01 * 2).
    assert effect.added_power.meridian_power(180.0) == pytest.approx(2.0 / 0.98, abs=1e-12)
    assert effect.added_power.meridian_power(90.0) == pytest.approx(0.0, abs=1e-12)
    (mag_h, meridian_h), (mag_v, meridian_v) = effect.magnification_principal
    assert (meridian_h, meridian_v) == (180.0, 90.0)
    assert mag_h == pytest.approx(1.0 / 0.98, abs=1e-12)  # ERRATA item 5, one meridian only
    assert mag_v == pytest.approx(1.0, abs=1e-12)
    assert effect.magnification == pytest.approx(math.sqrt(1.0 / 0.98), abs=1e-12)


def test_crossed_cylinders_in_contact_equal_a_sphere():
    crossed = effect_of(TrialLens(0.0, 1.0, 90.0), TrialLens(0.0, 1.0, 180.0))
    sphere = effect_of(TrialLens(1.0))
    np.testing.assert_allclose(crossed.added_power_matrix, sphere.added_power_matrix, atol=1e-12)
    np.testing.assert_allclose(crossed.magnification_matrix, sphere.magnification_matrix, atol=1e-12)
    assert crossed.added_power.is_close(LensPower(1.0 / 0.99), tol_diopters=1e-12)


@pytest.mark.parametrize("make", [TrialLens, thick], ids=["thin", "thick"])
def test_transposed_cylinder_gives_identical_effect(make):
    plus = effect_of(make(1.0, 2.0, 30.0), object_distance_m=0.9144)
    minus = effect_of(make(3.0, -2.0, 120.0), object_distance_m=0.9144)
    np.testing.assert_allclose(plus.added_power_matrix, minus.added_power_matrix, atol=1e-12)
    np.testing.assert_allclose(plus.magnification_matrix, minus.magnification_matrix, atol=1e-12)
    assert plus.added_power.is_close(minus.added_power, tol_diopters=1e-12)


def test_no_lens_adds_nothing_and_does_not_magnify():
    for distance_m in (math.inf, 0.9144):
        effect = effect_of(object_distance_m=distance_m)
        assert effect.added_power.is_close(LensPower(0.0), tol_diopters=1e-15)
        assert effect.magnification == 1.0
        assert effect.magnification_matrix == ((1.0, 0.0), (0.0, 1.0))


@settings(max_examples=60, deadline=None)
@given(
    sphere=st.floats(-10.0, 10.0),
    cylinder=st.floats(-6.0, 6.0),
    axis=st.floats(0.0, 180.0),
    vertex_mm=st.floats(0.0, 20.0),
)
def test_thin_lens_at_infinity_adds_p_over_1_minus_dp_per_principal_meridian(
    sphere, cylinder, axis, vertex_mm
):
    lens = TrialLens(sphere, cylinder, axis)
    added = effect_of(lens, vertex_distance_mm=vertex_mm).added_power
    d_m = vertex_mm / 1000.0
    for meridian in (lens.axis_deg, lens.axis_deg + 90.0):
        power = lens.marked_power.meridian_power(meridian)  # S along the axis, S + C across
        assert added.meridian_power(meridian) == pytest.approx(power / (1 - d_m * power), abs=1e-9)


# -- spectacle magnification ---------------------------------------------------------------


@pytest.mark.parametrize(("power", "expected"), [(4.0, 1 / 0.96), (-4.0, 1 / 1.04)])
def test_thin_lens_magnification_at_infinity_is_one_over_one_minus_dp(power, expected):
    # ERRATA item 5: 1/(1 - dP) = +4.2 % at +4 D and -3.8 % at -4 D, 10 mm: "about 4 %".
    effect = effect_of(TrialLens(power))
    assert effect.magnification == pytest.approx(expected, abs=1e-12)
    assert abs(effect.magnification - 1.0) == pytest.approx(0.04, abs=0.0025)
    assert (effect.magnification > 1.0) == (power > 0.0)


@pytest.mark.parametrize(("power", "lens_to_object_m"), [(2.0, 0.9044), (-3.0, 0.49)])
def test_thin_lens_magnification_for_a_near_object(power, lens_to_object_m):
    """M = (s + d) / (s + d - d P s), s = lens-to-object distance, d = vertex distance.

    Object of height h at s in front of the lens, camera pupil d behind it.  The chief ray
    reaches the pupil centre, so after the lens its angle is u' = -y/d for lens height y; before
    the lens u = u' + P y.  From the object, y = h + s u = h + s y (P - 1/d), so
    y = h d / (s + d - d P s) and u' = -h / (s + d - d P s).  Without the lens the same object
    subtends u0 = -h / (s + d).  The ratio u'/u0 is M.
    """
    d = 0.010
    s = lens_to_object_m
    expected = (s + d) / (s + d - d * power * s)
    effect = effect_of(TrialLens(power), object_distance_m=s + d)
    assert effect.magnification == pytest.approx(expected, abs=1e-12)


def test_thick_plano_convex_lens_magnifies_more_by_the_shape_factor():
    lens = thick(2.0, thickness_mm=3.0)
    reduced_m = 0.003 / 1.523
    # Front surface from F_bv = F1 / (1 - (t/n) F1) solved for F1 (plano back surface).
    front = 2.0 / (1.0 + reduced_m * 2.0)
    np.testing.assert_allclose(lens.front_surface_power_matrix(), [[front, 0.0], [0.0, front]], atol=1e-12)
    shape_factor = 1.0 / (1.0 - reduced_m * front)  # = 1.00394, "about +0.4 %"
    thick_effect, thin_effect = effect_of(lens), effect_of(TrialLens(2.0))
    assert thick_effect.magnification / thin_effect.magnification == pytest.approx(shape_factor, abs=1e-12)
    assert thick_effect.magnification / thin_effect.magnification - 1 == pytest.approx(0.004, abs=0.0005)
    # The marked power is the back vertex power: same added power as the thin lens.
    assert thick_effect.added_power.is_close(thin_effect.added_power, tol_diopters=1e-12)


@pytest.mark.parametrize(
    "lens",
    [thick(2.0), thick(-4.0, thickness_mm=1.5), thick(-1.0, -2.0, 30.0, thickness_mm=2.0, back=-6.0),
     thick(0.0, 2.0, 90.0, index=1.7)],
    ids=["plano-convex", "plano-concave", "toric-meniscus", "plano-cylinder-n1.7"],
)
def test_thick_lens_back_vertex_power_equals_marked_power(lens):
    """Trace a parallel beam through the surfaces rebuilt from their radii, one meridian at a time."""
    n = lens.refractive_index
    front, back = lens.surface_radii_mm()
    back_power = 0.0 if math.isinf(back.radii_mm[0]) else (1 - n) / (back.radii_mm[0] / 1000)
    assert back_power == pytest.approx(lens.back_surface_diopters, abs=1e-12)
    for radius_mm, meridian in zip(front.radii_mm, front.meridians_deg):
        front_power = 0.0 if math.isinf(radius_mm) else (n - 1) / (radius_mm / 1000)
        height, angle = 1e-3, 0.0
        angle -= front_power * height
        height += (lens.center_thickness_mm / 1000 / n) * angle
        angle -= back_power * height
        back_vertex_power = -angle / height
        assert back_vertex_power == pytest.approx(lens.marked_power.meridian_power(meridian), abs=1e-9)
    # The 4x4 ray transfer agrees: a parallel beam leaves with vergence -C A^-1.
    matrix = lens.ray_transfer_matrix()
    vergence = -matrix[2:, :2] @ np.linalg.inv(matrix[:2, :2])
    np.testing.assert_allclose(vergence, lens.marked_power.power_matrix(), atol=1e-12)


def test_surface_radii_of_a_plano_convex_lens_follow_the_lensmaker_relation():
    front, back = thick(2.0).surface_radii_mm()
    front_power = 2.0 / (1.0 + 0.003 / 1.523 * 2.0)
    assert front.radii_mm == pytest.approx((523.0 / front_power,) * 2, abs=1e-9)  # R = (n-1)/F
    assert back.radii_mm == (math.inf, math.inf)
    with pytest.raises(VissimInputError, match="index"):
        TrialLens(2.0).surface_radii_mm()


# -- pupils (thesis Table 4.1, ERRATA item 3) ------------------------------------------------


@pytest.mark.parametrize(
    ("f_number", "camera_mm", "thesis_eye_mm"),
    [(4.0, 4.5, 3.4), (4.5, 4.0, 3.0), (5.0, 3.6, 2.7)],  # Krueger 2015, Table 4.1
)
def test_pupils_reproduce_thesis_table_4_1(f_number, camera_mm, thesis_eye_mm):
    assert round(entrance_pupil_diameter_mm(18.0, f_number), 1) == camera_mm
    assert round(thesis_eye_pupil_diameter_mm(f_number), 1) == thesis_eye_mm


def test_camera_at_f5_has_a_3_6_mm_entrance_pupil():
    assert entrance_pupil_diameter_mm(18.0, 5.0) == pytest.approx(3.6, abs=1e-12)  # ERRATA item 3


# -- bad input -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("build", "fragment"),
    [
        (lambda: TrialLensSetup((TrialLens(2.0),), object_distance_m=0.005), "0.005 m"),
        (lambda: TrialLensSetup((thick(2.0),), vertex_distance_mm=10, object_distance_m=0.012), "0.013 m"),
        (lambda: TrialLensSetup((TrialLens(2.0),), object_distance_m=-1.0), "-1 m"),
        (lambda: TrialLensSetup((TrialLens(2.0),), vertex_distance_mm=-1.0), "-1 mm"),
        (lambda: TrialLensSetup((TrialLens(1.0),) * 4), "at most 3"),
        (lambda: TrialLens(2.0, refractive_index=1.0), "refractive index must be within 1.01-3"),
        (lambda: TrialLens(2.0, refractive_index=0.5, center_thickness_mm=2.0), "0.5"),
        (lambda: TrialLens(2.0, refractive_index=1.5, center_thickness_mm=-1.0), "-1 mm"),
        (lambda: TrialLens(2.0, center_thickness_mm=3.0), "refractive index"),
        (lambda: TrialLens(float("nan")), "dioptres"),
        (lambda: TrialLens(math.inf), "dioptres"),
        (lambda: entrance_pupil_diameter_mm(18.0, 0.0), "f-number"),
    ],
)
def test_bad_input_raises_one_line_naming_the_value(build, fragment):
    with pytest.raises(VissimInputError) as info:
        build()
    message = str(info.value)
    assert fragment in message
    assert "\n" not in message


def test_lens_focusing_on_the_camera_plane_is_refused():
    # A +100 D lens 10 mm in front focuses a distant object on the camera principal plane.
    with pytest.raises(VissimInputError, match="infinite"):
        effect_of(TrialLens(100.0))


def test_axis_a_hair_above_zero_is_the_horizontal_meridian():
    # Regression: prescription._normalise_axis maps 1e-13 deg to 180.00000000000006 deg.
    lens = TrialLens(0.0, -1.0, 1e-13)
    assert lens.axis_deg == 180.0
    effect = effect_of(lens, TrialLens(0.0, 0.0, 0.0))
    assert effect.added_power.axis_deg <= 180.0
    assert effect.camera_prescription.is_close(-effect.added_power)
