"""The fit's statistics: each candidate's power vector with its covariance, their ranking, the residual.

The noise covariance is a sandwich ``(J^T J)^-1 J^T S J (J^T J)^-1`` (`sandwich_covariance`)
with S measured from the residual within its correlation length
(`residual_correlation_lag_px`); the model's own error, `MODEL_ERROR_DIOPTERS`, is added in
quadrature (`vissim.fit.rx_fit`, "Intervals").
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from vissim.fit.forward import ForwardModel
from vissim.fit.problem import FitProblem
from vissim.fit.result import Solution
from vissim.imaging.metrics import psnr_db
from vissim.lazy_import import lazy_module

scipy_signal = lazy_module("scipy.signal")

__all__ = ["sandwich_covariance", "residual_correlation_lag_px", "fitted_solution", "rank_solutions", "Ranking",
           "residual_statistics", "Residual", "MODEL_ERROR_DIOPTERS", "SAME_SOLUTION_DIOPTERS",
           "CORRELATION_CUTOFF", "MAX_CORRELATION_LAG_PX"]

#: Candidates whose power vectors agree within this are one solution (a principal power ~ 0 has no sign).
SAME_SOLUTION_DIOPTERS = 0.05
#: The residual's correlation length is where its autocorrelation falls below this ...
CORRELATION_CUTOFF = 0.1
#: ... looked for up to this lag (px).
MAX_CORRELATION_LAG_PX = 12
#: Model error per power-vector component (D, one standard deviation), added in quadrature to the noise's.
#: Measured on the 14 must-show bench renders (256 spp, f/5, one K at LogMAR 1.0; spherical,
#: cylindrical and toric lenses from -4 to +4 D): the RMS of fit - vergence theory over their 42
#: power-vector components is 0.0047 D, their noise standard errors about 0.001 D; the rest,
#: sqrt(0.0047^2 - 0.001^2), is the model's (README, "Prescription recovery").
MODEL_ERROR_DIOPTERS = 0.0045


def sandwich_covariance(jac: np.ndarray, residual: np.ndarray, shape: tuple[int, int], lag_px: int) -> np.ndarray:
    """Covariance of least-squares parameters for spatially correlated, uneven residuals (module doc).

    ``(J^T J)^-1 J^T S J (J^T J)^-1`` with S estimated from the residual itself: the scores
    ``s_a = J_a r`` (one image per parameter) cross-correlated within ``lag_px`` under a 2-D
    Bartlett window, whose Fourier transform (a Fejer kernel) is non-negative, so the estimate
    is positive semi-definite (Newey and West 1987, in two dimensions).  ``lag_px = 0`` is
    White's estimator (uneven but uncorrelated residuals).  Scaled by N / (N - k) for the k
    fitted parameters (and gain and offset).
    """
    jac = np.asarray(jac, dtype=float)
    n, k = jac.shape
    bread = np.linalg.pinv(jac.T @ jac)
    scores = (jac * np.asarray(residual, dtype=float)[:, None]).T.reshape(k, *shape)
    taper = 1.0 - np.abs(np.arange(-lag_px, lag_px + 1)) / (lag_px + 1.0)
    window = np.outer(taper, taper)
    smoothed = [scipy_signal.fftconvolve(s, window, mode="same") for s in scores]
    meat = np.array([[float(np.sum(smoothed[a] * scores[b])) for b in range(k)] for a in range(k)])
    meat = 0.5 * (meat + meat.T)
    return n / max(n - k - 2, 1) * (bread @ meat @ bread)


def residual_correlation_lag_px(residual_image: np.ndarray, max_lag_px: int = MAX_CORRELATION_LAG_PX) -> int:
    """The residual's correlation length: the smallest lag (px) where its autocorrelation, averaged over
    rows and columns, falls below `CORRELATION_CUTOFF` (at most ``max_lag_px``)."""
    r = residual_image - residual_image.mean()
    var = float(np.mean(r * r))
    if var <= 0:
        return 0
    for lag in range(1, max_lag_px + 1):
        rho = 0.5 * (float(np.mean(r[lag:, :] * r[:-lag, :])) + float(np.mean(r[:, lag:] * r[:, :-lag]))) / var
        if rho < CORRELATION_CUTOFF:
            return lag
    return max_lag_px


def _effective_vector(model, q, nuisances) -> np.ndarray:
    p = model.optics(q, nuisances).effective_power
    return np.array([0.5 * (p[0, 0] + p[1, 1]), 0.5 * (p[0, 0] - p[1, 1]), 0.5 * (p[0, 1] + p[1, 0])])


def _effective_jacobian(model, q, nuisances) -> np.ndarray:
    """d(effective power vector)/d(q), 3 x 3, by central differences."""
    g = np.zeros((3, 3))
    for k in range(3):
        h = 1e-5
        dq = np.zeros(3)
        dq[k] = h
        g[:, k] = (_effective_vector(model, q + dq, nuisances) - _effective_vector(model, q - dq, nuisances)) / (2 * h)
    return g


def fitted_solution(problem: FitProblem, result, shape: tuple[int, int], model_error_diopters: float
                    ) -> tuple[Solution, np.ndarray, float]:
    """One least-squares ``result`` as a `Solution` (effective power, covariances), the parameters' covariance, sigma^2."""
    theta = result.x
    n_pixels = shape[0] * shape[1]
    ssr = float(2.0 * result.cost)
    dof = max(n_pixels - len(theta) - 2, 1)
    sigma2 = ssr / dof
    jac = np.asarray(result.jac)
    residual = np.asarray(result.fun)
    cov_white = sigma2 * np.linalg.pinv(jac.T @ jac)  # white, even noise: the curvature scaled by sigma^2
    lag = 2 * residual_correlation_lag_px(residual.reshape(shape))  # the Bartlett window halves the covariance at half its reach
    cov_theta = sandwich_covariance(jac, residual, shape, lag)
    q, _, nuisances, _, _ = problem.unpack(theta)
    p = _effective_vector(problem.model, q, nuisances)
    g = _effective_jacobian(problem.model, q, nuisances)
    cov_noise = g @ cov_theta[:3, :3] @ g.T
    cov_white_p = g @ cov_white[:3, :3] @ g.T
    cov_p = cov_noise + model_error_diopters ** 2 * np.eye(3)
    marked = tuple(float(v) for v in q) if problem.model.name == "bench" else None
    noise = {"correlation_lag_px": lag,
             "white_standard_error": [float(v) for v in np.sqrt(np.maximum(np.diag(cov_white_p), 0.0))],
             "noise_standard_error": [float(v) for v in np.sqrt(np.maximum(np.diag(cov_noise), 0.0))],
             "model_error_diopters": model_error_diopters}
    return (Solution(tuple(float(v) for v in p), cov_p, ssr, theta.copy(), marked, cov_noise, noise), cov_theta, sigma2)


@dataclass(frozen=True)
class Ranking:
    """The candidates ranked: the best fit and its statistics, the distinct others with their delta chi2."""

    best_result: Any
    best: Solution
    cov_theta: np.ndarray
    sigma2: float
    inflation: float
    alternatives: list
    delta_chi2: float | None


def rank_solutions(problem: FitProblem, results: list, shape: tuple[int, int], model_error_diopters: float) -> Ranking:
    """Statistics: the best candidate's solution, and each distinct other's delta chi2 (`vissim.fit.rx_fit`, "Sign").

    The residual variance counts white noise; the measured spread (sandwich) is wider on renders,
    so chi-square differences are deflated by the largest ratio of the two (never by less than 1).
    """
    results = sorted(results, key=lambda r: r.cost)
    best_result = results[0]
    best, cov_theta, sigma2 = fitted_solution(problem, best_result, shape, model_error_diopters)
    white, measured = (np.square(best.uncertainty[k]) for k in ("white_standard_error", "noise_standard_error"))
    inflation = float(max(1.0, np.max(np.divide(measured, white, out=np.ones(3), where=white > 0))))
    alternatives: list[tuple[Solution, float]] = []
    for result in results[1:]:
        candidate = fitted_solution(problem, result, shape, model_error_diopters)[0]
        distinct = np.max(np.abs(np.subtract(candidate.power_vector, best.power_vector))) > SAME_SOLUTION_DIOPTERS
        if distinct and all(np.max(np.abs(np.subtract(candidate.power_vector, a.power_vector))) > SAME_SOLUTION_DIOPTERS
                            for a, _ in alternatives):
            alternatives.append((candidate, (candidate.ssr - best.ssr) / (sigma2 * inflation)))
    delta_chi2 = min((d for _, d in alternatives), default=None)
    return Ranking(best_result, best, cov_theta, sigma2, inflation, alternatives, delta_chi2)


@dataclass(frozen=True)
class Residual:
    """The best model image (gain and offset applied) and how much of the capture it leaves."""

    fitted: np.ndarray
    gain: float
    offset: float
    unexplained: float  # fraction of the capture's variance
    psnr_db: float


def residual_statistics(problem: FitProblem, theta: np.ndarray, forward: ForwardModel, img: np.ndarray) -> Residual:
    """The model image at ``theta`` and its residual against the capture: unexplained variance, PSNR."""
    prediction = problem.prediction(theta, forward)
    fitted, gain, offset = problem.projected(prediction)
    residual = img - fitted
    sst = float(np.sum((img - img.mean()) ** 2))
    unexplained = float(np.sum(residual ** 2)) / sst
    data_range = float(img.max() - img.min())
    mse = float(np.mean(residual ** 2))
    return Residual(fitted, gain, offset, unexplained, psnr_db(mse, data_range))
