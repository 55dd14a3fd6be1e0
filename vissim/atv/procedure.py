"""The two-phase threshold procedure of thesis Listing 5.1, and a simulated observer.

Phase 1 (as the thesis): start with [0, 1]; repeatedly show an intensity drawn at random among
the multiples of 0.1 strictly inside the current interval; "seen" lowers the maximum to it, "not
seen" raises the minimum; stop when the interval is 0.1 wide.  (Drawing strictly inside makes
every presentation shrink the interval; the endpoints 0 and 1 are never shown.)

Phase 2: the thesis's participant moved a slider; vissim replaces it by a **bisection** (the
binary search the thesis names as the alternative, §5.3): show the midpoint of the interval,
"seen" moves the maximum down to it, "not seen" the minimum up, until the interval is at most
``resolution_code`` wide (default 0.001: 7 steps from 0.1).  The estimate is the midpoint of the
final interval; the *minimum visible* is its upper end (the least intensity reported seen, or
the phase-1 maximum).  For an observer who sees exactly the intensities >= T, T lies in the
final interval, so the estimate is within ``resolution_code / 2`` of T.

Everything is deterministic given the seed (NumPy PCG64).  Intensities are display code values
in [0, 1] (ERRATA item 9).
"""

from __future__ import annotations

import logging
import math
from dataclasses import asdict, dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from vissim.checks import GUESS_LAPSE_RANGE, finite_number
from vissim.errors import VissimInputError

__all__ = ["Observer", "Presentation", "ProcedureConfig", "PsychometricFunction", "SimulatedObserver",
           "ThresholdResult", "run_procedure"]

log = logging.getLogger(__name__)


@runtime_checkable
class Observer(Protocol):
    """Anything that answers whether a stimulus of ``intensity`` (code value 0-1) was seen."""

    def seen(self, intensity: float) -> bool: ...


@dataclass(frozen=True)
class PsychometricFunction:
    """Probability of "seen": ``guess + (1 - guess - lapse) * F(x)``, Weibull ``F = 1 - 2^-(x/T)^slope``.

    Parameterised so that ``F(threshold) = 1/2`` exactly; with ``guess == lapse`` the threshold is
    also where the observer says "seen" half the time, the point a bisection converges to.
    ``guess_rate`` is the false-alarm rate of a yes/no task (seen with nothing visible),
    ``lapse_rate`` the rate of missing a clearly visible stimulus (Wichmann & Hill 2001).
    """

    threshold: float
    slope: float = 20.0
    guess_rate: float = 0.0
    lapse_rate: float = 0.0

    def __post_init__(self) -> None:
        t = finite_number(self.threshold, "threshold", "display code value")
        if t <= 0:
            raise VissimInputError(f"threshold must be a positive display code value, got {self.threshold!r}")
        s = finite_number(self.slope, "psychometric slope", "(Weibull exponent)", allow_inf=True)
        if s <= 0:
            raise VissimInputError(f"psychometric slope must be > 0 (Weibull exponent), got {self.slope!r}")
        for name in ("guess_rate", "lapse_rate"):
            v = finite_number(getattr(self, name), name, "probability")
            low, high = GUESS_LAPSE_RANGE
            if not low <= v < high:
                raise VissimInputError(f"{name} must be at least {low:g} and less than {high:g}, got {v!r}")
        object.__setattr__(self, "threshold", t)
        object.__setattr__(self, "slope", s)

    def probability_seen(self, intensity) -> np.ndarray | float:
        x = np.maximum(np.asarray(intensity, dtype=float), 0.0)
        with np.errstate(over="ignore"):  # (x/t)^s -> inf is the right limit: seen for sure
            f = 1.0 - np.exp2(-np.power(x / self.threshold, self.slope))
        p = self.guess_rate + (1.0 - self.guess_rate - self.lapse_rate) * f
        return float(p) if np.ndim(p) == 0 else p


@dataclass(frozen=True)
class SimulatedObserver:
    """A seeded observer answering by a `PsychometricFunction`.

    ``slope=math.inf`` is the ideal observer: "seen" iff intensity >= threshold (no guesses,
    no lapses).  Each call draws one uniform number, so a run is reproducible from the seed.
    """

    psychometric: PsychometricFunction
    seed: int | None = 0
    _rng: np.random.Generator = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_rng", np.random.default_rng(self.seed))

    @classmethod
    def ideal(cls, threshold: float) -> SimulatedObserver:
        return cls(PsychometricFunction(threshold, slope=math.inf))

    def seen(self, intensity: float) -> bool:
        u = self._rng.random()
        if math.isinf(self.psychometric.slope):
            return bool(intensity >= self.psychometric.threshold)
        return bool(u < self.psychometric.probability_seen(intensity))


@dataclass(frozen=True)
class ProcedureConfig:
    """Phase-1 grid step and interval, phase-2 resolution (all display code values)."""

    minimum_code: float = 0.0
    maximum_code: float = 1.0
    phase1_step_code: float = 0.1
    resolution_code: float = 0.001
    method: str = "bisection"

    def __post_init__(self) -> None:
        lo = finite_number(self.minimum_code, "minimum intensity", "display code value")
        hi = finite_number(self.maximum_code, "maximum intensity", "display code value")
        step = finite_number(self.phase1_step_code, "phase-1 step", "display code value")
        res = finite_number(self.resolution_code, "phase-2 resolution", "display code value")
        if not 0.0 <= lo < hi <= 1.0:
            raise VissimInputError(f"intensity range must satisfy 0 <= min < max <= 1 (code values), got [{lo:g}, {hi:g}]")
        n = (hi - lo) / step if step > 0 else -1
        if step <= 0 or abs(n - round(n)) > 1e-9 or round(n) < 1:
            raise VissimInputError(f"phase-1 step must divide the range {hi - lo:g} (code value) evenly, got {step:g}")
        if not 0.0 < res <= step:
            raise VissimInputError(f"phase-2 resolution must be within (0, {step:g}] (code value), got {res:g}")
        if self.method != "bisection":
            raise VissimInputError(f"phase-2 method must be 'bisection', got {self.method!r}")

    @property
    def phase2_steps(self) -> int:
        return max(0, math.ceil(math.log2(self.phase1_step_code / self.resolution_code) - 1e-12))


@dataclass(frozen=True)
class Presentation:
    phase: int
    intensity_code: float
    seen: bool


@dataclass(frozen=True)
class ThresholdResult:
    """The outcome of one run: the final interval, the estimate and every presentation."""

    threshold_code: float  # midpoint of the final interval
    lower_code: float
    upper_code: float  # the minimum visible: least intensity reported seen (or the phase-1 maximum)
    phase1_interval_code: tuple[float, float]
    presentations: tuple[Presentation, ...]
    config: ProcedureConfig
    seed: int | None

    @property
    def minimum_visible_code(self) -> float:
        return self.upper_code

    @property
    def never_seen(self) -> bool:
        """No presentation was seen: the threshold may lie above the maximum intensity."""
        return not any(p.seen for p in self.presentations)

    def as_json(self) -> dict:
        return {
            "threshold_code": self.threshold_code,
            "minimum_visible_code": self.minimum_visible_code,
            "interval_code": [self.lower_code, self.upper_code],
            "phase1_interval_code": list(self.phase1_interval_code),
            "never_seen": self.never_seen,
            "presentations": [asdict(p) for p in self.presentations],
            "config": {"phase2_method" if k == "method" else k: v for k, v in asdict(self.config).items()},
            "seed": self.seed,
        }


def run_procedure(observer: Observer, config: ProcedureConfig | None = None, *, seed: int | None = 0) -> ThresholdResult:
    """Run Listing 5.1 (phase 1 quasi-random, phase 2 bisection) against ``observer``."""
    config = config or ProcedureConfig()
    rng = np.random.default_rng(seed)
    step = config.phase1_step_code
    # Phase 1 on integer grid indices, so that 0.1-multiples stay exact.
    lo_i, hi_i = 0, round((config.maximum_code - config.minimum_code) / step)
    presentations: list[Presentation] = []

    def seen(phase: int, intensity: float) -> bool:
        presentations.append(Presentation(phase, intensity, bool(observer.seen(intensity))))
        return presentations[-1].seen

    while hi_i - lo_i > 1:
        k = int(rng.integers(lo_i + 1, hi_i))  # strictly inside
        lo_i, hi_i = (lo_i, k) if seen(1, config.minimum_code + k * step) else (k, hi_i)
    lo = config.minimum_code + lo_i * step
    hi = config.minimum_code + hi_i * step
    phase1 = (lo, hi)
    for _ in range(config.phase2_steps):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if seen(2, mid) else (mid, hi)
    result = ThresholdResult(0.5 * (lo + hi), lo, hi, phase1, tuple(presentations), config, seed)
    log.debug("threshold %.4f in [%.4f, %.4f] after %d presentations", result.threshold_code, lo, hi, len(presentations))
    return result
