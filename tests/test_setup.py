"""vissim.optics.rx.viewing_setup.ViewingSetup: each constructor against closed-form vergence arithmetic.

Oracles are written out here, independent of the 4 x 4 ray transfer code: thin-lens vergence
stepping (L' = L + F, then L2 = L' / (1 - d L') across a gap d; Keating, *Geometric, Physical
and Visual Optics*, 2nd ed., ch. 5), the spectacle magnification of a thin lens for a finite
object, M = 1 / (1 - F d (s - d) / s) (chief ray to the pupil centre), and blur = pupil x
defocus (D x mm = mrad).  Tolerances: 1e-9 D / 1e-9 relative where both sides are exact
arithmetic; the DSLR's 4x4 trace agrees with the stepping to rounding.
"""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from vissim.optics.rx.prescription import Prescription
from vissim.optics.rx.viewing_setup import ViewingSetup
from vissim.optics.rx.trial_lens import TrialLens, TrialLensSetup

ARCMIN_PER_MRAD = 180.0 * 60.0 / math.pi / 1000.0


def test_dslr_constructor_is_vergence_stepping_through_a_thin_lens():
    s, d, power = 0.9144, 0.010, 2.0  # the thesis's chart, vertex distance and a +2 D lens
    entering = -1.0 / (s - d) + power
    added = entering / (1.0 - d * entering) + 1.0 / s  # 1.9960 D (ERRATA item 4)
    magnification = 1.0 / (1.0 - power * d * (s - d) / s)  # 1.0202
    setup = ViewingSetup.dslr(18.0, 5.0, s, TrialLensSetup((TrialLens(power),), 10.0, s))
    assert setup.pupil_diameter_mm == pytest.approx(3.6, abs=1e-12)
    np.testing.assert_allclose(setup.defocus_matrix_diopters, added * np.eye(2), atol=1e-9)
    np.testing.assert_allclose(setup.magnification_matrix, magnification * np.eye(2), rtol=1e-9)
    assert round(added, 4) == 1.9960 and round(magnification, 4) == 1.0202
    assert setup.camera_prescription.sphere_diopters == pytest.approx(-added, abs=1e-9)  # a plus lens: myopic camera
    ((blur, _), _) = setup.blur_diameter_arcmin
    assert blur == pytest.approx(3.6 * added * ARCMIN_PER_MRAD, rel=1e-9)


def test_dslr_focus_error_is_one_over_focus_minus_one_over_chart():
    setup = ViewingSetup.dslr(18.0, 5.0, 2.0, TrialLensSetup((), 10.0, 0.9144))
    expected = 1.0 / 2.0 - 1.0 / 0.9144  # focused beyond the chart: the chart is hyperopic defocus
    np.testing.assert_allclose(setup.defocus_matrix_diopters, expected * np.eye(2), atol=1e-12)
    assert setup.magnification_matrix == ((1.0, 0.0), (0.0, 1.0))
    assert setup.camera_prescription.sphere_diopters == pytest.approx(-expected, abs=1e-12)


@pytest.mark.parametrize(("rx", "distance_m", "accommodation", "expected"), [
    (Prescription(-2.0), 6.0, 0.0, np.diag([2.0 - 1 / 6, 2.0 - 1 / 6])),  # myope: 6 m like -1.83 D
    (Prescription(-2.0), 0.5, 0.0, np.zeros((2, 2))),  # focuses 0.5 m
    (Prescription(1.0), 6.0, 0.0, np.diag([-1.0 - 1 / 6, -1.0 - 1 / 6])),  # hyperope "beyond infinity"
    (Prescription(0.0), 0.25, 3.0, np.diag([-1.0, -1.0])),  # emmetrope, 3 D of 4 D needed
    (Prescription(0.0, -2.0, 90.0), math.inf, 0.0, np.diag([2.0, 0.0])),  # excess power horizontally
])
def test_eye_constructor_is_accommodation_minus_rx_minus_proximity(rx, distance_m, accommodation, expected):
    setup = ViewingSetup.eye(rx, 4.0, accommodation, distance_m)
    np.testing.assert_allclose(setup.defocus_matrix_diopters, expected, atol=1e-12)
    assert setup.pupil_diameter_mm == 4.0 and setup.magnification_matrix == ((1.0, 0.0), (0.0, 1.0))
    proximity = 0.0 if math.isinf(distance_m) else 1.0 / distance_m
    assert setup.camera_prescription.is_close(Prescription(rx.sphere_diopters + proximity - accommodation,
                                                           rx.cylinder_diopters, rx.axis_deg))


def test_eye_refuses_a_refractive_error():
    with pytest.raises(TypeError):
        ViewingSetup.eye(Prescription(-2.0).refractive_error(), 4.0)


def test_atv_observer_adds_p_over_one_minus_dp_at_the_eye():
    # +1.25 DS eye (a hyperope), +2 D trial lens 15 mm in front, collimated source, no accommodation.
    vergence = 2.0 / (1.0 - 0.015 * 2.0)
    setup = ViewingSetup.atv_observer(Prescription(1.25), 4.0, 0.0, 2.0, 15.0)
    np.testing.assert_allclose(setup.defocus_matrix_diopters, (vergence - 1.25) * np.eye(2), atol=1e-12)
    assert setup.camera_prescription.sphere_diopters == pytest.approx(1.25 - vergence, abs=1e-12)
    with_accommodation = ViewingSetup.atv_observer(Prescription(1.25), 4.0, 0.5, -2.0, 15.0)
    expected = -2.0 / (1.0 + 0.015 * 2.0) - 1.25 + 0.5
    np.testing.assert_allclose(with_accommodation.defocus_matrix_diopters, expected * np.eye(2), atol=1e-12)


def _changed_fields(a: ViewingSetup, b: ViewingSetup) -> set[str]:
    return {f.name for f in dataclasses.fields(a) if getattr(a, f.name) != getattr(b, f.name)}


def test_each_thesis_choice_is_one_field_replaced():
    lenses = (TrialLens(2.0),)
    bench = ViewingSetup.dslr(18.0, 5.0, 0.9144, TrialLensSetup(lenses, 10.0, 0.9144))
    thesis_pupil = bench.with_thesis_pupil(5.0)
    assert _changed_fields(bench, thesis_pupil) == {"pupil_diameter_mm"} and thesis_pupil.pupil_diameter_mm == 2.7
    table = bench.with_table_4_2_power(lenses, 10.0)
    assert _changed_fields(bench, table) == {"defocus_matrix_diopters"}
    np.testing.assert_allclose(table.defocus_matrix_diopters, 2.0 / (1.0 - 0.02) * np.eye(2), atol=1e-12)  # 2.0408
    flat = bench.without_magnification()
    assert _changed_fields(bench, flat) == {"magnification_matrix"} and flat.magnification_matrix == ((1.0, 0.0), (0.0, 1.0))


powers = st.floats(-10.0, 10.0, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(powers, powers, st.floats(0.0, 180.0), st.floats(0.5, 9.0), st.floats(0.0, 4.0), st.floats(0.1, 100.0))
def test_blur_is_pupil_times_principal_defocus_and_prescription_round_trips(sphere, cylinder, axis, pupil,
                                                                            accommodation, distance_m):
    setup = ViewingSetup.eye(Prescription(sphere, cylinder, axis), pupil, accommodation, distance_m)
    eigen = np.linalg.eigvalsh(np.asarray(setup.defocus_matrix_diopters))
    blur = sorted(d for d, _ in setup.blur_diameter_arcmin)
    np.testing.assert_allclose(blur, sorted(pupil * np.abs(eigen) * ARCMIN_PER_MRAD), rtol=1e-9, atol=1e-9)
    again = ViewingSetup.eye(setup.camera_prescription, pupil, 0.0, math.inf)
    np.testing.assert_allclose(again.defocus_matrix_diopters, setup.defocus_matrix_diopters, atol=1e-9)
    assert setup.wavefront.to_prescription().is_close(setup.camera_prescription, 1e-9)


@pytest.mark.parametrize("rx, accommodation, distance_m", [
    (Prescription(-2.0), 0.0, 0.5), (Prescription(0.0), 2.5, 6.0), (Prescription(-1.0, -1.0, 30.0), 1.0, 0.4),
    (Prescription(1.0), 0.0, math.inf)])
def test_an_eye_at_a_depth_is_the_viewing_setup_of_that_eye_there(rx, accommodation, distance_m):
    # The depth blurs' DepthViewer and ViewingSetup.eye decide the same defocus: D = A I - Rx - I/d.
    from vissim.optics.rx.viewing_setup import DepthViewer

    eye = DepthViewer(rx, 3.0, accommodation)
    proximity = 0.0 if math.isinf(distance_m) else 1.0 / distance_m
    setup = eye.viewing_setup(distance_m)
    assert setup == ViewingSetup.eye(rx, 3.0, accommodation, distance_m)
    assert eye.wavefront_at(proximity).to_prescription().is_close(setup.camera_prescription, 1e-9)
    assert eye.sphere_at_diopters(proximity) == pytest.approx(rx.sphere_diopters + proximity - accommodation)
    # it focuses the spherical equivalent of its focus matrix
    assert eye.in_focus_proximity_diopters == pytest.approx(np.trace(setup.focus_matrix_diopters) / 2, abs=1e-12)


def test_an_eye_refuses_negative_accommodation_and_a_smaller_extra_wavefront():
    from vissim.errors import VissimInputError
    from vissim.optics.rx.viewing_setup import DepthViewer
    from vissim.optics.pupil.wavefront import Wavefront

    with pytest.raises(VissimInputError, match="accommodation exerted must be >= 0 dioptres"):
        DepthViewer(Prescription(-1.0), 3.0, -0.5)
    with pytest.raises(VissimInputError, match="extra_wavefront is measured over 2 mm"):
        DepthViewer(Prescription(-1.0), 3.0, extra_wavefront=Wavefront({(4, 0): 0.1}, 2.0))
