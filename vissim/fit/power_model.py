"""How the fitted power vector sets the camera's defocus and magnification.

Blur alone cannot give the sign of the power: for a centred circular pupil and a second-order
wavefront, +D and -D give the same intensity PSF (geometric optics: the same ellipse; wave
optics: the PSF of -W is that of W rotated by 180 degrees, and a quadratic W's PSF is
centrosymmetric).  On the bench the sign is carried by the trial lens's spectacle
magnification: a plus lens magnifies, a minus lens minifies.  A model says how magnification
follows power:

``bench`` (`BenchLensModel`)
    The fitted vector q is the marked power (M, J0, J45) of one trial lens in the bench's holder,
    made physical exactly as the bench makes it (crown glass, realistic thickness:
    `vissim.bench.dslr.bench.DslrBench.physical_lenses`).  Vergence theory
    (`viewing_setup`) gives the power it adds at the camera,
    the *effective* power reported (what ``vissim trial-lens`` prints as ``effective_*``), and
    its magnification matrix.  The sign is then in the data.
``free`` (`FreeMagnificationModel`)
    q is the effective power; an isotropic magnification is a separate nuisance.  Blur carries
    no sign, so the sign is reported undetermined.
``none`` (`NoMagnificationModel`)
    q is the effective power, no magnification (a capture whose sharp reference was taken
    through the same optics but for the refraction).  The sign is undetermined.

Each model maps q (and its own nuisances) to `ModelOptics`.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np

from vissim.bench.dslr.bench import DslrBench
from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import LensPower
from vissim.optics.rx.trial_lens import TrialLens

__all__ = ["ModelOptics", "BenchLensModel", "FreeMagnificationModel", "NoMagnificationModel", "MAGNIFICATION_MODELS",
           "power_model"]

MAGNIFICATION_MODELS = ("bench", "free", "none")
_IDENTITY = np.eye(2)


@dataclass(frozen=True)
class ModelOptics:
    """What one parameter vector means optically (2 x 2 matrices, TABO x/y frame)."""

    effective_power: np.ndarray  # power added at the camera, dioptres (plus lens > 0)
    defocus: np.ndarray  # the camera's defocus: effective power + focus error (+ fitted offset)
    magnification: np.ndarray


def _matrix(vector) -> np.ndarray:
    m, j0, j45 = (float(v) for v in vector)
    return np.array([[m + j0, j45], [j45, m - j0]])


class NoMagnificationModel:
    """q is the effective power; no magnification; the sign is not in the data."""

    name = "none"
    nuisance_names: tuple[str, ...] = ()
    determines_sign = False

    def __init__(self, focus_error_diopters: float = 0.0) -> None:
        self.focus_error_diopters = float(focus_error_diopters)

    def optics(self, q, nuisances=()) -> ModelOptics:
        power = _matrix(q)
        return ModelOptics(power, power + self.focus_error_diopters * _IDENTITY, _IDENTITY)

    def as_json(self) -> dict:
        return {"name": self.name, "parameters": "effective power vector", "determines_sign": False}


class FreeMagnificationModel(NoMagnificationModel):
    """q is the effective power; an isotropic magnification ``exp(log_magnification)`` is fitted apart."""

    name = "free"
    nuisance_names = ("log_magnification",)

    def optics(self, q, nuisances=(0.0,)) -> ModelOptics:
        power = _matrix(q)
        return ModelOptics(power, power + self.focus_error_diopters * _IDENTITY,
                           math.exp(float(nuisances[0])) * _IDENTITY)

    def as_json(self) -> dict:
        return {"name": self.name, "parameters": "effective power vector, isotropic magnification",
                "determines_sign": False}


class BenchLensModel:
    """q is the marked power vector of one trial lens on ``bench`` (module doc); vergence theory does the rest."""

    name = "bench"
    nuisance_names: tuple[str, ...] = ()
    determines_sign = True

    def __init__(self, bench: DslrBench) -> None:
        if not isinstance(bench, DslrBench):
            raise VissimInputError(f"the bench magnification model needs a DslrBench, got {bench!r}")
        self.bench = dataclasses.replace(bench, lenses=())
        self._no_lens = self.bench.viewing_setup()
        self.focus_error_diopters = float(np.asarray(self._no_lens.defocus_matrix_diopters)[0, 0])

    @functools.lru_cache(maxsize=4096)  # noqa: B019 (one model per fit; the cache dies with it)
    def _setup(self, q: tuple[float, float, float]):
        marked = LensPower.from_power_vector(*q)
        lens = TrialLens(marked.sphere_diopters, marked.cylinder_diopters, marked.axis_deg)
        return dataclasses.replace(self.bench, lenses=(lens,)).viewing_setup()

    def optics(self, q, nuisances=()) -> ModelOptics:
        setup = self._setup(tuple(float(v) for v in q))
        defocus = np.asarray(setup.defocus_matrix_diopters, dtype=float)
        return ModelOptics(defocus - self.focus_error_diopters * _IDENTITY, defocus,
                           np.asarray(setup.magnification_matrix, dtype=float))

    def as_json(self) -> dict:
        b = self.bench
        return {"name": self.name, "parameters": "marked power vector of one trial lens (thin, made physical "
                "as the bench makes it); effective power and magnification by vergence theory",
                "determines_sign": True, "vertex_distance_mm": b.vertex_distance_mm,
                "chart_distance_mm": b.chart_distance_mm, "focus_distance_mm": b.focus_distance_mm,
                "refractive_index": b.refractive_index, "focal_length_mm": b.focal_length_mm,
                "f_number": b.f_number}


def power_model(name: str, bench: DslrBench | None = None):
    """The model called ``name`` (`MAGNIFICATION_MODELS`); ``bench`` is needed for ``"bench"``."""
    if bench is not None:
        bench = dataclasses.replace(bench, lenses=())  # the fit must not see the lenses, only the holder
    if name == "bench":
        if bench is None:
            raise VissimInputError("magnification model 'bench' needs the bench setup (vertex and chart distances)")
        return BenchLensModel(bench)
    focus_error = 0.0 if bench is None else float(np.asarray(bench.viewing_setup().defocus_matrix_diopters)[0, 0])
    if name == "free":
        return FreeMagnificationModel(focus_error)
    if name == "none":
        return NoMagnificationModel(focus_error)
    raise VissimInputError(f"magnification model must be one of {', '.join(MAGNIFICATION_MODELS)}, got {name!r}")
