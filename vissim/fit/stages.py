"""The stages of `vissim.fit.rx_fit.fit_rx`: multi-started least squares in power vectors.

1. the shift by cross-correlation, then re-solved inside every least-squares step;
2. the blur alone (`fit_blur`): the effective power with a free isotropic magnification, from
   the best sphere of a scan (J = 0) and four cylinders around it (axes 0, 45, 90, 135);
3. the chosen magnification model from each combination of the principal powers' signs
   (`fit_signs`: the blur is even in each principal power);
4. in wave mode, each candidate refined in wave optics (`refine_in_wave_optics`).
"""

from __future__ import annotations

import math

import numpy as np

from vissim.bench.dslr.bench import DslrBench
from vissim.fit.forward import ForwardModel
from vissim.fit.power_model import power_model
from vissim.fit.problem import FitProblem, parameter_bounds
from vissim.imaging.registration import register
from vissim.lazy_import import lazy_module
from vissim.progress import Progress, counter

scipy_optimize = lazy_module("scipy.optimize")

__all__ = ["forward_reach_diopters", "fit_blur", "fit_signs", "refine_in_wave_optics"]

_SCAN_STEP_DIOPTERS = 0.25


def forward_reach_diopters(max_power_diopters: float, pupil: float, fit_focus_offset: bool, fit_pupil: bool) -> float:
    """The largest defocus the forward model must reach, as a power at the nominal pupil (D).

    The largest principal defocus the bounds allow (|M| + |J|, J0 and J45 within half of it),
    with the trial lens's vergence gain at the vertex, plus the focus offset; scaled up by the
    widest pupil the fit may try (mm; ``pupil`` the nominal one).
    """
    reach = max_power_diopters * (1.0 + math.sqrt(0.5)) * 1.1 + (3.0 if fit_focus_offset else 0.0)
    widest = pupil * (math.exp(0.7) if fit_pupil else 1.0)
    return reach * widest / pupil


def fit_blur(problem: FitProblem, ref: np.ndarray, bench: DslrBench | None, max_power_diopters: float,
             max_shift_px: float, progress: Progress | None):
    """Stages 1 and 2: the shift by cross-correlation, then the blur alone (module doc).

    The effective power with a free isotropic magnification (principal powers >= 0), from the
    best sphere of a scan and four cylinders around it; the best of those fits, and the names of
    its parameters.  Its evaluations count in ``problem``'s.
    """
    shift = register(problem.image, ref, upsample_factor=20).shift_px  # the image's content relative to the reference
    blur_model = power_model("free", bench) if problem.model.determines_sign else problem.model
    blur_problem = FitProblem(problem.forward, problem.image, blur_model, problem.fit_focus, problem.fit_pupil)
    blur_lower, blur_upper = parameter_bounds(blur_problem, max_power_diopters, max_shift_px)
    base = np.zeros(len(blur_problem.names))
    base[3:5] = np.clip(shift, -max_shift_px * 0.9, max_shift_px * 0.9)
    starts = list(_blur_starts(blur_problem, base, max_power_diopters))
    advance = counter(progress, "fit: blur from each start", len(starts))
    stage_a = min((_fitted(_least_squares(blur_problem, start, blur_lower, blur_upper), advance) for start in starts),
                  key=lambda r: r.cost)
    problem.evaluations += blur_problem.evaluations
    return stage_a, blur_problem.names


def fit_signs(problem: FitProblem, stage_a, blur_names: list[str], lower, upper, progress: Progress | None) -> list:
    """Stage 3: the chosen model from each combination of the principal powers' signs of ``stage_a``.

    A model that does not tie magnification to power cannot tell them apart: each combination
    is then ``stage_a``'s fit, its powers' signs flipped, without a new fit.
    """
    results = []
    signs = list(_sign_combinations(stage_a.x[:3]))
    determines_sign = problem.model.determines_sign
    advance = counter(progress if determines_sign else None, "fit: each sign of the powers", len(signs))
    for vector in signs:
        theta = np.zeros(len(problem.names))
        theta[:5] = (*vector, *stage_a.x[3:5])
        for name in problem.names[5:]:
            theta[problem.names.index(name)] = stage_a.x[blur_names.index(name)]
        if determines_sign:
            results.append(_fitted(_least_squares(problem, theta, lower, upper), advance))
        else:  # the blur is even in each principal power: every combination fits alike
            results.append(scipy_optimize.OptimizeResult(x=np.clip(theta, lower, upper), cost=stage_a.cost,
                                                         jac=stage_a.jac, fun=stage_a.fun))
    return results


def refine_in_wave_optics(problem: FitProblem, results: list, wave: ForwardModel, lower, upper,
                          progress: Progress | None) -> list:
    """Stage 4 (wave mode): each candidate refitted in wave optics; ``problem`` predicts in wave optics from then on."""
    advance = counter(progress, "fit: wave refinement", len(results))
    results = [_fitted(_least_squares(problem, r.x, lower, upper, wave), advance) for r in results]
    problem.forward = wave
    return results


def _blur_starts(problem: FitProblem, base: np.ndarray, max_power: float) -> list[np.ndarray]:
    """Stage A starts: the best sphere of a scan (J = 0), and four cylinders around it (axes 0, 45, 90, 135)."""
    def at(m, j0, j45):
        theta = base.copy()
        theta[:3] = (m, j0, j45)
        return theta

    spheres = np.arange(0.0, max_power * 0.8, _SCAN_STEP_DIOPTERS)
    costs = [problem.cost(at(m, 0.0, 0.0)) for m in spheres]
    m0 = float(spheres[int(np.argmin(costs))])
    h = max(0.25, 0.4 * m0)
    return [at(m0, 0.0, 0.0)] + [at(m0, h * c, h * s) for c, s in ((1, 0), (-1, 0), (0, 1), (0, -1))]


def _sign_combinations(power_vector) -> list[tuple[float, float, float]]:
    """The four power vectors with the blur of ``power_vector``: each principal power's sign flipped or not."""
    m, j0, j45 = power_vector
    values, vectors = np.linalg.eigh(np.array([[m + j0, j45], [j45, m - j0]]))
    out = []
    for s1 in (1.0, -1.0):
        for s2 in (1.0, -1.0):
            d = vectors @ np.diag([s1 * abs(values[0]), s2 * abs(values[1])]) @ vectors.T
            out.append((0.5 * (d[0, 0] + d[1, 1]), 0.5 * (d[0, 0] - d[1, 1]), d[0, 1]))
    return out


def _least_squares(problem: FitProblem, start: np.ndarray, lower, upper, forward: ForwardModel | None = None):
    diff_step = 1e-4 if (forward or problem.forward).mode == "geometric" else 2e-3
    return scipy_optimize.least_squares(lambda t: problem.residual(t, forward), np.clip(start, lower, upper),
                                        bounds=(lower, upper), x_scale="jac", diff_step=diff_step, method="trf",
                                        xtol=1e-10, ftol=1e-10, gtol=1e-10, max_nfev=200)


def _fitted(result, advance):
    """``result``, after reporting one fit done (``advance``)."""
    advance()
    return result
