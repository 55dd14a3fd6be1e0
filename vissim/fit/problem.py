"""The least-squares problem: the parameter vector <-> the model image and its residual against the capture.

The parameters are, in order, the power vector q (``q_M``, ``q_J0``, ``q_J45``, D), the shift
(``shift_rows_px``, ``shift_cols_px``), the magnification model's nuisances, and the optional
``focus_offset_diopters`` and ``log_pupil_scale``.  Gain and offset are solved in closed form at
every evaluation (variable projection).
"""

from __future__ import annotations

import math

import numpy as np

from vissim.fit.forward import ForwardModel

__all__ = ["FitProblem", "parameter_bounds"]


class FitProblem:
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


def parameter_bounds(problem: FitProblem, max_power: float, max_shift: float):
    """(lower, upper) of each parameter: power within ``max_power`` D (J within half), shift within ``max_shift`` px."""
    lower = [-max_power, -max_power / 2, -max_power / 2] + [-max_shift] * 2
    upper = [max_power, max_power / 2, max_power / 2] + [max_shift] * 2
    for name in problem.names[5:]:
        limit = {"log_magnification": 0.2, "focus_offset_diopters": 3.0, "log_pupil_scale": 0.7}[name]
        lower.append(-limit)
        upper.append(limit)
    return np.array(lower), np.array(upper)
