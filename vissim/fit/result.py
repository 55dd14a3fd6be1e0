"""The fit's result: `Solution` (one sign combination's power vector and covariance) and `RxFit`, the record.

`RxFit.as_json` is the record the CLI and a campaign write; `Solution.summary` writes one
solution as sphere, cylinder and axis with their 95 % intervals (``+-`` `Z95` standard errors).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from vissim.optics.rx.prescription import LensPower

__all__ = ["RxFit", "Solution", "Z95", "UNCERTAINTY_NOTE"]

Z95 = 1.959964
UNCERTAINTY_NOTE = ("interval_95: +-1.96 sqrt(noise variance + model_error_diopters^2) per component; noise: the "
                    "sandwich covariance (curvature J^T J with the residual's own spread, uneven and spatially "
                    "correlated within correlation_lag_px); interval_95_noise: the noise alone; white_standard_error: "
                    "what white, even noise would give")
_VECTOR_KEYS = ("M_diopters", "J0_diopters", "J45_diopters")


def _intervals_95(vector, sd) -> dict:
    """``[v - 1.96 sd, v + 1.96 sd]`` per power-vector component, by name."""
    return {k: [v - Z95 * s, v + Z95 * s] for k, v, s in zip(_VECTOR_KEYS, vector, sd)}


def _principal_standard_errors(power_vector, covariance: np.ndarray) -> tuple[float, float, float]:
    """The sphere's and cylinder's standard errors (D) and the axis's 95 % half-width (deg, inf without cylinder)."""
    m, j0, j45 = power_vector
    j = math.hypot(j0, j45)
    e_par = np.array([j0, j45]) / j if j > 0 else np.array([1.0, 0.0])
    cov_j = covariance[1:, 1:]
    var_par = float(e_par @ cov_j @ e_par)
    var_perp = float(np.array([-e_par[1], e_par[0]]) @ cov_j @ np.array([-e_par[1], e_par[0]]))
    cov_m_par = float(covariance[0, 1:] @ e_par)
    sd_sphere = math.sqrt(max(covariance[0, 0] + var_par + 2 * cov_m_par, 0.0))
    sd_cyl = 2.0 * math.sqrt(max(var_par, 0.0))
    axis_half = math.degrees(Z95 * math.sqrt(max(var_perp, 0.0)) / (2.0 * j)) if j > 0 else math.inf
    return sd_sphere, sd_cyl, axis_half


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
        sd_sphere, sd_cyl, axis_half = _principal_standard_errors(self.power_vector, self.covariance)
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
        ``"ok"``, ``"unresolved"`` (the blur is below `vissim.fit.decisions.MIN_RESOLVED_BLUR_PX`:
        only a bound on the power, ``power_bound_diopters`` in the record), ``"sign undetermined"`` (another
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
