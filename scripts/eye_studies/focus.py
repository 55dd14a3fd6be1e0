"""Chromatic focus on renders: the trial-lens sphere that focuses a letter best, at 450, 550 and 650 nm.

* **Renders**: `vissim.render.eye_render` (a Sloan letter at ``chart_distance_m``, a trial lens of
  sphere S at 12 mm, a schematic eye relaxed), monochromatic on the mono variant; the lens in
  spectacle crown at the render's wavelength (`eye_render.eye_scene_dict`: n_d 1.523, V_d 58.6,
  Cauchy, `vissim.optics.rx.glass`).
* **Sweep**: one lattice of spheres for every wavelength, ``step_diopters`` apart (multiples of the
  step, not centred on any prediction), covering each wavelength's predicted best sphere ± ``margin``.
* **Sharpness**: the letter's gradient energy, G(I) = Σ (I[r, c+1] − I[r, c])² + (I[r+1, c] − I[r, c])²
  over the image, I normalised by its white (mean of the top 5 % of pixels of the sweep's sharpest
  render), without the render noise's share: two renders A, B of independent seeds, and
  G((A + B)/2) − G(A − B)/4 (the noise's expected share of the first term is the second: the
  difference holds twice the noise variance, the mean half of it).
* **Peak**: a Gaussian through the ``fit_points`` samples centred on the largest: a least-squares
  parabola in log(sharpness) against S; its vertex is the best-focus sphere.
* **Prediction** (`predicted_best_sphere_diopters`): the sphere S whose paraxial residual refraction
  (`vissim.optics.eyes.spectacles.residual_refraction`: the eye's dispersion, traced paraxially, and
  the crown lens's, at the spectacle plane in front of the lens) equals the chart's vergence at that
  plane.  The thick lens is the bench's (`realistic_center_thickness_mm`, 1 mm minimum edge and
  centre, ``PREDICTION_APERTURE_MM``); its thickness moves the predicted differences by < 1e-3 D.
  The eye's own part, reported beside it, is the corneal-plane LCA of `vissim.optics.eyes.lca.lca_curve`
  over the render's pupil: paraxial (y-nu) and traced (the traced wavefront's paraxial refraction);
  the lens's share is the prediction less the paraxial LCA, and "traced LCA + lens" their sum.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np

from vissim.errors import VissimInputError
from vissim.optics.eyes.defaults import DEFAULT_EYE_MODEL, DEFAULT_SPECTACLE_VERTEX_MM

__all__ = ["FocusSweep", "ChromaticFocus", "predicted_best_sphere_diopters", "gradient_energy", "denoised_gradient_energy", "gaussian_peak",
           "sphere_lattice", "chromatic_focus"]

#: The lens aperture the predicted lens's thickness is computed for, mm (its effect: module doc).
PREDICTION_APERTURE_MM = 20.0
#: The study's pupil, mm: the entrance pupil its chromatic focus is measured over.
FOCUS_STUDY_PUPIL_MM = 3.0
WAVELENGTHS_NM = (450.0, 550.0, 650.0)
REFERENCE_NM = 550.0


def _thick_lens(sphere_diopters: float, aperture_mm: float = PREDICTION_APERTURE_MM):
    from vissim.bench.lenses.holder import physical_lens
    from vissim.optics.rx.trial_lens import CROWN_GLASS_INDEX, TrialLens

    return physical_lens(TrialLens(sphere_diopters, 0.0, 0.0), aperture_mm, CROWN_GLASS_INDEX)  # the bench's rule


def predicted_best_sphere_diopters(model: str, wavelength_nm: float, chart_distance_m: float,
                                   vertex_mm: float = DEFAULT_SPECTACLE_VERTEX_MM, aperture_mm: float = PREDICTION_APERTURE_MM) -> float:
    """The trial sphere, D, that images the chart on the retina at ``wavelength_nm`` (paraxial; module doc)."""
    from vissim.optics.eyes.models import eye_model
    from vissim.optics.eyes.spectacles import residual_refraction

    eye = eye_model(model)

    def mismatch(sphere: float) -> float:
        refraction = residual_refraction(eye, (_thick_lens(sphere, aperture_mm),), vertex_mm,
                                         wavelength_nm=wavelength_nm)
        chart_vergence = -1000.0 / (1000.0 * chart_distance_m - refraction.plane_distance_mm)
        return refraction.power_vector_diopters[0] - chart_vergence

    s0, s1 = 0.0, -1.0
    f0, f1 = mismatch(s0), mismatch(s1)
    for _ in range(30):  # secant: the residual falls ~1 D per dioptre of lens
        if abs(f1) < 1e-10:
            break
        s0, s1, f0 = s1, s1 - f1 * (s1 - s0) / (f1 - f0), f1
        f1 = mismatch(s1)
    return float(s1)


def gradient_energy(image: np.ndarray, white: float) -> float:
    """Σ of squared forward differences along rows and columns of ``image / white`` (module doc)."""
    scaled = np.asarray(image, dtype=float) / white
    return float(np.sum(np.diff(scaled, axis=0) ** 2) + np.sum(np.diff(scaled, axis=1) ** 2))


def denoised_gradient_energy(first: np.ndarray, second: np.ndarray, white: float) -> float:
    """G of the two renders' mean less the render noise's expected share, G(A − B)/4 (module doc)."""
    a, b = np.asarray(first, dtype=float), np.asarray(second, dtype=float)
    return gradient_energy(0.5 * (a + b), white) - 0.25 * gradient_energy(a - b, white)


def gaussian_peak(spheres_diopters, scores, fit_points: int = 5) -> float:
    """The vertex of a parabola fitted (least squares) to log(score) over the ``fit_points`` samples
    centred on the largest score: a Gaussian's peak, D."""
    s = np.asarray(spheres_diopters, dtype=float)
    y = np.asarray(scores, dtype=float)
    if len(s) < fit_points or fit_points < 3 or np.any(y <= 0.0):
        raise VissimInputError(f"a peak fit needs >= {max(fit_points, 3)} positive scores, got {len(s)}")
    i = int(np.argmax(y))
    lo = min(max(i - fit_points // 2, 0), len(s) - fit_points)
    if i in (0, len(s) - 1):
        raise VissimInputError(f"the sharpest render is at the sweep's end ({s[i]:+.4f} D): widen the sweep")
    a, b, _ = np.polyfit(s[lo:lo + fit_points], np.log(y[lo:lo + fit_points]), 2)
    if a >= 0.0:
        raise VissimInputError("the sharpness has no maximum near the sweep's best sample")
    return float(-b / (2.0 * a))


def sphere_lattice(centres_diopters, margin_diopters: float, step_diopters: float) -> np.ndarray:
    """Multiples of ``step_diopters`` covering every centre ± ``margin_diopters``."""
    lo = math.floor((min(centres_diopters) - margin_diopters) / step_diopters)
    hi = math.ceil((max(centres_diopters) + margin_diopters) / step_diopters)
    return step_diopters * np.arange(lo, hi + 1)


@dataclass(frozen=True)
class FocusSweep:
    """One wavelength's sweep: spheres (D), their sharpness, the fitted best sphere and the prediction."""

    wavelength_nm: float
    spheres_diopters: tuple[float, ...]
    sharpness: tuple[float, ...]
    best_sphere_diopters: float
    predicted_sphere_diopters: float
    seconds: float


@dataclass(frozen=True)
class ChromaticFocus:
    """The study's result: per wavelength a `FocusSweep`; differences against `REFERENCE_NM`, D."""

    model: str
    pupil_mm: float
    sweeps: tuple[FocusSweep, ...]
    traced_lca_diopters: dict = field(default_factory=dict)
    paraxial_lca_diopters: dict = field(default_factory=dict)
    seconds: float = 0.0

    def sweep(self, wavelength_nm: float) -> FocusSweep:
        return next(s for s in self.sweeps if s.wavelength_nm == wavelength_nm)

    def rendered_difference_diopters(self, wavelength_nm: float) -> float:
        return self.sweep(wavelength_nm).best_sphere_diopters - self.sweep(REFERENCE_NM).best_sphere_diopters

    def predicted_difference_diopters(self, wavelength_nm: float) -> float:
        return self.sweep(wavelength_nm).predicted_sphere_diopters - self.sweep(REFERENCE_NM).predicted_sphere_diopters

    def lens_share_diopters(self, wavelength_nm: float) -> float:
        """The prediction less the eye's own (paraxial, corneal-plane) LCA: the crown lens's dispersion and
        the vertex distance's share."""
        return self.predicted_difference_diopters(wavelength_nm) - self.paraxial_lca_diopters[wavelength_nm]

    def traced_difference_diopters(self, wavelength_nm: float) -> float:
        """The traced LCA (`vissim.optics.eyes.lca.lca_curve`, the traced wavefront's paraxial refraction over
        the render's pupil) plus the lens's share."""
        return self.traced_lca_diopters[wavelength_nm] + self.lens_share_diopters(wavelength_nm)


def _sweep(base, spheres, wavelength_nm: float, predicted: float) -> FocusSweep:
    from vissim.render.eye_render import render_eye

    start = time.perf_counter()
    pairs = []
    for sphere in spheres:
        pair = []
        for seed in (base.seed, base.seed + 1):
            settings = dataclasses.replace(base, wavelength_nm=wavelength_nm, lens=(float(sphere), 0.0, 0.0), seed=seed)
            pair.append(render_eye(settings).pixels.astype(float))  # its lens in crown at that wavelength
        pairs.append(pair)
    sharpest = pairs[int(np.argmax([gradient_energy(a + b, 2.0) for a, b in pairs]))][0]
    white = float(np.mean(np.sort(sharpest, axis=None)[-max(1, sharpest.size // 20):]))
    scores = [denoised_gradient_energy(a, b, white) for a, b in pairs]
    best = gaussian_peak(spheres, scores)
    return FocusSweep(wavelength_nm, tuple(float(s) for s in spheres), tuple(scores), best, predicted,
                      time.perf_counter() - start)


def chromatic_focus(*, model: str = DEFAULT_EYE_MODEL, pupil_mm: float = FOCUS_STUDY_PUPIL_MM, wavelengths_nm=WAVELENGTHS_NM,
                    step_diopters: float = 0.0625, margin_diopters: float = 0.375, spp: int = 256, seed: int = 0,
                    size_px: tuple[int, int] = (64, 64), arcmin_per_px: float = 0.5, logmar: float = 0.6,
                    chart_distance_m: float = 6.0) -> ChromaticFocus:
    """Run the study (module doc): a `ChromaticFocus`."""
    from vissim.optics.eyes.lca import lca_curve
    from vissim.optics.eyes.models import eye_model
    from vissim.render.eye_render import EyeRender

    if not 0.0 < step_diopters <= 0.125:
        raise VissimInputError(f"sphere step must be within (0, 0.125] D, got {step_diopters:g} D")
    start = time.perf_counter()
    predicted = {w: predicted_best_sphere_diopters(model, w, chart_distance_m) for w in wavelengths_nm}
    spheres = sphere_lattice(list(predicted.values()), margin_diopters, step_diopters)
    base = EyeRender(model=model, pupil_mm=pupil_mm, size_px=size_px, arcmin_per_px=arcmin_per_px, spp=spp,
                     seed=seed, chart_distance_m=chart_distance_m, logmar=logmar, letter="K")
    sweeps = []
    for w in wavelengths_nm:
        own = spheres[np.abs(spheres - predicted[w]) <= margin_diopters + 1e-9]
        sweeps.append(_sweep(base, own, w, predicted[w]))
    curve = lca_curve(eye_model(model), list(wavelengths_nm), pupil_mm=pupil_mm, reference_nm=REFERENCE_NM)
    return ChromaticFocus(model, pupil_mm, tuple(sweeps), {r.wavelength_nm: r.traced_diopters for r in curve.rows},
                          {r.wavelength_nm: r.paraxial_diopters for r in curve.rows}, time.perf_counter() - start)
