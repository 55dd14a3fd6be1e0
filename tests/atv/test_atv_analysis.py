"""Quadratic fit, confidence band and vertex intervals: recovery of known parameters.

Synthetic curves use the thesis's 17 trial lenses (§5.1) and a noise level like the spread
between the sessions of Appendix A (~0.01 code value).
"""

from pathlib import Path

import numpy as np
import pytest

from vissim.atv.analysis import analyse_curve, analyse_subject, fit_quadratic
from vissim.atv.data import THESIS_TRIAL_LENSES_DIOPTERS, load_subject
from vissim.errors import VissimInputError

LENSES = np.array(THESIS_TRIAL_LENSES_DIOPTERS)
SUBJECT_001 = Path(__file__).resolve().parents[2] / "validation" / "atv" / "subject_001.json"


def parabola(x, vertex, curvature=0.012, floor=0.07):
    return floor + curvature * (np.asarray(x) - vertex) ** 2


def test_noiseless_parabola_is_recovered_exactly():
    fit = fit_quadratic(LENSES, parabola(LENSES, 1.25) + 1e-9 * np.sin(LENSES))  # tiny residual, dof > 0
    assert fit.vertex_diopters == pytest.approx(1.25, abs=1e-6)
    assert fit.a == pytest.approx(0.012, rel=1e-6) and fit.has_minimum
    ci = fit.fieller_interval()
    assert ci.bounded and ci.lower_diopters < 1.25 < ci.upper_diopters and ci.upper_diopters - ci.lower_diopters < 1e-5


def test_coefficients_and_covariance_match_numpy_polyfit():
    # Independent implementation: numpy.polyfit(cov=True) scales by RSS / (n - 3) as well.
    rng = np.random.default_rng(1)
    y = parabola(LENSES, -0.7) + rng.normal(0, 0.01, LENSES.size)
    fit = fit_quadratic(LENSES, y)
    coef, cov = np.polyfit(LENSES, y, 2, cov=True)
    np.testing.assert_allclose(fit.coefficients, coef, rtol=1e-10)
    np.testing.assert_allclose(np.array(fit.covariance), cov, rtol=1e-8, atol=1e-18)


def test_vertex_intervals_cover_the_true_vertex_at_the_nominal_rate():
    # 200 simulated curves (true vertex +1.25 D, sd 0.01 code).  Fieller is exact under this model:
    # coverage 0.95, binomial sd 0.015 over 200 reps, so [0.90, 0.99] is a ~3-sigma acceptance band.
    # The delta method is approximate; with well-determined curvature it should be close (>= 0.88).
    rng = np.random.default_rng(20150527)
    truth = 1.25
    fieller = delta = band = 0
    reps = 200
    for _ in range(reps):
        fit = fit_quadratic(LENSES, parabola(LENSES, truth) + rng.normal(0.0, 0.01, LENSES.size))
        fieller += fit.fieller_interval(0.95).contains(truth)
        delta += fit.delta_interval(0.95).contains(truth)
        lo, hi = fit.band(0.0)
        band += lo <= parabola(0.0, truth) <= hi
    assert 0.90 <= fieller / reps <= 0.99
    assert 0.88 <= delta / reps <= 0.99
    assert 0.90 <= band / reps <= 0.99  # pointwise band of the mean curve at x = 0


def test_vertex_estimates_are_unbiased_over_repetitions():
    rng = np.random.default_rng(7)
    vertices = [fit_quadratic(LENSES, parabola(LENSES, -2.0) + rng.normal(0, 0.01, LENSES.size)).vertex_diopters for _ in range(200)]
    # sd of the vertex here is ~0.1 D; the mean of 200 is within 0.05 D (~7 standard errors).
    assert np.mean(vertices) == pytest.approx(-2.0, abs=0.05)


def test_downward_parabola_has_no_minimum_and_says_so():
    rng = np.random.default_rng(3)
    y = 0.3 - 0.01 * LENSES**2 + rng.normal(0, 0.005, LENSES.size)
    analysis = analyse_curve(LENSES, y, measured_se_diopters=1.0)
    assert not analysis.fit.has_minimum and analysis.vertex_diopters is None
    assert analysis.se_within_interval is None and analysis.vertex_minus_se_diopters is None
    assert any("no minimum" in n for n in analysis.notes)


def test_insignificant_curvature_gives_an_unbounded_fieller_interval():
    rng = np.random.default_rng(5)
    y = 0.1 + 0.01 * LENSES + 0.0005 * LENSES**2 + rng.normal(0, 0.02, LENSES.size)
    fit = fit_quadratic(LENSES, y)
    assert abs(fit.a) < 2.1 * np.sqrt(fit.covariance[0][0])  # not significant at 95 % (t(14) = 2.14)
    ci = fit.fieller_interval()
    assert not ci.bounded and ci.contains(1e6)
    assert fit.delta_interval().bounded  # the delta method cannot tell


def test_window_fits_only_lenses_near_the_minimum():
    y = np.maximum(0.06, 0.06 + 0.05 * (np.abs(LENSES - 1.0) - 0.5))  # a V with a flat floor at +1 D
    analysis = analyse_curve(LENSES, y, window_diopters=2.0)
    used = np.array(analysis.used_in_fit)
    assert used.sum() == np.sum(np.abs(LENSES - LENSES[np.argmin(y)]) <= 2.0)
    assert analysis.fit.n_points == used.sum()


def test_too_few_points_are_refused():
    with pytest.raises(VissimInputError, match=">= 4 points at >= 3 distinct lenses"):
        fit_quadratic([0, 1, 2], [0.1, 0.05, 0.1])


def test_subject_001_fits():
    # Values computed by this analysis from the transcribed Appendix A (the thesis prints no fitted
    # vertex); pinned to 0.01 D to catch changes.  SE from lines 1093/1096.
    results = {(a.eye, a.condition): a for a in analyse_subject(load_subject(SUBJECT_001))}
    assert set(results) == {("R", "with_drops"), ("L", "with_drops"), ("R", "without_drops"), ("L", "without_drops")}
    expected = {("R", "with_drops"): 0.11, ("L", "with_drops"): 0.17, ("R", "without_drops"): -3.14, ("L", "without_drops"): -2.71}
    for key, vertex in expected.items():
        assert results[key].vertex_diopters == pytest.approx(vertex, abs=0.01)
    # With one drop the vertex is ~1 D on the minus side of the SE; without drops ~4 D (accommodation).
    for eye in "RL":
        with_drops, without = results[(eye, "with_drops")], results[(eye, "without_drops")]
        assert with_drops.measured_se_diopters > with_drops.vertex_interval.upper_diopters
        assert without.vertex_diopters < with_drops.vertex_diopters - 2.0
    assert results[("L", "without_drops")].sessions_per_point[0] == 1  # -5.00 D L: only exam 2 printed
