"""Accommodation: amplitude from age, and what an uncorrected eye exerts for a target.

Expected values are hand-derived from the sign derivation in ``vissim.optics.rx.accommodation``
(need = M + 1/d, M the correcting lens's spherical equivalent, clamped to [0, amplitude])
and from Hofstetter's (1950) three lines; exact up to float rounding (abs 1e-12).
"""

import math

import pytest

from vissim.errors import VissimInputError
from vissim.optics.rx.accommodation import (
    Accommodation,
    accommodation_for_target,
    amplitude_from_age_diopters,
    clear_vision_range_m,
    required_accommodation_diopters,
)
from vissim.optics.rx.prescription import Prescription

MYOPE = Prescription(-2.0)
EMMETROPE = Prescription(0.0)
HYPEROPE = Prescription(+1.0)


@pytest.mark.parametrize(
    "age, statistic, expected",
    [
        (20, "mean", 12.5),  # 18.5 - 0.3 * 20
        (20, "minimum", 10.0),  # 15 - 0.25 * 20
        (20, "maximum", 17.0),  # 25 - 0.4 * 20
        (45, "mean", 5.0),
        (70, "mean", 0.0),  # 18.5 - 21 < 0: absolute presbyopia
    ],
)
def test_hofstetter_amplitude_by_age(age, statistic, expected):
    assert amplitude_from_age_diopters(age, statistic) == pytest.approx(expected, abs=1e-12)
    assert Accommodation.from_age(age, statistic).amplitude_diopters == pytest.approx(expected, abs=1e-12)
    assert "Hofstetter 1950" in Accommodation.from_age(age, statistic).source


def test_cycloplegia_and_presbyopia_mean_no_accommodation():
    for eye in (Accommodation.cycloplegic(), Accommodation.absolute_presbyopia()):
        assert eye.amplitude_diopters == 0.0
        assert eye.for_target(MYOPE, 0.25) == 0.0
        assert eye.for_target(HYPEROPE, math.inf) == 0.0


@pytest.mark.parametrize(
    "distance_m, expected_d",
    [(0.5, 0.0), (0.25, 2.0), (0.2, 3.0), (6.0, 0.0), (math.inf, 0.0)],
)
def test_uncorrected_myope_accommodates_only_nearer_than_its_far_point(distance_m, expected_d):
    # far point 0.5 m: 0 D there, 1/d - 2 nearer, nothing helps beyond (need < 0 -> relaxed).
    assert accommodation_for_target(MYOPE, distance_m, 10.0) == pytest.approx(expected_d, abs=1e-12)


def test_myope_need_beyond_far_point_is_negative_before_clamping():
    assert required_accommodation_diopters(MYOPE, 6.0) == pytest.approx(-2.0 + 1 / 6, abs=1e-12)


def test_hyperope_accommodates_even_at_infinity_and_is_limited_by_amplitude():
    assert accommodation_for_target(HYPEROPE, math.inf, 5.0) == pytest.approx(1.0, abs=1e-12)
    assert accommodation_for_target(HYPEROPE, 0.5, 5.0) == pytest.approx(3.0, abs=1e-12)
    assert accommodation_for_target(HYPEROPE, 0.5, 2.0) == pytest.approx(2.0, abs=1e-12)


def test_astigmatic_eye_focuses_its_spherical_equivalent():
    # -1.00 -2.00 x 90 has M = -2: like the -2 D myope.
    eye = Prescription(-1.0, -2.0, 90.0)
    assert accommodation_for_target(eye, 0.5, 5.0) == pytest.approx(0.0, abs=1e-12)
    assert accommodation_for_target(eye, 0.25, 5.0) == pytest.approx(2.0, abs=1e-12)


@pytest.mark.parametrize("distance_m", [0.34, 0.5, 1.0, 2.0, 6.0, math.inf])
def test_emmetrope_with_3_D_can_focus_every_target_beyond_a_third_of_a_metre(distance_m):
    # "Keeps all panels beyond 0.33 m sharp" for ONE accommodation state at a time: for each
    # target distance >= 0.34 m, accommodation_for_target finds A = 1/d within the 3 D amplitude
    # and the effective prescription for that target is then exactly plano.
    exerted = accommodation_for_target(EMMETROPE, distance_m, 3.0)
    proximity = 0.0 if math.isinf(distance_m) else 1.0 / distance_m
    assert exerted == pytest.approx(proximity, abs=1e-12) and exerted <= 3.0
    assert effective_prescription(EMMETROPE, distance_m, exerted).sphere_diopters == pytest.approx(0.0, abs=1e-12)


def test_emmetrope_with_3_D_cannot_focus_a_quarter_metre():
    exerted = accommodation_for_target(EMMETROPE, 0.25, 3.0)
    assert exerted == 3.0
    # 1 D of demand left: the effective correcting lens is +1 D (too little power, like a hyperope).
    assert effective_prescription(EMMETROPE, 0.25, exerted).sphere_diopters == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize(
    "eye, amplitude, expected",
    [
        (MYOPE, 3.0, (0.2, 0.5)),  # proximities 2..5 D
        (EMMETROPE, 3.0, (1 / 3, math.inf)),
        (HYPEROPE, 3.0, (0.5, math.inf)),
        (Prescription(+2.0), 1.0, None),  # cannot even focus infinity
        (EMMETROPE, 0.0, (math.inf, math.inf)),
    ],
)
def test_range_of_clear_vision(eye, amplitude, expected):
    got = clear_vision_range_m(eye, amplitude)
    if expected is None:
        assert got is None
    else:
        assert got == pytest.approx(expected, abs=1e-12)


def effective_prescription(rx, distance_m, accommodation_diopters=0.0):
    """Oracle, written out (not vissim's code): Rx + 1/d - A on the sphere (docs/conventions.md, Depth)."""
    proximity = 0.0 if math.isinf(distance_m) else 1.0 / distance_m
    return Prescription(rx.sphere_diopters + proximity - accommodation_diopters, rx.cylinder_diopters, rx.axis_deg)


def test_bad_inputs_are_one_line_errors():
    with pytest.raises(VissimInputError, match="amplitude .* >= 0 dioptres"):
        Accommodation(-1.0)
    with pytest.raises(VissimInputError, match="age must be within 0-130 years"):
        amplitude_from_age_diopters(200)
    with pytest.raises(VissimInputError, match="statistic"):
        amplitude_from_age_diopters(20, "median")
    with pytest.raises(VissimInputError, match="target distance must be a positive number of metres"):
        accommodation_for_target(MYOPE, 0.0, 3.0)
    with pytest.raises(TypeError, match="RefractiveError"):
        accommodation_for_target(MYOPE.refractive_error(), 1.0, 3.0)
