"""Quadratic analysis of minimum visible vs trial-lens power (thesis §5.5, Figs 5.5-5.8).

Per eye and condition -- *with drops*: the cycloplegic session; *without drops*: the mean over
the sessions without drops at each lens (or, with ``average_sessions=False``, every session's
value as its own point) -- the minimum-visible code value ``y`` is fitted by ordinary least
squares with ``y = a x^2 + b x + c``, x the trial-lens power in dioptres.  Errors are taken as
independent, normal and of equal variance; the covariance of (a, b, c) is ``s^2 (X^T X)^-1``
with ``s^2 = RSS / (n - 3)``.  Numerics: the fit is solved by QR in ``t = (x - xc) / h`` (xc, h: the
centre and half-width of the lenses), and every statistic below is evaluated in t (quadratic
forms as squared norms ``|W^T d|^2``, ``V_t = W W^T``) and mapped back, so none depends on where
the origin or the unit of x lies.

* **Confidence band** of the mean curve: pointwise ``yhat(x) +- t(n-3) sqrt(x^T V x)``, x = (x^2, x, 1).
* **Vertex** ``x0 = -b / (2a)``: the trial-lens power of the least threshold.  If ``a <= 0`` the
  parabola has no minimum; the stationary point is reported but flagged, never used as an
  estimate of the spherical equivalent.
* **Vertex interval, primary: Fieller (1954)**, exact under the model above: the set of x0 with
  ``(b + 2a x0)^2 <= t^2 Var(b + 2a x0)`` (solved about the vertex, with cancellation-free roots).
  It is bounded only when the curvature is significant (``a^2 > t^2 Var(a)``); otherwise it is
  the whole line or the complement of an interval, and is reported as unbounded.  **Secondary:
  delta method**, ``x0 +- t se``, ``se^2 = g V g^T`` with ``g = (b / (2a^2), -1 / (2a))``:
  symmetric, and over-confident when a is poorly determined.
* **Comparison**: the measured spherical equivalent is S + C/2 of the cycloplegic autorefraction
  (the correcting lens, so a hyperope's is positive, like the trial lens that corrects him).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, replace
from typing import NamedTuple

import numpy as np

from vissim.atv.data import EYES, SubjectData
from vissim.checks import finite_number, instance_of, number_array
from vissim.errors import VissimInputError
from vissim.lazy_import import lazy_module

scipy_linalg = lazy_module("scipy.linalg")
scipy_stats = lazy_module("scipy.stats")

__all__ = ["CONDITIONS", "CurveAnalysis", "QuadraticFit", "VertexInterval", "analyse_curve",
           "analyse_subject", "fit_quadratic"]

log = logging.getLogger(__name__)

CONDITIONS = ("with_drops", "without_drops")
#: Fewest points a windowed fit uses (3 parameters + 2 degrees of freedom).
MIN_WINDOW_POINTS = 5
CONDITION_LABELS = {
    "with_drops": "with eye drops (cycloplegic session)",
    "without_drops": "without eye drops (mean of sessions)",
    "cycloplegia": "virtual, cycloplegia",
    "accommodation_free": "virtual, accommodation free",
}


@dataclass(frozen=True)
class VertexInterval:
    """A confidence set for the vertex (trial-lens power, D).

    ``kind``: ``"bounded"`` -- [lower, upper]; ``"exclusive"`` -- everything *outside*
    (lower, upper) (Fieller with insignificant curvature); ``"unbounded"`` -- the whole line.
    """

    lower_diopters: float
    upper_diopters: float
    kind: str
    method: str
    level: float

    @property
    def bounded(self) -> bool:
        return self.kind == "bounded"

    def contains(self, x_diopters: float) -> bool:
        if self.kind == "unbounded":
            return True
        inside = bool(self.lower_diopters <= x_diopters <= self.upper_diopters)
        return inside if self.kind == "bounded" else not inside

    def describe(self) -> str:
        if self.kind == "bounded":
            return f"[{self.lower_diopters:+.2f}, {self.upper_diopters:+.2f}] D"
        if self.kind == "exclusive":
            return f"unbounded (outside ({self.lower_diopters:+.2f}, {self.upper_diopters:+.2f}) D)"
        return "unbounded (whole line)"

    def as_json(self) -> dict:
        out = asdict(self)
        return out | {k: out[k] if math.isfinite(out[k]) else None for k in ("lower_diopters", "upper_diopters")}


class _Scaled(NamedTuple):
    """The fit in t = (x - xc) / h: coefficients (alpha, beta, gamma) and W with V_t = W W^T."""

    xc: float
    h: float
    coef: np.ndarray
    root: np.ndarray


def _centring(lo: float, hi: float) -> tuple[float, float]:
    return (lo + hi) / 2.0, ((hi - lo) / 2.0) or 1.0


def _to_x(xc: float, h: float) -> np.ndarray:
    """M with (a, b, c) = M (alpha, beta, gamma)."""
    return np.array([[1.0 / h**2, 0.0, 0.0], [-2.0 * xc / h**2, 1.0 / h, 0.0], [xc**2 / h**2, -xc / h, 1.0]])


@dataclass(frozen=True, eq=False)
class QuadraticFit:
    """OLS fit ``y = a x^2 + b x + c``; coefficients in code/D^2, code/D, code."""

    coefficients: tuple[float, float, float]
    covariance: tuple[tuple[float, float, float], ...]
    residual_sd_code: float
    dof: int
    n_points: int
    x_range_diopters: tuple[float, float]

    @property
    def a(self) -> float:
        return self.coefficients[0]

    @property
    def b(self) -> float:
        return self.coefficients[1]

    @property
    def has_minimum(self) -> bool:
        return self.a > 0.0

    @property
    def vertex_diopters(self) -> float:
        """Stationary point -b/(2a) (a minimum only if `has_minimum`); NaN for a == 0."""
        sc = self._scaled()
        return sc.xc + sc.h * self._vertex_t() if self.a != 0.0 else math.nan

    def _scaled(self) -> _Scaled:
        cached = self.__dict__.get("_scaled_cache")
        if cached is None:  # built from its fields: re-express them in t
            xc, h = _centring(*self.x_range_diopters)
            to_t = np.array([[h * h, 0.0, 0.0], [2.0 * xc * h, h, 0.0], [xc * xc, xc, 1.0]])  # inverse of _to_x
            cov_t = to_t @ np.asarray(self.covariance, dtype=float) @ to_t.T
            w, q = np.linalg.eigh((cov_t + cov_t.T) / 2.0)
            cached = _Scaled(xc, h, to_t @ np.asarray(self.coefficients, dtype=float), q * np.sqrt(np.maximum(w, 0.0)))
            object.__setattr__(self, "_scaled_cache", cached)
        return cached

    def _vertex_t(self) -> float:
        alpha, beta = self._scaled().coef[:2]
        return float(-beta / (2.0 * alpha))

    def _t(self, level: float) -> float:
        if not 0.0 < level < 1.0:
            raise VissimInputError(f"confidence level must be within (0, 1), got {level!r}")
        return float(scipy_stats.t.ppf(0.5 + level / 2.0, self.dof))

    def predict(self, x_diopters) -> np.ndarray:
        sc = self._scaled()
        t = (np.asarray(x_diopters, dtype=float) - sc.xc) / sc.h
        alpha, beta, gamma = sc.coef
        return (alpha * t + beta) * t + gamma

    def band(self, x_diopters, level: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
        """Pointwise confidence band of the mean curve at ``x_diopters``."""
        sc = self._scaled()
        t = (np.asarray(x_diopters, dtype=float) - sc.xc) / sc.h
        sd = np.linalg.norm(np.stack([t * t, t, np.ones_like(t)], axis=-1) @ sc.root, axis=-1)
        half = self._t(level) * sd
        y = self.predict(x_diopters)
        return y - half, y + half

    def delta_interval(self, level: float = 0.95) -> VertexInterval:
        if self.a == 0.0:
            return VertexInterval(-math.inf, math.inf, "unbounded", "delta", level)
        sc = self._scaled()
        tv = self._vertex_t()
        # se_t = sd(beta + 2 alpha tv) / (2 |alpha|): g V g^T with g = -(2 tv, 1) / (2 alpha)
        se = sc.h * float(np.linalg.norm(2.0 * tv * sc.root[0] + sc.root[1])) / (2.0 * abs(float(sc.coef[0])))
        half = self._t(level) * se
        vertex = self.vertex_diopters
        return VertexInterval(vertex - half, vertex + half, "bounded", "delta", level)

    def fieller_interval(self, level: float = 0.95) -> VertexInterval:
        sc = self._scaled()
        alpha, beta = (float(c) for c in sc.coef[:2])
        crit = self._t(level)
        k2 = crit * crit
        sd_a = float(np.linalg.norm(sc.root[0]))
        qa = (abs(alpha) - crit * sd_a) * (abs(alpha) + crit * sd_a)  # alpha^2 - k^2 Var(alpha)
        tc = self._vertex_t() if qa > 0.0 else 0.0  # expand about the vertex when it is bounded
        # bc: slope at tc (~0), wc its W-row; with u = 2 (t - tc) the set is
        # (bc + alpha u)^2 <= k^2 Var(bc + alpha u)  <=>  qa u^2 + 2 qb u + qc <= 0
        bc = beta + 2.0 * alpha * tc
        wc = 2.0 * tc * sc.root[0] + sc.root[1]
        vaa, vac, vcc = float(sc.root[0] @ sc.root[0]), float(sc.root[0] @ wc), float(wc @ wc)
        qb = alpha * bc - k2 * vac
        qc = bc * bc - k2 * vcc
        # qb^2 - qa qc with the alpha^2 bc^2 terms cancelled analytically (no difference of near-equals)
        disc = k2 * (qa * vcc + k2 * vac * vac + bc * (bc * vaa - 2.0 * alpha * vac))
        if qa == 0.0 or (qa < 0.0 and not disc > 0.0):
            return VertexInterval(-math.inf, math.inf, "unbounded", "fieller", level)
        q = -(qb + math.copysign(math.sqrt(max(disc, 0.0)), qb))
        roots = sorted(sc.xc + sc.h * (tc + u / 2.0) for u in (q / qa, qc / q if q != 0.0 else 0.0))
        return VertexInterval(roots[0], roots[1], "bounded" if qa > 0.0 else "exclusive", "fieller", level)

    def as_json(self) -> dict:
        return {
            "model": "minimum_visible_code = a x^2 + b x + c, x = trial lens (D), OLS",
            "a_code_per_diopter2": self.a,
            "b_code_per_diopter": self.b,
            "c_code": self.coefficients[2],
            "covariance": [list(r) for r in self.covariance],
            "residual_sd_code": self.residual_sd_code,
            "dof": self.dof,
            "n_points": self.n_points,
            "has_minimum": self.has_minimum,
            "vertex_diopters": self.vertex_diopters if math.isfinite(self.vertex_diopters) else None,
        }


def fit_quadratic(x_diopters: Sequence[float], y_code: Sequence[float]) -> QuadraticFit:
    """Least-squares parabola with its coefficient covariance (needs >= 4 points, >= 3 distinct x).

    Fits ``y = a x^2 + b x + c`` by ordinary least squares (QR on centred, scaled lens powers,
    so the covariance is well conditioned).

    Parameters
    ----------
    x_diopters : sequence of float
        Trial-lens powers, dioptres.
    y_code : sequence of float
        The minimum visible code value at each lens (one per power, same length).

    Returns
    -------
    QuadraticFit
        ``coefficients`` (a in code/D^2, b in code/D, c in code), their ``covariance``, the
        residual SD (code), degrees of freedom, and the vertex (``vertex_diopters``, a minimum
        when ``has_minimum``).

    Raises
    ------
    VissimInputError
        Lengths that differ, values that are not finite, or fewer than 4 points at 3 lenses.

    Examples
    --------
    >>> import vissim
    >>> fit = vissim.fit_quadratic([-1.0, -0.5, 0.0, 0.5, 1.0], [3.0, 1.2, 0.5, 1.3, 2.9])
    >>> round(fit.a, 3), fit.has_minimum, round(fit.vertex_diopters, 3), fit.dof
    (2.371, True, 0.004, 2)
    """
    x = number_array(x_diopters, "x_diopters (trial-lens powers)", "D").ravel()
    y = number_array(y_code, "y_code (minimum visible code values)", "code values").ravel()
    if x.shape != y.shape:
        raise VissimInputError(f"need one minimum-visible value per trial lens, got {x.size} lenses and {y.size} values")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise VissimInputError("trial-lens powers (D) and minimum-visible code values must be finite")
    if x.size < 4 or np.unique(x).size < 3:
        raise VissimInputError(
            f"a quadratic with an error estimate needs >= 4 points at >= 3 distinct lenses, got {x.size} points "
            f"at {np.unique(x).size} lenses (D)"
        )
    xc, h = _centring(float(x.min()), float(x.max()))
    t = (x - xc) / h
    q, r = np.linalg.qr(np.stack([t * t, t, np.ones_like(t)], axis=1))
    coef_t = scipy_linalg.solve_triangular(r, q.T @ y)
    residual = y - ((coef_t[0] * t + coef_t[1]) * t + coef_t[2])
    dof = x.size - 3
    s2 = float(residual @ residual) / dof
    root = math.sqrt(s2) * scipy_linalg.solve_triangular(r, np.eye(3))  # V_t = s^2 R^-1 R^-T = W W^T
    to_x = _to_x(xc, h)
    cov = (to_x @ root) @ (to_x @ root).T
    fit = QuadraticFit(coefficients=tuple(float(c) for c in to_x @ coef_t),
                       covariance=tuple(tuple(float(v) for v in row) for row in (cov + cov.T) / 2.0),
                       residual_sd_code=math.sqrt(s2), dof=dof, n_points=int(x.size),
                       x_range_diopters=(float(x.min()), float(x.max())))
    object.__setattr__(fit, "_scaled_cache", _Scaled(xc, h, coef_t, root))
    return fit


@dataclass(frozen=True, eq=False)
class CurveAnalysis:
    """One eye under one condition: the points, the fit, the vertex and the comparison with SE."""

    subject_id: str
    eye: str
    condition: str
    lens_diopters: tuple[float, ...]
    minimum_visible_code: tuple[float, ...]
    sessions_per_point: tuple[int, ...]
    fit: QuadraticFit
    vertex_interval: VertexInterval  # primary: Fieller
    vertex_interval_delta: VertexInterval
    measured_se_diopters: float | None
    level: float = 0.95
    notes: tuple[str, ...] = field(default=())
    used_in_fit: tuple[bool, ...] = field(default=())  # empty: every point
    window_diopters: float | None = None  # None: every lens fitted (the thesis)

    @property
    def label(self) -> str:
        return f"subject {self.subject_id}, {'right' if self.eye == 'R' else 'left' if self.eye == 'L' else self.eye} eye, {CONDITION_LABELS.get(self.condition, self.condition)}"

    @property
    def vertex_diopters(self) -> float | None:
        """The fitted minimum, or ``None`` when the parabola has none."""
        return self.fit.vertex_diopters if self.fit.has_minimum else None

    @property
    def data_minimum_lens_diopters(self) -> float:
        """The lens with the least measured value (the thesis's circles)."""
        return self.lens_diopters[int(np.argmin(self.minimum_visible_code))]

    @property
    def vertex_minus_se_diopters(self) -> float | None:
        if self.vertex_diopters is None or self.measured_se_diopters is None:
            return None
        return self.vertex_diopters - self.measured_se_diopters

    @property
    def se_within_interval(self) -> bool | None:
        if self.vertex_diopters is None or self.measured_se_diopters is None:
            return None
        return bool(self.vertex_interval.contains(self.measured_se_diopters))

    def as_json(self) -> dict:
        return {
            "subject_id": self.subject_id,
            "eye": self.eye,
            "condition": self.condition,
            "points": [
                {"trial_lens_diopters": x, "minimum_visible_code": y, "sessions": n}
                for x, y, n in zip(self.lens_diopters, self.minimum_visible_code, self.sessions_per_point)
            ],
            "fit": self.fit.as_json(),
            "fit_window_diopters": self.window_diopters,
            "used_in_fit": list(self.used_in_fit) if self.used_in_fit else [True] * len(self.lens_diopters),
            "level": self.level,
            "vertex_diopters": self.vertex_diopters,
            "vertex_interval_fieller": self.vertex_interval.as_json(),
            "vertex_interval_delta": self.vertex_interval_delta.as_json(),
            "measured_se_diopters": self.measured_se_diopters,
            "vertex_minus_se_diopters": self.vertex_minus_se_diopters,
            "se_within_fieller_interval": self.se_within_interval,
            "data_minimum_lens_diopters": self.data_minimum_lens_diopters,
            "notes": list(self.notes),
        }


def analyse_curve(
    lens_diopters: Sequence[float],
    minimum_visible_code: Sequence[float],
    *,
    measured_se_diopters: float | None = None,
    sessions_per_point: Sequence[int] | None = None,
    subject_id: str = "",
    eye: str = "",
    condition: str = "",
    level: float = 0.95,
    window_diopters: float | None = None,
) -> CurveAnalysis:
    """Fit one curve and derive its vertex, intervals and notes.

    ``window_diopters``: ``None`` fits every lens (the thesis); a half-width W fits only the lenses
    within W of the lens with the least value (a local parabola around the minimum).
    """
    x = np.asarray(lens_diopters, dtype=float)
    y = np.asarray(minimum_visible_code, dtype=float)
    if x.shape != y.shape or x.ndim != 1:
        raise VissimInputError(f"need one minimum-visible value per trial lens, got {x.size} lenses and {y.size} values")
    widened = None
    if window_diopters is None:
        used = np.ones(x.shape, dtype=bool)
    else:
        window = finite_number(window_diopters, "fit window", "D")
        if window <= 0:
            raise VissimInputError(f"fit window must be a positive half-width in D, got {window:g} D")
        distance = np.abs(x - x[int(np.argmin(y))])
        used = distance <= window + 1e-9
        if used.sum() < MIN_WINDOW_POINTS and x.size >= MIN_WINDOW_POINTS:
            used = np.zeros(x.shape, dtype=bool)
            used[np.argsort(distance, kind="stable")[:MIN_WINDOW_POINTS]] = True
            widened = f"the ±{window:g} D window held too few lenses; the {MIN_WINDOW_POINTS} lenses nearest the least value were fitted"
    fit = fit_quadratic(x[used], y[used])
    fieller = fit.fieller_interval(level)
    delta = fit.delta_interval(level)
    notes = [widened] if widened else []
    if not fit.has_minimum:
        notes.append(
            f"the fitted parabola opens {'downward' if fit.a < 0 else 'nowhere (a = 0)'} (a = {fit.a:.3g} code/D^2): "
            "it has no minimum, so no vertex estimates the spherical equivalent"
        )
    elif not fieller.bounded:
        notes.append("the curvature is not significant at this level: the Fieller interval of the vertex is unbounded")
    else:
        lo, hi = fit.x_range_diopters
        if not lo <= fit.vertex_diopters <= hi:
            notes.append(f"the vertex {fit.vertex_diopters:+.2f} D lies outside the measured lenses ({lo:+g} to {hi:+g} D): an extrapolation")
    counts = tuple(int(n) for n in sessions_per_point) if sessions_per_point is not None else (1,) * len(lens_diopters)
    return CurveAnalysis(subject_id=subject_id, eye=eye, condition=condition,
                         lens_diopters=tuple(float(x) for x in lens_diopters),
                         minimum_visible_code=tuple(float(y) for y in minimum_visible_code),
                         sessions_per_point=counts, fit=fit, vertex_interval=fieller, vertex_interval_delta=delta,
                         measured_se_diopters=measured_se_diopters, level=level, notes=tuple(notes),
                         used_in_fit=tuple(bool(u) for u in used),
                         window_diopters=None if window_diopters is None else float(window_diopters))


def analyse_subject(
    subject: SubjectData, *, level: float = 0.95, average_sessions: bool = True, window_diopters: float | None = None
) -> tuple[CurveAnalysis, ...]:
    """Both eyes, with and without drops (conditions without sessions are skipped).

    Parameters
    ----------
    subject : SubjectData
        From `vissim.load_subject`.
    level : float
        Confidence level of the vertex intervals (0-1).
    average_sessions : bool
        Average the sessions at each trial-lens power before fitting.
    window_diopters : float, optional
        Fit only lens powers within this many dioptres of the curve's minimum.

    Returns
    -------
    tuple of CurveAnalysis
        One per eye and condition: the points (lens power in D, minimum visible code), the
        quadratic fit, the vertex (best lens, D) with Fieller and delta-method intervals and
        the comparison with the measured spherical equivalent.

    Examples
    --------
    Needs ATV data files; see tutorial 6:

    >>> import vissim
    >>> subject = vissim.load_subject("subject_01.json")  # doctest: +SKIP
    >>> [(a.eye, a.condition) for a in vissim.analyse_subject(subject)]  # doctest: +SKIP
    [('OD', 'without_drops'), ('OS', 'without_drops')]
    """
    instance_of(subject, SubjectData, "analyse_subject's subject", "a SubjectData (from vissim.load_subject(path))")
    results = []
    for condition in CONDITIONS:
        drops = condition == "with_drops"
        n_sessions = len(subject.sessions(drops))
        if n_sessions == 0:
            log.info("subject %s has no session %s", subject.subject_id, condition.replace("_", " "))
            continue
        for eye in EYES:
            values = subject.minimum_visible(eye, drops)
            if average_sessions:
                lenses = list(values)
                ys = [float(np.mean(v)) for v in values.values()]
                counts = [len(v) for v in values.values()]
            else:
                lenses = [lens for lens, v in values.items() for _ in v]
                ys = [y for v in values.values() for y in v]
                counts = [1] * len(ys)
            analysis = analyse_curve(
                lenses, ys, measured_se_diopters=subject.measured_se_diopters(eye), sessions_per_point=counts,
                subject_id=subject.subject_id, eye=eye, condition=condition, level=level, window_diopters=window_diopters,
            )
            incomplete = [f"{lens:+.2f} D" for lens, v in values.items() if len(v) < n_sessions]
            if average_sessions and incomplete:
                analysis = replace(analysis, notes=analysis.notes + (
                    f"mean over fewer than the {n_sessions} sessions at {', '.join(incomplete)} (rows not printed)",))
            for note in analysis.notes:
                log.info("%s: %s", analysis.label, note)
            results.append(analysis)
    return tuple(results)
