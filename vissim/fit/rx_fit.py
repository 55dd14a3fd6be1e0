"""Fit the refraction a capture shows: `fit_rx` and its result record `RxFit`.

**What is fitted.**  The sphero-cylinder added at the camera (``vissim trial-lens``'s
``effective_*``; positive for a plus lens), in power vectors (M, J0, J45) so that the axis
never wraps.  The parameters are the power vector q of the magnification model
(`vissim.fit.power_model`: the trial lens's marked power on the bench, or the effective
power itself), the sub-pixel shift (rows, cols), and optional nuisances: a focus offset (a
sphere added to the defocus but not to the magnification), the pupil diameter (as a log
scale), an isotropic magnification (model ``free``).  Gain and offset are solved in closed
form at every evaluation (variable projection), so an exposure or paper-level difference
between capture and reference costs nothing.

**How.**  `scipy.optimize.least_squares` (trust region, finite-difference Jacobian) on
the pixel residual of `vissim.fit.forward.ForwardModel`.  Multi-started:

1. the shift is initialised by cross-correlation (`vissim.imaging.registration.register`)
   and then re-solved inside every least-squares step as two of the fitted parameters;
2. stage A fits the blur alone: the effective power with a free isotropic magnification, from
   the best sphere of a scan (J = 0) and four cylinders around it (axes 0, 45, 90, 135);
3. the blur ellipse is even in *each* principal power, so stage B starts the chosen model from
   the four combinations of the principal powers' signs (++, +-, -+, --);
4. in wave mode all this runs in geometric optics (cheap, analytic) and each candidate is
   refined in wave optics.

**Sign.**  Blur is even in each principal power; the signs are in the magnification (model
``bench``: the trial lens magnifies each meridian by its own power).  The candidates other than
the best (those that differ from it by more than `SAME_SOLUTION_DIOPTERS`: a principal
power near zero has no sign to decide) are kept with ``delta_chi2 = (SSR - SSR_best) / (sigma^2 kappa)``,
``kappa >= 1`` the largest ratio of the measured (sandwich) to the white variance of a power component;
the signs are *determined* when every one of them is worse by at least
`SIGN_MIN_DELTA_CHI2`.  Otherwise all plausible solutions are reported and the top-level
sphere, cylinder, axis and power vector are ``None``.

**Intervals.**  95 % intervals, ``+-1.96 sqrt(sigma_noise^2 + sigma_model^2)`` per power-vector
component.  The noise part is the curvature of the objective scaled by the measured residuals,
as a sandwich ``(J^T J)^-1 J^T S J (J^T J)^-1`` (`sandwich_covariance`): a render's
Monte-Carlo noise is uneven (it lives on the letter's blurred edges, where ``J`` is large, not on
the flat paper) and the model's mismatch is spatially correlated, so the textbook
``sigma^2 (J^T J)^-1`` with ``sigma^2 = SSR / (N - k)`` (kept in the record as
``white_standard_error``) was 2.5-2.9x too narrow on bench renders, measured against 40
re-renders with other seeds (``tests/fit/test_fit_coverage.py``), where the sandwich is within 10 %.  The model part, `MODEL_ERROR_DIOPTERS`, is the fit's error against
vergence theory on bench renders that noise does not explain (measured, see the constant);
``model_error_diopters=0`` gives noise-only intervals (also in the record, ``interval_95_noise``).
The effective power's covariance is carried from q by the model's Jacobian.  The axis is
*determined* when the cylinder differs from zero at 95 % (the 2-dof test
``J^T Cov_J^-1 J >=`` `AXIS_MIN_CHI2`); its interval is 1.96 sigma_perp / (2 |J|).

**Resolution.**  At coarse sampling a sub-pixel shift of the sharp reference and a small blur
look alike (measured: about 0.1 D of spurious power on a synthetic no-lens capture at 1 arcmin/px
and 3.6 mm), so a fit whose largest blur is below `MIN_RESOLVED_BLUR_PX` reports status
``"unresolved"`` with a bound on the power, not a value.

**Failure.**  Bad inputs (shapes, non-finite pixels, no structure, a blurred reference) raise
`VissimInputError`.  A fit is *failed* (``status == "failed"``, with a
reason, and no prescription) when the model leaves more than `MAX_UNEXPLAINED_FRACTION`
of the capture's variance unexplained, or a parameter ends on its bound.

**Where.**  Input checks: `vissim.fit.inputs`; the least-squares problem: `vissim.fit.problem`;
the stages: `vissim.fit.stages`; covariances and ranking: `vissim.fit.statistics`; the
thresholds and decisions: `vissim.fit.decisions`; the record: `vissim.fit.result`.
"""

from __future__ import annotations

import logging
import math
import time
from typing import Any

import numpy as np

from vissim.bench.dslr.bench import DslrBench
from vissim.checks import DEFAULT_WAVELENGTH_NM
from vissim.fit.decisions import (AXIS_MIN_CHI2, AXIS_MIN_CYLINDER_DIOPTERS, MAX_UNEXPLAINED_FRACTION,
                                  MIN_RESOLVED_BLUR_PX, SIGN_MIN_DELTA_CHI2, Decision, decide)
from vissim.fit.forward import ForwardModel
from vissim.fit.inputs import check_fit_arguments
from vissim.fit.power_model import power_model
from vissim.fit.problem import FitProblem, parameter_bounds
from vissim.fit.result import RxFit
from vissim.fit.stages import fit_blur, fit_signs, forward_reach_diopters, refine_in_wave_optics
from vissim.fit.statistics import (MODEL_ERROR_DIOPTERS, SAME_SOLUTION_DIOPTERS, Ranking, Residual, rank_solutions,
                                   residual_statistics)
from vissim.progress import Progress

__all__ = ["fit_rx"]

log = logging.getLogger(__name__)


def fit_rx(image: Any, reference: Any, *, arcmin_per_px: float, pupil_diameter_mm: float, mode: str = "geometric",
           magnification: str = "bench", bench: DslrBench | None = None, wavelength_nm: float = DEFAULT_WAVELENGTH_NM,
           fit_focus_offset: bool = False, fit_pupil: bool = False, max_power_diopters: float = 6.0,
           max_shift_px: float = 8.0, model_error_diopters: float = MODEL_ERROR_DIOPTERS,
           progress: Progress | None = None) -> RxFit:
    """Fit the sphero-cylinder added at the camera that turns ``reference`` into ``image`` (module doc).

    Parameters
    ----------
    image : ndarray (H, W)
        Linear light, one channel: the capture through the lenses.
    reference : ndarray (H, W)
        The same size and sampling as ``image``, sharp (no lens).
    arcmin_per_px
        The images' sampling.
    pupil_diameter_mm
        The camera's entrance pupil, mm.
    mode
        ``"geometric"`` (ray optics: a Mitsuba render has no diffraction) or ``"wave"``.
    magnification
        How magnification follows power (`vissim.fit.power_model`); ``"bench"`` needs ``bench``.
    bench
        The bench of ``magnification="bench"`` (its lenses are ignored: only vertex, chart and
        focus distances, glass).
    fit_focus_offset
        Fit a focus offset (dioptres) as a nuisance.  It trades against the power: use it only
        when magnification or diffraction can separate them.
    fit_pupil
        Fit the pupil (a log scale) as a nuisance; the same caution.
    model_error_diopters
        The model's own error per power-vector component (one standard deviation), added to the
        noise in the intervals; the default was measured on Mitsuba bench renders (module doc).
    progress
        ``progress(stage, done, total)`` after each least-squares fit: the blur's starts, the
        sign candidates, the wave refinements (`vissim.progress`).

    Returns
    -------
    RxFit
        ``status``, the best power vector ``best.power_vector`` = (M, J0, J45) in dioptres (the
        power the blur adds; `Solution.spherocylinder` writes it), its covariance and
        intervals, the other sign combinations and residual statistics.  ``image`` and
        ``reference`` are (H, W) arrays in the same orientation (row 0 at the top).

    Examples
    --------
    A letter blurred by 1 D of pure defocus (geometric optics, no magnification change); the
    sign of pure defocus cannot be told from the blur alone, so the status says so:

    >>> import vissim
    >>> chart = vissim.render_chart_angular(vissim.single_letter_spec("K", 1.0), arcmin_per_px=1.0)
    >>> front = vissim.Wavefront.from_prescription(vissim.Prescription(-1.0), pupil_diameter_mm=3.0)
    >>> psf = vissim.compute_psf(front, arcmin_per_px=1.0, mode="geometric")
    >>> blurred = vissim.blur_image(chart.pixels, psf, arcmin_per_px=1.0)
    >>> fit = vissim.fit_rx(blurred, chart.pixels, arcmin_per_px=1.0, pupil_diameter_mm=3.0,
    ...                     magnification="none")
    >>> fit.status, round(abs(fit.best.power_vector[0]), 1)
    ('sign undetermined', 1.0)
    """
    started = time.perf_counter()
    step, pupil, img, ref, model_error_diopters = check_fit_arguments(image, reference, arcmin_per_px, pupil_diameter_mm,
                                                                      mode, magnification, model_error_diopters)
    model = power_model(magnification, bench)
    reach = forward_reach_diopters(max_power_diopters, pupil, fit_focus_offset, fit_pupil)
    geometric = ForwardModel(ref, step, pupil, mode="geometric", max_power_diopters=reach, max_shift_px=max_shift_px)
    problem = FitProblem(geometric, img, model, fit_focus_offset, fit_pupil)
    lower, upper = parameter_bounds(problem, max_power_diopters, max_shift_px)

    stage_a, blur_names = fit_blur(problem, ref, bench, max_power_diopters, max_shift_px, progress)
    results = fit_signs(problem, stage_a, blur_names, lower, upper, progress)
    forward = geometric
    if mode == "wave":
        forward = ForwardModel(ref, step, pupil, mode="wave", wavelength_nm=wavelength_nm, max_power_diopters=reach,
                               max_shift_px=max_shift_px)
        results = refine_in_wave_optics(problem, results, forward, lower, upper, progress)
    ranked = rank_solutions(problem, results, img.shape, model_error_diopters)
    residual = residual_statistics(problem, ranked.best_result.x, forward, img)
    decision = decide(problem, ranked, residual, pupil, step, lower, upper)
    settings = _settings_record(step, pupil, mode, wavelength_nm, model, fit_focus_offset, fit_pupil, max_power_diopters,
                                max_shift_px, problem, decision.resolution_power_diopters, model_error_diopters,
                                ranked.inflation)
    return _record(problem, ranked, residual, decision, settings, fit_pupil, started)


def _record(problem: FitProblem, ranked: Ranking, residual: Residual, decision: Decision, settings: dict,
            fit_pupil: bool, started: float) -> RxFit:
    """The `RxFit` of the ranked candidates and the decisions; ``started`` the fit's start (`time.perf_counter`, s)."""
    nuisance_record = _nuisance_record(problem, ranked, residual, fit_pupil)
    seconds = time.perf_counter() - started
    log.info("fit-rx: %s, effective %s, PSNR %.1f dB, %d evaluations, %.1f s", decision.status,
             ranked.best.spherocylinder().format(3), residual.psnr_db, problem.evaluations, seconds)
    return RxFit(status=decision.status, reason=decision.reason, best=ranked.best,
                 alternatives=tuple(ranked.alternatives), sign_delta_chi2=ranked.delta_chi2,
                 axis_determined=decision.axis_determined, residual_psnr_db=residual.psnr_db,
                 residual_sigma=math.sqrt(ranked.sigma2), unexplained_fraction=residual.unexplained,
                 nuisances=nuisance_record, settings=settings, evaluations=problem.evaluations, seconds=seconds,
                 model=residual.fitted)


def _settings_record(step: float, pupil: float, mode: str, wavelength_nm: float, model, fit_focus_offset: bool,
                     fit_pupil: bool, max_power_diopters: float, max_shift_px: float, problem: FitProblem,
                     resolution_power: float, model_error_diopters: float, inflation: float) -> dict:
    """The record's settings: the fit's arguments, its parameters and every threshold it decided by."""
    return {"arcmin_per_px": step, "pupil_diameter_mm": pupil, "mode": mode, "wavelength_nm": wavelength_nm,
            "magnification_model": model.as_json(), "fit_focus_offset": fit_focus_offset, "fit_pupil": fit_pupil,
            "max_power_diopters": max_power_diopters, "max_shift_px": max_shift_px, "pixels": int(problem.image.size),
            "parameters": problem.names, "sign_min_delta_chi2": SIGN_MIN_DELTA_CHI2,
            "axis_min_chi2": AXIS_MIN_CHI2, "max_unexplained_fraction": MAX_UNEXPLAINED_FRACTION,
            "min_resolved_blur_px": MIN_RESOLVED_BLUR_PX, "resolution_power_diopters": resolution_power,
            "axis_min_cylinder_diopters": AXIS_MIN_CYLINDER_DIOPTERS, "same_solution_diopters": SAME_SOLUTION_DIOPTERS,
            "model_error_diopters": model_error_diopters, "sign_chi2_deflation": inflation}


def _nuisance_record(problem: FitProblem, ranked: Ranking, residual: Residual, fit_pupil: bool) -> dict:
    """The record's nuisances: shift, gain, offset, magnification, and each fitted nuisance with its standard error."""
    theta = ranked.best_result.x
    _, shift_fit, nuisances, _, pupil_fit = problem.unpack(theta)
    sd_theta = np.sqrt(np.maximum(np.diag(ranked.cov_theta), 0.0))
    record = {
        "shift_rows_px": float(shift_fit[0]), "shift_cols_px": float(shift_fit[1]),
        "shift_sign": "the image's content relative to the reference (positive: down, right)",
        "gain": residual.gain, "offset": residual.offset,
        "magnification_matrix": problem.model.optics(theta[:3], nuisances).magnification.tolist(),
    }
    for k, name in enumerate(problem.names[5:], start=5):
        record[name] = float(theta[k])
        record[name + "_standard_error"] = float(sd_theta[k])
    if fit_pupil:
        record["pupil_diameter_mm"] = pupil_fit
    return record
