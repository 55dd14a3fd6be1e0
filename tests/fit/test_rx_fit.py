"""Prescription fits of synthetic captures: sign, axis, ambiguity, refusals.

Captures come from vissim's own forward chain (``tests/fit/synthetic.py``: fine chart, bench
magnification, ray-traced or wave PSF, block means, Gaussian noise), not from the fit's model.
Truth is the power the bench's lens adds at the camera by vergence theory
(:meth:`vissim.bench.dslr.bench.DslrBench.viewing_setup`): what ``vissim trial-lens`` prints as
``effective_*`` for the lens as rendered.
"""

import numpy as np
import pytest

from vissim.errors import VissimInputError
from vissim.fit.rx_fit import fit_rx
from vissim.optics.rx.trial_lens import TrialLens

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
    with pytest.raises(VissimInputError, match=r"96 × 96 px but the reference is 95 × 96 px \(width × height\)"):
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


@pytest.mark.slow  # a whole campaign or fit: run with -m slow
def test_the_wrong_reference_gives_a_flagged_failed_fit_not_an_answer():
    image, _, _ = capture(TrialLens(1.0), letter="K")
    _, other_letter, _ = capture(None, letter="O")
    fit = _fit(image, other_letter)
    record = fit.as_json()
    assert fit.status == "failed" and "unexplained" in fit.reason
    assert record["sphere_diopters"] is None and record["power_vector"] is None


def test_the_sandwich_covariance_matches_monte_carlo_for_uneven_correlated_noise():
    """A linear model (two parameters on a 48 x 48 image) with noise 4x stronger on one half and
    smoothed over 3 px.  Over 300 fits (Monte Carlo's own error ~4 %), the sandwich standard errors
    (window twice the correlation length found, as fit_rx uses) are 0.75-1.1 of the spread of the
    estimates (measured when written: 0.93 and 0.80; a Bartlett window under-weights the longest
    lags), where the textbook sigma^2 (J^T J)^-1 gives under 0.6 of it (measured 0.39, 0.33)."""
    from scipy.ndimage import uniform_filter

    from vissim.fit.statistics import residual_correlation_lag_px, sandwich_covariance

    rng = np.random.default_rng(7)
    shape = (48, 48)
    rows, cols = np.mgrid[:48, :48]
    design = np.stack([np.sin(rows / 3.0) * (cols > 24), np.cos(cols / 4.0) * (rows > 10)], axis=-1).reshape(-1, 2)
    scale = np.where(cols > 24, 4.0, 1.0).ravel()
    estimates, sandwich_se, white_se = [], [], []
    for _ in range(300):
        noise = uniform_filter(rng.standard_normal(shape), 3, mode="wrap").ravel() * scale
        beta, *_ = np.linalg.lstsq(design, noise, rcond=None)
        residual = noise - design @ beta
        estimates.append(beta)
        lag = 2 * residual_correlation_lag_px(residual.reshape(shape))
        sandwich_se.append(np.sqrt(np.diag(sandwich_covariance(design, residual, shape, lag))))
        sigma2 = residual @ residual / (residual.size - 2)
        white_se.append(np.sqrt(np.diag(sigma2 * np.linalg.inv(design.T @ design))))
    spread = np.std(estimates, axis=0)
    ratio = np.mean(sandwich_se, axis=0) / spread
    assert np.all((ratio > 0.75) & (ratio < 1.1)), ratio
    assert np.all(np.mean(white_se, axis=0) / spread < 0.6)
