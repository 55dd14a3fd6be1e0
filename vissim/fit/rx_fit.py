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
"""

from __future__ import annotations

import logging
import math
import os
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.optimize
import scipy.signal

from vissim.checks import DEFAULT_WAVELENGTH_NM, size_text
from vissim.bench.dslr.bench import DslrBench
from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.checks import describe
from vissim.checks import pupil_diameter_mm as check_pupil_mm
from vissim.errors import VissimInputError, VissimTypeError
from vissim.fit.forward import FORWARD_MODES, ForwardModel
from vissim.fit.power_model import MAGNIFICATION_MODELS, power_model
from vissim.optics.prescription import LensPower
from vissim.progress import Progress, counter
from vissim.units import mrad_to_arcmin
from vissim.imaging.registration import register

__all__ = ["RxFit", "fit_rx", "check_fit_inputs", "sandwich_covariance", "residual_correlation_lag_px",
           "SIGN_MIN_DELTA_CHI2", "AXIS_MIN_CHI2", "MAX_UNEXPLAINED_FRACTION", "MODEL_ERROR_DIOPTERS", "Z95"]

log = logging.getLogger(__name__)

#: Another sign combination must fit worse by this many units of chi-square (3 standard errors) to be rejected.
SIGN_MIN_DELTA_CHI2 = 9.0
#: 95 % point of chi-square with 2 dof: the cylinder (J0, J45) differs from zero.
AXIS_MIN_CHI2 = 5.991
#: Below this cylinder the axis is reported undetermined whatever the statistics: the model's
#: systematic error (about 0.01 D per component on renders, measured) exceeds its noise there.
AXIS_MIN_CYLINDER_DIOPTERS = 0.125
#: A fitted blur narrower than this (px, largest principal meridian) is not resolved: the power is only bounded.
MIN_RESOLVED_BLUR_PX = 2.0
#: Candidates whose power vectors agree within this are one solution (a principal power ~ 0 has no sign).
SAME_SOLUTION_DIOPTERS = 0.05
#: A fit whose model leaves more than this fraction of the capture's variance unexplained failed.
MAX_UNEXPLAINED_FRACTION = 0.05
#: A sharp reference's steepest step is at least this fraction of its contrast (an edge spread <~ 3 px).
MIN_REFERENCE_SHARPNESS = 0.3
#: An image has structure when its contrast exceeds this many times its pixel-to-pixel noise.
MIN_CONTRAST_OVER_NOISE = 8.0
Z95 = 1.959964
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
UNCERTAINTY_NOTE = ("interval_95: +-1.96 sqrt(noise variance + model_error_diopters^2) per component; noise: the "
                    "sandwich covariance (curvature J^T J with the residual's own spread, uneven and spatially "
                    "correlated within correlation_lag_px); interval_95_noise: the noise alone; white_standard_error: "
                    "what white, even noise would give")
_SCAN_STEP_DIOPTERS = 0.25


# -- input checks --------------------------------------------------------------------------
def _as_image(value: Any, name: str) -> np.ndarray:
    if isinstance(value, (str, bytes, os.PathLike)):
        raise VissimTypeError(f"the {name} must be an ndarray of linear light (read a file with "
                              f"vissim.imageio.read_image(path).pixels), got {describe(value)}")
    array = np.asarray(value)
    if array.ndim == 3 and array.shape[2] == 3:
        raise VissimInputError(f"the {name} has 3 channels; fit one channel (or luminance) at a time")
    if array.ndim != 2 or min(array.shape) < 16:
        raise VissimInputError(f"the {name} must be one 2-D channel of at least 16 x 16 px, got shape {array.shape}")
    if not np.issubdtype(array.dtype, np.number) or np.iscomplexobj(array):
        raise VissimInputError(f"the {name} must hold real numbers, got dtype {array.dtype}")
    array = array.astype(np.float64)
    if not np.all(np.isfinite(array)):
        raise VissimInputError(f"the {name} has NaN or infinite pixels")
    return array


def _contrast(image: np.ndarray) -> float:
    low, high = np.percentile(image, (0.5, 99.5))
    return float(high - low)


def _pixel_noise(image: np.ndarray) -> float:
    """Robust pixel noise: the MAD of horizontal and vertical differences / sqrt 2 (0 for noise-free renders)."""
    diffs = np.concatenate([np.diff(image, axis=0).ravel(), np.diff(image, axis=1).ravel()])
    return float(1.4826 * np.median(np.abs(diffs - np.median(diffs))) / math.sqrt(2.0))


def reference_sharpness(reference: np.ndarray) -> float:
    """The steepest pixel step (99.9th percentile of |differences|) over the contrast: ~0.5-1 when sharp."""
    diffs = np.concatenate([np.abs(np.diff(reference, axis=0)).ravel(), np.abs(np.diff(reference, axis=1)).ravel()])
    return float(np.percentile(diffs, 99.9) / max(_contrast(reference), 1e-300))


def check_fit_inputs(image: Any, reference: Any) -> tuple[np.ndarray, np.ndarray]:
    """The two images as float64 arrays, or one `VissimInputError` naming what is wrong."""
    img = _as_image(image, "image")
    ref = _as_image(reference, "reference")
    if img.shape != ref.shape:
        raise VissimInputError(f"the image is {size_text(img.shape)} but the reference is {size_text(ref.shape)}; "
                               "they must match, pixel for pixel")
    for array, name in ((img, "image"), (ref, "reference")):
        contrast, noise = _contrast(array), _pixel_noise(array)
        if contrast <= max(MIN_CONTRAST_OVER_NOISE * noise, 1e-9 * max(1.0, float(np.abs(array).max()))):
            raise VissimInputError(f"the {name} has no structure to fit: contrast {contrast:.3g} against pixel "
                                   f"noise {noise:.3g} (linear units); it needs a chart or letter")
    sharpness = reference_sharpness(ref)
    if sharpness < MIN_REFERENCE_SHARPNESS:
        raise VissimInputError(
            f"the reference is itself blurred: its steepest step is {sharpness:.2f} of its contrast (a sharp "
            f"reference has >= {MIN_REFERENCE_SHARPNESS}); give the no-lens capture or the chart")
    return img, ref


# -- the result ----------------------------------------------------------------------------
_VECTOR_KEYS = ("M_diopters", "J0_diopters", "J45_diopters")


def _intervals_95(vector, sd) -> dict:
    """``[v - 1.96 sd, v + 1.96 sd]`` per power-vector component, by name."""
    return {k: [v - Z95 * s, v + Z95 * s] for k, v, s in zip(_VECTOR_KEYS, vector, sd)}


@dataclass(frozen=True)
class Solution:
    """One sign's best fit: effective power vector, its covariance, and the sum of squared residuals."""

    power_vector: tuple[float, float, float]
    covariance: np.ndarray = field(repr=False)
    ssr: float
    parameters: np.ndarray = field(repr=False)
    marked_vector: tuple[float, float, float] | None = None
    noise_covariance: np.ndarray | None = field(default=None, repr=False)
    uncertainty: dict = field(default_factory=dict)

    def spherocylinder(self) -> LensPower:
        return LensPower.from_power_vector(*self.power_vector).minus_cylinder()

    def summary(self, axis_determined: bool) -> dict:
        rx = self.spherocylinder()
        sd = np.sqrt(np.maximum(np.diag(self.covariance), 0.0))
        m, j0, j45 = self.power_vector
        j = math.hypot(j0, j45)
        e_par = np.array([j0, j45]) / j if j > 0 else np.array([1.0, 0.0])
        cov_j = self.covariance[1:, 1:]
        var_par = float(e_par @ cov_j @ e_par)
        var_perp = float(np.array([-e_par[1], e_par[0]]) @ cov_j @ np.array([-e_par[1], e_par[0]]))
        cov_m_par = float(self.covariance[0, 1:] @ e_par)
        sd_sphere = math.sqrt(max(self.covariance[0, 0] + var_par + 2 * cov_m_par, 0.0))
        sd_cyl = 2.0 * math.sqrt(max(var_par, 0.0))
        axis_half = math.degrees(Z95 * math.sqrt(max(var_perp, 0.0)) / (2.0 * j)) if j > 0 else math.inf
        out = {
            "sphere_diopters": rx.sphere_diopters,
            "cylinder_diopters": rx.cylinder_diopters,
            "axis_deg": rx.axis_deg if axis_determined else None,
            "power_vector": dict(zip(_VECTOR_KEYS, (m, j0, j45))),
            "interval_95": {
                **_intervals_95((m, j0, j45), sd),
                "sphere_diopters": [rx.sphere_diopters - Z95 * sd_sphere, rx.sphere_diopters + Z95 * sd_sphere],
                "cylinder_diopters": [rx.cylinder_diopters - Z95 * sd_cyl, min(0.0, rx.cylinder_diopters + Z95 * sd_cyl)],
                "axis_deg": ([rx.axis_deg - axis_half, rx.axis_deg + axis_half]
                             if axis_determined and axis_half < 90.0 else None),
            },
            "standard_error": dict(zip(_VECTOR_KEYS, sd)),
            "sum_squared_residuals": self.ssr,
        }
        if self.noise_covariance is not None:
            sd_noise = np.sqrt(np.maximum(np.diag(self.noise_covariance), 0.0))
            out["interval_95_noise"] = _intervals_95((m, j0, j45), sd_noise)
            out["uncertainty"] = dict(self.uncertainty, note=UNCERTAINTY_NOTE)
        if self.marked_vector is not None:
            out["trial_lens_marked_power"] = str(LensPower.from_power_vector(*self.marked_vector).minus_cylinder())
        return out


@dataclass(frozen=True)
class RxFit:
    """The result of `fit_rx`; `as_json` is the record the CLI and a campaign write.

    Attributes
    ----------
    status : str
        ``"ok"``, ``"unresolved"`` (the blur is below `MIN_RESOLVED_BLUR_PX`: only a bound
        on the power, ``power_bound_diopters`` in the record), ``"sign undetermined"`` (another
        combination of the principal powers' signs fits as well: the record's sphere, cylinder,
        axis and power vector are None and ``solutions`` lists the candidates with their delta
        chi2) or ``"failed"`` (``reason``).
    reason : str or None
        Why the fit failed or is unresolved.
    best : Solution
        The best sign combination: its power vector (M, J0, J45 in D), covariance (D^2) and sum
        of squared residuals.
    alternatives : tuple of (Solution, float)
        The other sign combinations and their delta chi2 over the best.
    sign_delta_chi2 : float or None
        The smallest delta chi2 of another sign combination (>= 9 for a determined sign).
    axis_determined : bool
        Whether the cylinder (>= 0.125 D) differs from zero at 95 %, so that its axis is reported.
    residual_psnr_db, residual_sigma, unexplained_fraction : float
        The fit's residual as a PSNR (dB), its standard deviation (image units) and the fraction
        of the image's variance the model leaves.
    nuisances, settings : dict
        The fitted nuisance parameters (shift in px, gain, offset, ...) and the fit's settings.
    evaluations : int
        Forward-model evaluations.
    seconds : float
        Wall time of the fit, s.
    model : ndarray
        The best model image, the capture's shape.

    Examples
    --------
    See `fit_rx`; ``power_vector`` and ``prescription`` are None unless ``status`` is "ok".
    """

    status: str
    reason: str | None
    best: Solution
    alternatives: tuple  # ((Solution, delta_chi2), ...): the other sign combinations, distinct from best
    sign_delta_chi2: float | None
    axis_determined: bool
    residual_psnr_db: float
    residual_sigma: float
    unexplained_fraction: float
    nuisances: dict
    settings: dict
    evaluations: int
    seconds: float
    model: np.ndarray = field(repr=False)

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def __repr__(self) -> str:
        """One short line: the fitted power, the residual and the fit's cost (`as_json` has the rest)."""
        if self.status == "ok":
            rx, m = self.effective_power, self.best.power_vector[0]
            power = (f"{rx} D" if self.axis_determined else
                     f"{rx.sphere_diopters:+.2f} D sphere, {rx.cylinder_diopters:+.2f} D cylinder (axis not determined)")
            found = f"effective power {power}, M {m:+.3f} D"
        else:
            found = f"reason {self.reason!r}"
        delta = "" if self.sign_delta_chi2 is None else f", sign delta chi2 {self.sign_delta_chi2:.3g}"
        return (f"RxFit(status={self.status!r}, {found}, residual PSNR {self.residual_psnr_db:.1f} dB, "
                f"unexplained {100 * self.unexplained_fraction:.2g} %{delta}, "
                f"{self.evaluations} evaluations in {self.seconds:.1f} s)")

    @property
    def power_vector(self) -> tuple[float, float, float] | None:
        return self.best.power_vector if self.status == "ok" else None

    @property
    def effective_power(self) -> LensPower | None:
        return self.best.spherocylinder() if self.status == "ok" else None

    def as_json(self) -> dict:
        best = self.best.summary(self.axis_determined)
        confident = self.status == "ok"
        out: dict[str, Any] = {
            "status": self.status,
            "reason": self.reason,
            "quantity": "sphero-cylinder added at the camera (vissim trial-lens effective_*), minus-cylinder form",
            "sphere_diopters": best["sphere_diopters"] if confident else None,
            "cylinder_diopters": best["cylinder_diopters"] if confident else None,
            "axis_deg": best["axis_deg"] if confident else None,
            "axis_determined": self.axis_determined if confident else False,
            "sign_determined": self.status == "ok",
            "power_bound_diopters": self.settings.get("resolution_power_diopters") if self.status == "unresolved" else None,
            "sign_delta_chi2": self.sign_delta_chi2,
            "power_vector": best["power_vector"] if confident else None,
            "interval_95": best["interval_95"] if confident else None,
            "interval_95_noise": best.get("interval_95_noise") if confident else None,
            "uncertainty": best.get("uncertainty"),
            "residual_psnr_db": self.residual_psnr_db,
            "residual_sigma": self.residual_sigma,
            "unexplained_variance_fraction": self.unexplained_fraction,
            "nuisances": self.nuisances,
            "settings": self.settings,
            "evaluations": self.evaluations,
            "seconds": self.seconds,
        }
        out["solutions"] = [dict(best, delta_chi2=0.0)]
        if self.status != "failed":
            out["solutions"] += [dict(s.summary(self.axis_determined), delta_chi2=d) for s, d in self.alternatives]
        return out


# -- the fit -------------------------------------------------------------------------------
class _Problem:
    """Parameters <-> model image and residual, with gain and offset projected out."""

    def __init__(self, forward: ForwardModel, image: np.ndarray, model, fit_focus: bool, fit_pupil: bool):
        self.forward, self.image, self.model = forward, image, model
        self.names = ["q_M", "q_J0", "q_J45", "shift_rows_px", "shift_cols_px", *model.nuisance_names]
        if fit_focus:
            self.names.append("focus_offset_diopters")
        if fit_pupil:
            self.names.append("log_pupil_scale")
        self.fit_focus, self.fit_pupil = fit_focus, fit_pupil
        self.n_model_nuisances = len(model.nuisance_names)
        self.evaluations = 0
        self._image_centred = image - image.mean()

    def unpack(self, theta: np.ndarray):
        q, shift = theta[:3], theta[3:5]
        i = 5
        nuisances = theta[i:i + self.n_model_nuisances]
        i += self.n_model_nuisances
        focus = theta[i] if self.fit_focus else 0.0
        i += self.fit_focus
        pupil = self.forward.pupil_diameter_mm * (math.exp(theta[i]) if self.fit_pupil else 1.0)
        return q, shift, nuisances, focus, pupil

    def prediction(self, theta: np.ndarray, forward: ForwardModel | None = None) -> np.ndarray:
        q, shift, nuisances, focus, pupil = self.unpack(theta)
        optics = self.model.optics(q, nuisances)
        self.evaluations += 1
        return (forward or self.forward).predict(optics.defocus + focus * np.eye(2), optics.magnification, shift, pupil)

    def projected(self, prediction: np.ndarray) -> tuple[np.ndarray, float, float]:
        centred = prediction - prediction.mean()
        norm = float(np.sum(centred * centred))
        gain = float(np.sum(centred * self._image_centred)) / norm if norm > 0 else 0.0
        offset = float(self.image.mean() - gain * prediction.mean())
        return gain * prediction + offset, gain, offset

    def residual(self, theta: np.ndarray, forward: ForwardModel | None = None) -> np.ndarray:
        fitted, _, _ = self.projected(self.prediction(theta, forward))
        return (self.image - fitted).ravel()

    def cost(self, theta: np.ndarray) -> float:
        r = self.residual(theta)
        return float(np.einsum("i,i->", r, r))


def _bounds(problem: _Problem, max_power: float, max_shift: float):
    lower = [-max_power, -max_power / 2, -max_power / 2] + [-max_shift] * 2
    upper = [max_power, max_power / 2, max_power / 2] + [max_shift] * 2
    for name in problem.names[5:]:
        limit = {"log_magnification": 0.2, "focus_offset_diopters": 3.0, "log_pupil_scale": 0.7}[name]
        lower.append(-limit)
        upper.append(limit)
    return np.array(lower), np.array(upper)


def _blur_starts(problem: _Problem, base: np.ndarray, max_power: float) -> list[np.ndarray]:
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


def _least_squares(problem: _Problem, start: np.ndarray, lower, upper, forward: ForwardModel | None = None):
    diff_step = 1e-4 if (forward or problem.forward).mode == "geometric" else 2e-3
    return scipy.optimize.least_squares(lambda t: problem.residual(t, forward), np.clip(start, lower, upper),
                                        bounds=(lower, upper), x_scale="jac", diff_step=diff_step, method="trf",
                                        xtol=1e-10, ftol=1e-10, gtol=1e-10, max_nfev=200)


def _fitted(result, advance):
    """``result``, after reporting one fit done (``advance``)."""
    advance()
    return result


def _effective_vector(model, q, nuisances) -> np.ndarray:
    p = model.optics(q, nuisances).effective_power
    return np.array([0.5 * (p[0, 0] + p[1, 1]), 0.5 * (p[0, 0] - p[1, 1]), 0.5 * (p[0, 1] + p[1, 0])])


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
    smoothed = [scipy.signal.fftconvolve(s, window, mode="same") for s in scores]
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


def _solution(problem: _Problem, result, shape: tuple[int, int], model_error_diopters: float
              ) -> tuple[Solution, np.ndarray, float]:
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
    g = np.zeros((3, 3))
    for k in range(3):  # d(effective)/d(q) by central differences
        h = 1e-5
        dq = np.zeros(3)
        dq[k] = h
        g[:, k] = (_effective_vector(problem.model, q + dq, nuisances) - _effective_vector(problem.model, q - dq, nuisances)) / (2 * h)
    cov_noise = g @ cov_theta[:3, :3] @ g.T
    cov_white_p = g @ cov_white[:3, :3] @ g.T
    cov_p = cov_noise + model_error_diopters ** 2 * np.eye(3)
    marked = tuple(float(v) for v in q) if problem.model.name == "bench" else None
    noise = {"correlation_lag_px": lag,
             "white_standard_error": [float(v) for v in np.sqrt(np.maximum(np.diag(cov_white_p), 0.0))],
             "noise_standard_error": [float(v) for v in np.sqrt(np.maximum(np.diag(cov_noise), 0.0))],
             "model_error_diopters": model_error_diopters}
    return (Solution(tuple(float(v) for v in p), cov_p, ssr, theta.copy(), marked, cov_noise, noise), cov_theta, sigma2)


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
    step, pupil, img, ref, model_error_diopters = _checked_arguments(image, reference, arcmin_per_px, pupil_diameter_mm,
                                                                     mode, magnification, model_error_diopters)
    model = power_model(magnification, bench)
    reach = _forward_reach_diopters(max_power_diopters, pupil, fit_focus_offset, fit_pupil)
    geometric = ForwardModel(ref, step, pupil, mode="geometric", max_power_diopters=reach, max_shift_px=max_shift_px)
    problem = _Problem(geometric, img, model, fit_focus_offset, fit_pupil)
    lower, upper = _bounds(problem, max_power_diopters, max_shift_px)

    stage_a, blur_names = _fit_blur(problem, ref, bench, max_power_diopters, max_shift_px, progress)
    results = _fit_signs(problem, stage_a, blur_names, lower, upper, progress)
    forward = geometric
    if mode == "wave":
        forward = ForwardModel(ref, step, pupil, mode="wave", wavelength_nm=wavelength_nm, max_power_diopters=reach,
                               max_shift_px=max_shift_px)
        results = _refine_in_wave_optics(problem, results, forward, lower, upper, progress)
    ranked = _rank_solutions(problem, results, img.shape, model_error_diopters)
    residual = _residual_statistics(problem, ranked.best_result.x, forward, img)
    largest_blur_px, resolution_power = _blur_size(ranked.best, pupil, step)
    on_bound = _parameters_on_bound(problem, ranked.best_result.x, lower, upper)
    status, reason = _status(residual.unexplained, on_bound, largest_blur_px, resolution_power, ranked.delta_chi2, model)
    axis_determined = status == "ok" and _axis_is_determined(ranked.best)

    nuisance_record = _nuisance_record(problem, ranked, residual, fit_pupil)
    settings = {"arcmin_per_px": step, "pupil_diameter_mm": pupil, "mode": mode, "wavelength_nm": wavelength_nm,
                "magnification_model": model.as_json(), "fit_focus_offset": fit_focus_offset, "fit_pupil": fit_pupil,
                "max_power_diopters": max_power_diopters, "max_shift_px": max_shift_px, "pixels": int(img.size),
                "parameters": problem.names, "sign_min_delta_chi2": SIGN_MIN_DELTA_CHI2,
                "axis_min_chi2": AXIS_MIN_CHI2, "max_unexplained_fraction": MAX_UNEXPLAINED_FRACTION,
                "min_resolved_blur_px": MIN_RESOLVED_BLUR_PX, "resolution_power_diopters": resolution_power,
                "axis_min_cylinder_diopters": AXIS_MIN_CYLINDER_DIOPTERS, "same_solution_diopters": SAME_SOLUTION_DIOPTERS,
                "model_error_diopters": model_error_diopters, "sign_chi2_deflation": ranked.inflation}
    seconds = time.perf_counter() - started
    log.info("fit-rx: %s, effective %s, PSNR %.1f dB, %d evaluations, %.1f s", status,
             ranked.best.spherocylinder().format(3), residual.psnr_db, problem.evaluations, seconds)
    return RxFit(status=status, reason=reason, best=ranked.best, alternatives=tuple(ranked.alternatives),
                 sign_delta_chi2=ranked.delta_chi2, axis_determined=axis_determined, residual_psnr_db=residual.psnr_db,
                 residual_sigma=math.sqrt(ranked.sigma2), unexplained_fraction=residual.unexplained,
                 nuisances=nuisance_record, settings=settings, evaluations=problem.evaluations, seconds=seconds,
                 model=residual.fitted)


# -- the stages of fit_rx ------------------------------------------------------------------
def _checked_arguments(image, reference, arcmin_per_px, pupil_diameter_mm, mode: str, magnification: str,
                       model_error_diopters) -> tuple[float, float, np.ndarray, np.ndarray, float]:
    """Checks: (arcmin per px, pupil mm, image, reference, model error D), or a `VissimInputError`."""
    step = check_arcmin_per_px(arcmin_per_px)
    pupil = check_pupil_mm(pupil_diameter_mm)
    if mode not in FORWARD_MODES:
        raise VissimInputError(f"fit mode must be one of {', '.join(FORWARD_MODES)}, got {mode!r}")
    if magnification not in MAGNIFICATION_MODELS:
        raise VissimInputError(f"magnification model must be one of {', '.join(MAGNIFICATION_MODELS)}, got {magnification!r}")
    img, ref = check_fit_inputs(image, reference)
    model_error_diopters = float(model_error_diopters)
    if not (math.isfinite(model_error_diopters) and 0.0 <= model_error_diopters <= 10.0):
        raise VissimInputError(f"the model error must be within 0-10 D, got {model_error_diopters!r} D")
    return step, pupil, img, ref, model_error_diopters


def _forward_reach_diopters(max_power_diopters: float, pupil: float, fit_focus_offset: bool, fit_pupil: bool) -> float:
    """The largest defocus the forward model must reach, as a power at the nominal pupil (D).

    The largest principal defocus the bounds allow (|M| + |J|, J0 and J45 within half of it),
    with the trial lens's vergence gain at the vertex, plus the focus offset; scaled up by the
    widest pupil the fit may try (mm; ``pupil`` the nominal one).
    """
    reach = max_power_diopters * (1.0 + math.sqrt(0.5)) * 1.1 + (3.0 if fit_focus_offset else 0.0)
    widest = pupil * (math.exp(0.7) if fit_pupil else 1.0)
    return reach * widest / pupil


def _fit_blur(problem: _Problem, ref: np.ndarray, bench: DslrBench | None, max_power_diopters: float,
              max_shift_px: float, progress: Progress | None):
    """Stages 1 and 2: the shift by cross-correlation, then the blur alone (module doc).

    The effective power with a free isotropic magnification (principal powers >= 0), from the
    best sphere of a scan and four cylinders around it; the best of those fits, and the names of
    its parameters.  Its evaluations count in ``problem``'s.
    """
    shift = register(problem.image, ref, upsample_factor=20).shift_px  # the image's content relative to the reference
    blur_model = power_model("free", bench) if problem.model.determines_sign else problem.model
    blur_problem = _Problem(problem.forward, problem.image, blur_model, problem.fit_focus, problem.fit_pupil)
    blur_lower, blur_upper = _bounds(blur_problem, max_power_diopters, max_shift_px)
    base = np.zeros(len(blur_problem.names))
    base[3:5] = np.clip(shift, -max_shift_px * 0.9, max_shift_px * 0.9)
    starts = list(_blur_starts(blur_problem, base, max_power_diopters))
    advance = counter(progress, "fit: blur from each start", len(starts))
    stage_a = min((_fitted(_least_squares(blur_problem, start, blur_lower, blur_upper), advance) for start in starts),
                  key=lambda r: r.cost)
    problem.evaluations += blur_problem.evaluations
    return stage_a, blur_problem.names


def _fit_signs(problem: _Problem, stage_a, blur_names: list[str], lower, upper, progress: Progress | None) -> list:
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
            results.append(scipy.optimize.OptimizeResult(x=np.clip(theta, lower, upper), cost=stage_a.cost,
                                                         jac=stage_a.jac, fun=stage_a.fun))
    return results


def _refine_in_wave_optics(problem: _Problem, results: list, wave: ForwardModel, lower, upper,
                           progress: Progress | None) -> list:
    """Stage 4 (wave mode): each candidate refitted in wave optics; ``problem`` predicts in wave optics from then on."""
    advance = counter(progress, "fit: wave refinement", len(results))
    results = [_fitted(_least_squares(problem, r.x, lower, upper, wave), advance) for r in results]
    problem.forward = wave
    return results


@dataclass(frozen=True)
class _Ranking:
    """The candidates ranked: the best fit and its statistics, the distinct others with their delta chi2."""

    best_result: Any
    best: Solution
    cov_theta: np.ndarray
    sigma2: float
    inflation: float
    alternatives: list
    delta_chi2: float | None


def _rank_solutions(problem: _Problem, results: list, shape: tuple[int, int], model_error_diopters: float) -> _Ranking:
    """Statistics: the best candidate's solution, and each distinct other's delta chi2 (module doc, "Sign").

    The residual variance counts white noise; the measured spread (sandwich) is wider on renders,
    so chi-square differences are deflated by the largest ratio of the two (never by less than 1).
    """
    results = sorted(results, key=lambda r: r.cost)
    best_result = results[0]
    best, cov_theta, sigma2 = _solution(problem, best_result, shape, model_error_diopters)
    white, measured = (np.square(best.uncertainty[k]) for k in ("white_standard_error", "noise_standard_error"))
    inflation = float(max(1.0, np.max(np.divide(measured, white, out=np.ones(3), where=white > 0))))
    alternatives: list[tuple[Solution, float]] = []
    for result in results[1:]:
        candidate = _solution(problem, result, shape, model_error_diopters)[0]
        distinct = np.max(np.abs(np.subtract(candidate.power_vector, best.power_vector))) > SAME_SOLUTION_DIOPTERS
        if distinct and all(np.max(np.abs(np.subtract(candidate.power_vector, a.power_vector))) > SAME_SOLUTION_DIOPTERS
                            for a, _ in alternatives):
            alternatives.append((candidate, (candidate.ssr - best.ssr) / (sigma2 * inflation)))
    delta_chi2 = min((d for _, d in alternatives), default=None)
    return _Ranking(best_result, best, cov_theta, sigma2, inflation, alternatives, delta_chi2)


@dataclass(frozen=True)
class _Residual:
    """The best model image (gain and offset applied) and how much of the capture it leaves."""

    fitted: np.ndarray
    gain: float
    offset: float
    unexplained: float  # fraction of the capture's variance
    psnr_db: float


def _residual_statistics(problem: _Problem, theta: np.ndarray, forward: ForwardModel, img: np.ndarray) -> _Residual:
    """The model image at ``theta`` and its residual against the capture: unexplained variance, PSNR."""
    prediction = problem.prediction(theta, forward)
    fitted, gain, offset = problem.projected(prediction)
    residual = img - fitted
    sst = float(np.sum((img - img.mean()) ** 2))
    unexplained = float(np.sum(residual ** 2)) / sst
    data_range = float(img.max() - img.min())
    mse = float(np.mean(residual ** 2))
    psnr = math.inf if mse == 0 else 10.0 * math.log10(data_range ** 2 / mse)
    return _Residual(fitted, gain, offset, unexplained, psnr)


def _blur_size(best: Solution, pupil: float, step: float) -> tuple[float, float]:
    """The best fit's largest blur diameter (px), and the power whose blur is `MIN_RESOLVED_BLUR_PX` (D)."""
    m, j0, j45 = best.power_vector
    principal = np.abs(np.linalg.eigvalsh(np.array([[m + j0, j45], [j45, m - j0]])))
    to_px = float(mrad_to_arcmin(pupil)) / step  # blur diameter in px per dioptre
    return float(principal.max()) * to_px, MIN_RESOLVED_BLUR_PX / to_px


def _parameters_on_bound(problem: _Problem, theta: np.ndarray, lower, upper) -> list[str]:
    """The names of the parameters that ended on (within 1e-6 of the range from) a bound."""
    return [name for name, x, lo, hi in zip(problem.names, theta, lower, upper) if min(x - lo, hi - x) <= 1e-6 * (hi - lo)]


def _status(unexplained: float, on_bound: list[str], largest_blur_px: float, resolution_power: float,
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


def _axis_is_determined(best: Solution) -> bool:
    """The cylinder differs from zero at 95 % (`AXIS_MIN_CHI2`) and is at least `AXIS_MIN_CYLINDER_DIOPTERS`."""
    j = np.array(best.power_vector[1:])
    cov_j = best.covariance[1:, 1:]
    try:
        axis_chi2 = float(j @ np.linalg.solve(cov_j, j))
    except np.linalg.LinAlgError:
        axis_chi2 = 0.0
    cylinder = 2.0 * float(np.hypot(*j))
    return axis_chi2 >= AXIS_MIN_CHI2 and cylinder >= AXIS_MIN_CYLINDER_DIOPTERS


def _nuisance_record(problem: _Problem, ranked: _Ranking, residual: _Residual, fit_pupil: bool) -> dict:
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
