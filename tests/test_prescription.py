"""Prescription notation, transposition and power vectors."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import (
    LensPower,
    Prescription,
    RefractiveError,
    SpheroCylinder,
)


@pytest.mark.parametrize(
    "text, expected",
    [
        ("-2.00 -1.25 x 180", (-2.0, -1.25, 180.0)),
        ("-2.00/-1.25x180", (-2.0, -1.25, 180.0)),
        ("-2.00-1.25x180", (-2.0, -1.25, 180.0)),
        ("+1.50 DS", (1.5, 0.0, 180.0)),
        ("plano -0.75 x 90", (0.0, -0.75, 90.0)),
        ("+0.50 +1.00 x 90", (0.5, 1.0, 90.0)),
        ("+0.50+1.00x90", (0.5, 1.0, 90.0)),
        ("-2.00 DS -1.25 DC x 180", (-2.0, -1.25, 180.0)),
        ("+2.00 DC × 90", (0.0, 2.0, 90.0)),
        ("-1.00 -0.50 x 0", (-1.0, -0.5, 180.0)),  # 0 and 180 are the same meridian
        ("+0.00 DS", (0.0, 0.0, 180.0)),
        ("plano", (0.0, 0.0, 180.0)),
        ("PL", (0.0, 0.0, 180.0)),
    ],
)
def test_parses_the_notations_people_write(text, expected):
    rx = Prescription.parse(text)
    assert (rx.sphere_diopters, rx.cylinder_diopters, rx.axis_deg) == expected


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("-2.00 -1.25 x 200", "outside 0-180"),
        ("-2.00 -1.25 x -5", "outside 0-180"),
        ("-2.00 -1.25", "no axis"),
        ("-2.00 -1.25 x", "no axis"),
        ("minus two", "cannot read"),
        ("+1..5 DS", "cannot read"),
        ("", "cannot read"),
    ],
)
def test_malformed_prescriptions_get_one_clear_error(text, fragment):
    with pytest.raises(VissimInputError) as info:
        Prescription.parse(text)
    message = str(info.value)
    assert fragment in message and "\n" not in message


def test_transposition_keeps_the_power():
    rx = Prescription.parse("-2.00 -1.25 x 180")
    plus = rx.transposed()
    assert (plus.sphere_diopters, plus.cylinder_diopters, plus.axis_deg) == (-3.25, 1.25, 90.0)
    assert plus.transposed() == rx
    assert rx.is_close(plus)


def test_power_vector_of_a_known_prescription():
    # Thibos, Wheeler & Horner 1997: M = S + C/2, J0 = -(C/2) cos 2a, J45 = -(C/2) sin 2a.
    m, j0, j45 = Prescription.parse("-2.00 -1.00 x 45").power_vector()
    assert m == pytest.approx(-2.5)
    assert j0 == pytest.approx(0.0, abs=1e-12)
    assert j45 == pytest.approx(0.5)


powers = st.floats(-20, 20).map(lambda v: round(v * 4) / 4)
axes = st.floats(0.5, 180)


@given(powers, powers, axes)
def test_power_vector_round_trip(sphere, cyl, axis):
    rx = Prescription(sphere, cyl, axis)
    back = Prescription.from_power_vector(*rx.power_vector())
    assert back.is_close(rx, 1e-9)
    assert back.cylinder_diopters <= 0  # minus-cylinder form


@given(powers, powers, axes, st.floats(0, 180))
def test_meridian_power_is_the_same_in_both_cylinder_forms(sphere, cyl, axis, meridian):
    rx = Prescription(sphere, cyl, axis)
    assert rx.meridian_power(meridian) == pytest.approx(rx.transposed().meridian_power(meridian), abs=1e-9)


def test_correcting_lens_and_refractive_error_have_opposite_signs_and_distinct_types():
    rx = Prescription.parse("-2.00 -0.50 x 90")
    error = rx.refractive_error()
    assert isinstance(error, RefractiveError) and not isinstance(error, Prescription)
    assert error.sphere_diopters == 2.0 and error.cylinder_diopters == 0.5
    assert error.prescription() == rx
    added = LensPower(2.0)
    assert added.prescription_of_camera() == Prescription(-2.0)


def test_nonfinite_values_are_refused():
    with pytest.raises(VissimInputError, match="dioptres"):
        SpheroCylinder(math.nan)
    with pytest.raises(VissimInputError, match="degrees"):
        SpheroCylinder(-1, -1, 181)


def test_axis_noise_near_the_horizontal_is_normalised_to_180():
    assert LensPower(0, 1, 1e-13).axis_deg == 180.0
    assert LensPower(0, 1, 180 - 1e-12).axis_deg == 180.0


# --- issue 33: a cylinder that rounds to zero is written as none ---------------------------------------

@given(powers, st.integers(2, 4))
def test_a_spherical_prescription_is_written_with_no_cylinder_or_axis(sphere, decimals):
    """A sphere alone is ``S DS`` (or ``plano DS``) at every precision: no cylinder, no axis."""
    text = Prescription(sphere).format(decimals)
    assert text.endswith(" DS") and " x " not in text


@given(powers, st.floats(-0.49, 0.49), axes, st.integers(2, 4))
def test_a_cylinder_that_rounds_to_zero_prints_no_axis(sphere, cyl_fraction, axis, decimals):
    """Issue 33: ``--rx -1.00DS`` read back from a traced eye printed a cylinder of ~1e-6 D as
    ``-0.000 x 136.5``. A cylinder under half the last printed digit is written ``DS``, its sphere the
    spherical equivalent: the same text in minus- and plus-cylinder form, and within half a digit
    (plus the cylinder's half) of the sphere."""
    cyl = cyl_fraction * 10.0 ** -decimals
    rx = Prescription(sphere, cyl, axis)
    text = rx.format(decimals)
    assert text.endswith(" DS") and " x " not in text
    assert text == rx.transposed().format(decimals)
    written = 0.0 if text.startswith("plano") else float(text.split()[0])
    assert abs(written - rx.spherical_equivalent_diopters) <= 0.5 * 10.0 ** -decimals + 1e-12


@given(powers, st.floats(0.51, 10.0), axes, st.integers(2, 4))
def test_a_cylinder_that_shows_keeps_its_axis(sphere, cyl_digits, axis, decimals):
    """A cylinder of at least half the last printed digit is written with its axis."""
    text = Prescription(sphere, -cyl_digits * 10.0 ** -decimals, axis).format(decimals)
    assert " x " in text and not text.endswith("DS")


@pytest.mark.parametrize("rx, text", [(Prescription(-1.0, -1e-6, 136.5), "-1.00 DS"),
                                      (Prescription(-0.001), "plano DS"),
                                      (Prescription(-2.0, -1.25, 180.0), "-2.00 -1.25 x 180")])
def test_written_forms_by_hand(rx, text):
    assert str(rx) == text
