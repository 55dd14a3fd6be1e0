"""The fit's decisions: failed, unresolved, sign undetermined or ok, and whether the axis is reported.

Each threshold is a named constant here, written into the fit's ``settings``
(`vissim.fit.rx_fit`, "Sign", "Resolution" and "Failure").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vissim.fit.problem import FitProblem
from vissim.fit.result import Solution
from vissim.fit.statistics import Ranking, Residual
from vissim.units import mrad_to_arcmin

__all__ = ["decide", "Decision", "fit_status", "axis_is_determined", "blur_size", "parameters_on_bound", "SIGN_MIN_DELTA_CHI2",
           "AXIS_MIN_CHI2", "AXIS_MIN_CYLINDER_DIOPTERS", "MIN_RESOLVED_BLUR_PX", "MAX_UNEXPLAINED_FRACTION"]

#: Another sign combination must fit worse by this many units of chi-square (3 standard errors) to be rejected.
SIGN_MIN_DELTA_CHI2 = 9.0
#: 95 % point of chi-square with 2 dof: the cylinder (J0, J45) differs from zero.
AXIS_MIN_CHI2 = 5.991
#: Below this cylinder the axis is reported undetermined whatever the statistics: the model's
#: systematic error (about 0.01 D per component on renders, measured) exceeds its noise there.
AXIS_MIN_CYLINDER_DIOPTERS = 0.125
#: A fitted blur narrower than this (px, largest principal meridian) is not resolved: the power is only bounded.
MIN_RESOLVED_BLUR_PX = 2.0
#: A fit whose model leaves more than this fraction of the capture's variance unexplained failed.
MAX_UNEXPLAINED_FRACTION = 0.05


def blur_size(best: Solution, pupil: float, step: float) -> tuple[float, float]:
    """The best fit's largest blur diameter (px), and the power whose blur is `MIN_RESOLVED_BLUR_PX` (D)."""
    m, j0, j45 = best.power_vector
    principal = np.abs(np.linalg.eigvalsh(np.array([[m + j0, j45], [j45, m - j0]])))
    to_px = float(mrad_to_arcmin(pupil)) / step  # blur diameter in px per dioptre
    return float(principal.max()) * to_px, MIN_RESOLVED_BLUR_PX / to_px


def parameters_on_bound(problem: FitProblem, theta: np.ndarray, lower, upper) -> list[str]:
    """The names of the parameters that ended on (within 1e-6 of the range from) a bound."""
    return [name for name, x, lo, hi in zip(problem.names, theta, lower, upper) if min(x - lo, hi - x) <= 1e-6 * (hi - lo)]


def fit_status(unexplained: float, on_bound: list[str], largest_blur_px: float, resolution_power: float,
               delta_chi2: float | None, model) -> tuple[str, str | None]:
    """Decisions, first that applies: failed (unexplained variance, a bound), unresolved, sign undetermined, ok."""
    if unexplained > MAX_UNEXPLAINED_FRACTION:
        return "failed", (f"the model leaves {100 * unexplained:.1f} % of the image's variance unexplained (at most "
                          f"{100 * MAX_UNEXPLAINED_FRACTION:g} %): a different chart, crop, sampling or optics")
    if on_bound:
        return "failed", f"the fit ended on the bound of {', '.join(on_bound)}"
    if largest_blur_px < MIN_RESOLVED_BLUR_PX:
        return "unresolved", (
            f"the fitted blur ({largest_blur_px:.2f} px across) is below {MIN_RESOLVED_BLUR_PX:g} px: at this "
            "sampling a sub-pixel shift of the sharp reference and a small power look alike; the power added is "
            f"below about {resolution_power:.2f} D in each meridian, its value and sign are not determined")
    if delta_chi2 is not None and delta_chi2 < SIGN_MIN_DELTA_CHI2:
        return "sign undetermined", (
            f"a solution with other signs of the principal powers fits as well (delta chi2 {delta_chi2:.2f} < "
            f"{SIGN_MIN_DELTA_CHI2:g})" if model.determines_sign else
            f"magnification model {model.name!r} does not tie magnification to power; blur alone is even in "
            "each principal power")
    return "ok", None


def axis_is_determined(best: Solution) -> bool:
    """The cylinder differs from zero at 95 % (`AXIS_MIN_CHI2`) and is at least `AXIS_MIN_CYLINDER_DIOPTERS`."""
    j = np.array(best.power_vector[1:])
    cov_j = best.covariance[1:, 1:]
    try:
        axis_chi2 = float(j @ np.linalg.solve(cov_j, j))
    except np.linalg.LinAlgError:
        axis_chi2 = 0.0
    cylinder = 2.0 * float(np.hypot(*j))
    return axis_chi2 >= AXIS_MIN_CHI2 and cylinder >= AXIS_MIN_CYLINDER_DIOPTERS


@dataclass(frozen=True)
class Decision:
    """What the fit may report: its status and why, whether the axis is determined, and the power it resolves (D)."""

    status: str
    reason: str | None
    axis_determined: bool
    resolution_power_diopters: float


def decide(problem: FitProblem, ranked: Ranking, residual: Residual, pupil: float, step: float, lower,
           upper) -> Decision:
    """The decisions on the best candidate of ``ranked`` (pupil in mm, sampling ``step`` in arcmin per px)."""
    largest_blur_px, resolution_power = blur_size(ranked.best, pupil, step)
    on_bound = parameters_on_bound(problem, ranked.best_result.x, lower, upper)
    status, reason = fit_status(residual.unexplained, on_bound, largest_blur_px, resolution_power, ranked.delta_chi2,
                                problem.model)
    axis_determined = status == "ok" and axis_is_determined(ranked.best)
    return Decision(status, reason, axis_determined, resolution_power)
