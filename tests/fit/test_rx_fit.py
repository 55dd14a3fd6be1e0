"""Prescription fits of synthetic captures: sign, axis, ambiguity, refusals.

Captures come from vissim's own forward chain (``tests/fit/synthetic.py``: fine chart, bench
magnification, ray-traced or wave PSF, block means, Gaussian noise), not from the fit's model.
Truth is the power the bench's lens adds at the camera by vergence theory
(:meth:`vissim.bench.dslr.DslrBench.viewing_setup`): what ``vissim trial-lens`` prints as
``effective_*`` for the lens as rendered.
"""

import numpy as np
import pytest

from vissim.errors import VissimInputError
from vissim.fit.rx_fit import fit_rx
from vissim.optics.trial_lens import TrialLens

from tests.fit.synthetic import BENCH, capture


def _fit(image, reference, **kw):
    kw.setdefault("bench", BENCH)
    return fit_rx(image, reference, arcmin_per_px=1.0, pupil_diameter_mm=3.6, **kw)


@pytest.mark.parametrize("power", [2.0, -2.0])
def test_a_plus_lens_on_the_bench_fits_as_plus_power_and_a_minus_lens_as_minus(power):
    image, reference, truth = capture(TrialLens(power))
    fit = _fit(image, reference)
    assert fit.status == "ok", fit.reason
    m, j0, j45 = fit.power_vector
    assert np.sign(m) == np.sign(power)
    # 0.02 D: the synthetic chain's own blur and resampling differ from the model's by ~0.005 D
    assert abs(m - truth[0]) < 0.02 and abs(j0) < 0.02 and abs(j45) < 0.02
    assert fit.sign_delta_chi2 > 100  # the magnification (2 %) decides the sign by far


def test_an_axis_of_30_fits_as_30_not_120_or_150():
    lens = TrialLens(0.5, -1.5, 30.0)  # effective power about +0.50 -1.50 x 30
    image, reference, truth = capture(lens)
    fit = _fit(image, reference)
    record = fit.as_json()
    assert fit.status == "ok" and record["axis_determined"]
    assert abs(record["axis_deg"] - 30.0) < 2.0  # 120 would be the wrong sign, 150 a mirrored frame
    assert record["cylinder_diopters"] == pytest.approx(-1.5, abs=0.05)
    assert np.allclose(fit.power_vector, truth, atol=0.02)
    low, high = record["interval_95"]["axis_deg"]
    assert low < record["axis_deg"] < high


def test_without_a_magnification_tie_the_sign_is_reported_undetermined():
    image, reference, truth = capture(TrialLens(2.0))
    fit = _fit(image, reference, magnification="none")
    record = fit.as_json()
    assert fit.status == "sign undetermined"
    assert record["sphere_diopters"] is None and record["power_vector"] is None and fit.power_vector is None
    means = [s["power_vector"]["M_diopters"] for s in record["solutions"]]
    # +P, -P and the two crossed cylinders (+P, -P in the principal meridians) blur alike
    assert min(abs(m - truth[0]) for m in means) < 0.02 and min(abs(m + truth[0]) for m in means) < 0.02
    assert all(s["delta_chi2"] == 0.0 for s in record["solutions"])


def test_a_spherical_lens_leaves_the_axis_undetermined():
    image, reference, _ = capture(TrialLens(1.5))
    record = _fit(image, reference).as_json()
    assert record["status"] == "ok"
    assert record["axis_determined"] is False and record["axis_deg"] is None
    assert record["interval_95"]["axis_deg"] is None


def test_no_lens_is_reported_unresolved_with_a_bound_not_a_power():
    image, reference, _ = capture(None)
    fit = _fit(image, reference)
    record = fit.as_json()
    # the fit alone gives about -0.12 D with a tiny interval (the shifted sharp reference's
    # pixels look like a little blur): it must not be reported as a power, nor with a sign
    assert fit.status == "unresolved"
    assert record["sphere_diopters"] is None and record["power_vector"] is None
    assert 0.1 < record["power_bound_diopters"] < 0.25  # 2 px of blur at 1 arcmin/px through 3.6 mm: 0.16 D


def test_sizes_that_differ_are_refused():
    image, reference, _ = capture(TrialLens(1.0))
    with pytest.raises(VissimInputError, match=r"96 x 96 px but the reference is 96 x 95 px"):
        _fit(image, reference[:, :95])


def test_a_blurred_reference_is_refused():
    image, reference, _ = capture(TrialLens(2.0))
    blurred_reference, _, _ = capture(TrialLens(1.0), noise=0.0)
    with pytest.raises(VissimInputError, match="reference is itself blurred"):
        _fit(image, blurred_reference)


def test_an_image_without_structure_is_refused():
    _, reference, _ = capture(TrialLens(1.0))
    flat = 0.5 + 0.002 * np.random.default_rng(3).standard_normal(reference.shape)
    with pytest.raises(VissimInputError, match="image has no structure"):
        _fit(flat, reference)


def test_the_wrong_reference_gives_a_flagged_failed_fit_not_an_answer():
    image, _, _ = capture(TrialLens(1.0), letter="K")
    _, other_letter, _ = capture(None, letter="O")
    fit = _fit(image, other_letter)
    record = fit.as_json()
    assert fit.status == "failed" and "unexplained" in fit.reason
    assert record["sphere_diopters"] is None and record["power_vector"] is None
