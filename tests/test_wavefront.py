"""Prescription <-> Zernike, and pupil rescaling."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import Prescription
from vissim.optics.pupil.wavefront import (
    Wavefront,
    parse_zernike_terms,
    prescription_to_zernike_um,
)


def test_standard_formulas_with_cylinder():
    # ERRATA item 1 (Thibos et al. 2004; Dai 2008); R = 3 mm.
    s, c, axis, r = -2.0, -1.0, 30.0, 3.0
    z = prescription_to_zernike_um(Prescription(s, c, axis), 2 * r)
    phi = math.radians(axis)
    assert z[(2, 0)] == pytest.approx(-(s + c / 2) * r**2 / (4 * math.sqrt(3)))
    assert z[(2, 2)] == pytest.approx(c * r**2 * math.cos(2 * phi) / (4 * math.sqrt(6)))
    assert z[(2, -2)] == pytest.approx(c * r**2 * math.sin(2 * phi) / (4 * math.sqrt(6)))


def test_myopic_eye_has_positive_defocus_coefficient():
    assert prescription_to_zernike_um(Prescription(-2.0), 4.0)[(2, 0)] > 0
    assert prescription_to_zernike_um(Prescription(+2.0), 4.0)[(2, 0)] < 0


def test_refractive_error_cannot_be_passed_as_a_prescription():
    with pytest.raises(TypeError, match="RefractiveError"):
        prescription_to_zernike_um(Prescription(-2.0).refractive_error(), 4.0)


powers = st.floats(-10, 10)


@given(powers, powers, st.floats(0.5, 180), st.floats(1, 8))
def test_prescription_zernike_round_trip(sphere, cyl, axis, pupil):
    rx = Prescription(sphere, cyl, axis)
    assert Wavefront.from_prescription(rx, pupil).to_prescription().is_close(rx, 1e-9)


@given(powers, powers, st.floats(0.5, 180))
def test_transposed_prescriptions_give_identical_wavefronts(sphere, cyl, axis):
    rx = Prescription(sphere, cyl, axis)
    a = prescription_to_zernike_um(rx, 5.0)
    b = prescription_to_zernike_um(rx.transposed(), 5.0)
    for key in a:
        assert a[key] == pytest.approx(b[key], abs=1e-9)


def test_wavefront_of_defocus_is_power_times_r_squared_over_two():
    # W(r) = -P r^2 / 2 (µm for D and mm) up to piston, P the correcting lens.
    front = Wavefront.from_prescription(Prescription(-2.0), 6.0)
    r = np.array([0.0, 1.0, 2.0, 3.0])
    w = front.opd_um(r, 0 * r)
    np.testing.assert_allclose(w - w[0], 2.0 * r**2 / 2, atol=1e-12)


def test_smaller_calculation_pupil_keeps_the_prescription():
    # Second-order terms of a sphero-cylinder rescale as (R'/R)^2: the Rx is pupil-independent.
    rx = Prescription.parse("-2.00 -1.25 x 30")
    small = Wavefront.from_prescription(rx, 6.0).rescaled(3.0)
    assert small.to_prescription().is_close(rx, 1e-9)
    assert small.coefficients_um[(2, 0)] == pytest.approx(prescription_to_zernike_um(rx, 3.0)[(2, 0)])


def test_rescaling_spherical_aberration_feeds_defocus():
    # Schwiegerling 2002 / Dai 2006: for e = R'/R, c40' = c40 e^4 and
    # c20' = c20 e^2 + sqrt(15) c40 (e^4 - e^2) (unit-RMS terms).
    c20, c40, e = 0.3, 0.2, 0.5
    small = Wavefront({(2, 0): c20, (4, 0): c40}, 6.0).rescaled(3.0)
    assert small.coefficients_um[(4, 0)] == pytest.approx(c40 * e**4)
    assert small.coefficients_um[(2, 0)] == pytest.approx(c20 * e**2 + math.sqrt(15) * c40 * (e**4 - e**2))


def test_larger_pupil_than_measured_is_refused():
    with pytest.raises(VissimInputError, match="cannot be extrapolated"):
        Wavefront({(2, 0): 1.0}, 4.0).rescaled(6.0)


def test_zernike_term_lists_parse_and_reject():
    assert parse_zernike_terms("2,0=0.5; 4,0=-0.1;2,0=0.25") == {(2, 0): 0.75, (4, 0): -0.1}
    for bad in ("2,1=0.5", "2,0=abc", "j4=1", ""):
        with pytest.raises(VissimInputError):
            parse_zernike_terms(bad)
