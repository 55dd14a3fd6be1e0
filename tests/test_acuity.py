"""Acuity notation and letter size (vissim.acuity) against the thesis and the standard charts."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from vissim.acuity import (
    decimal_to_logmar,
    letter_height_arcmin,
    letter_height_mm,
    logmar_to_decimal,
    logmar_to_snellen,
    snellen_to_logmar,
    subtense_arcmin,
    subtense_mm,
)
from vissim.errors import VissimInputError
from vissim.thesis import THESIS_CHART_DISTANCE_MM
from vissim.units import mm_to_m

THREE_FEET_M = mm_to_m(THESIS_CHART_DISTANCE_MM)  # the thesis's chart distance (section 4.1)
logmars = st.floats(min_value=-1.0, max_value=2.0, allow_nan=False)


def eq_4_1_mm(logmar: float, distance_m: float) -> float:
    """Krueger 2015, Eq. 4.1 verbatim: tan(deg2rad(5/60)) * distance_mm * 10**LogMAR."""
    return math.tan(math.radians(5.0 / 60.0)) * distance_m * 1000.0 * 10.0**logmar


def test_logmar_0_letter_is_1_33_mm_at_three_feet():
    # Thesis section 4.1 / Eq. 4.1: chart at 914.4 mm; 5 arcmin there is 1.330 mm.
    assert letter_height_mm(0.0, THREE_FEET_M) == pytest.approx(1.330, abs=5e-4)


def test_logmar_0_letter_is_8_73_mm_at_6_m():
    # Standard 6 m chart (ISO 8596; ETDRS at 4 m scales the same way): 5' at 6 m = 8.727 mm.
    assert letter_height_mm(0.0, 6.0) == pytest.approx(8.727, abs=5e-4)


def test_logmar_1_letter_is_13_3_mm_at_three_feet():
    # Thesis Figure 4.3: the top row (20/200 at three feet) is ten times the 20/20 letter.
    assert letter_height_mm(1.0, THREE_FEET_M) == pytest.approx(13.30, abs=5e-3)


@pytest.mark.parametrize(("logmar", "bound"), [(-0.3, 1e-6), (0.0, 1e-6), (0.4, 1e-6), (1.0, 2e-5)])
def test_letter_height_differs_from_eq_4_1_by_the_documented_amount(logmar, bound):
    # 2 d tan(theta/2) vs d tan(5') 10**LogMAR: relative difference ~ theta^2/12 - theta_0^2/3.
    for distance_m in (THREE_FEET_M, 6.0):
        rel = letter_height_mm(logmar, distance_m) / eq_4_1_mm(logmar, distance_m) - 1.0
        assert abs(rel) < bound


def test_logmar_0_is_5_px_tall_at_1_arcmin_per_px():
    # Thesis section 4.1: "letters with a LogMAR value of 0 ... [have] exactly 5 pixels of height".
    assert letter_height_arcmin(0.0) == 5.0
    assert letter_height_arcmin(1.0) == pytest.approx(50.0)
    assert letter_height_arcmin(-0.3) == pytest.approx(2.506, abs=1e-3)


def test_thesis_snellen_range():
    # Thesis section 4.1: LogMAR -0.3 .. 1.0 "corresponds to the range from 20/10 to 20/200".
    assert logmar_to_snellen(1.0) == "20/200"
    assert logmar_to_snellen(-0.3) == "20/10"
    assert logmar_to_snellen(0.0) == "20/20"
    assert logmar_to_snellen(1.0, test_distance=6) == "6/60"
    assert snellen_to_logmar("20/200") == pytest.approx(1.0)
    assert snellen_to_logmar("6/60") == pytest.approx(1.0)
    assert snellen_to_logmar(" 20 / 40 ") == pytest.approx(math.log10(2.0))


def test_eq_4_2_decimal_acuity():
    # Thesis Eq. 4.2 and its example: 20/40 is decimal 0.5.
    assert decimal_to_logmar(0.5) == pytest.approx(0.30103, abs=1e-5)
    assert logmar_to_decimal(0.0) == 1.0
    assert logmar_to_decimal(1.0) == pytest.approx(0.1)


@given(logmars)
def test_logmar_decimal_round_trip(logmar):
    assert decimal_to_logmar(logmar_to_decimal(logmar)) == pytest.approx(logmar, abs=1e-12)


@given(logmars, st.sampled_from([20, 6, 4]), st.integers(min_value=2, max_value=6))
def test_logmar_snellen_round_trip(logmar, test_distance, figures):
    text = logmar_to_snellen(logmar, test_distance, significant_figures=figures)
    # Rounding the denominator to `figures` significant figures moves it by < 5 * 10**-figures relative.
    assert snellen_to_logmar(text) == pytest.approx(logmar, abs=math.log10(1 + 5 * 10.0**-figures) + 1e-12)


@given(st.floats(min_value=0.01, max_value=1e4))
def test_subtense_round_trip(size_mm):
    assert subtense_mm(subtense_arcmin(size_mm, 0.9144), 0.9144) == pytest.approx(size_mm, rel=1e-12)


@pytest.mark.parametrize(
    ("call", "needle"),
    [
        (lambda: letter_height_mm(0.0, 0.0), "viewing distance"),
        (lambda: letter_height_mm(0.0, -1.0), "m"),
        (lambda: letter_height_mm(math.nan, 1.0), "LogMAR"),
        (lambda: letter_height_mm(0.0, math.inf), "viewing distance"),
        (lambda: letter_height_arcmin(math.inf), "LogMAR"),
        (lambda: logmar_to_decimal(1e6), "LogMAR"),
        (lambda: decimal_to_logmar(0.0), "decimal acuity"),
        (lambda: snellen_to_logmar("20-200"), "Snellen"),
        (lambda: snellen_to_logmar("0/20"), "Snellen test distance"),
        (lambda: logmar_to_snellen(0.0, test_distance=0), "test distance"),
        (lambda: letter_height_mm(4.0, 1.0), "180 deg"),
    ],
)
def test_bad_input_raises_one_line_naming_the_value(call, needle):
    with pytest.raises(VissimInputError) as info:
        call()
    assert needle in str(info.value)
    assert "\n" not in str(info.value)
