"""Accommodation: how much extra power an eye can add, and how much it adds for a target.

Sign derivation (``docs/conventions.md``: a `Prescription` is the
correcting lens at the eye's principal plane, a myope's sphere is negative).  Write ``M`` for
the prescription's spherical equivalent, ``E = -M`` for the eye's excess power, ``A >= 0``
for the accommodation exerted (extra power, dioptres) and ``L = 1/d`` for the *proximity* of
an object at ``d`` metres (light from it reaches the eye with vergence ``-L``; ``L = 0`` at
infinity).  A relaxed eye with excess power ``E`` focuses light of vergence ``-E``; with
accommodation it focuses ``-(E + A)``.  The dioptric error left for the object is therefore::

    residual excess power   E + A - L
    effective prescription  M + L - A      (the lens that would now correct the eye)

and the accommodation that makes the object sharp is ``A = M + L``:

* an uncorrected -2 D myope has its far point at 0.5 m and needs ``-2 + 2 = 0`` D there,
  ``1/d - 2`` D nearer than 0.5 m; beyond 0.5 m the need is negative and no accommodation
  helps (it relaxes to 0 and sees the object blurred by ``2 - 1/d`` D);
* a +1 D hyperope needs 1 D even for an object at infinity.

The need is clamped to ``[0, amplitude]``.  Astigmatism cannot be accommodated away; the eye
is assumed to focus its circle of least confusion, i.e. the spherical equivalent ``M``.

Amplitude of accommodation from age: Hofstetter's (1950) lines through Duane's (1922)
measurements, in dioptres, ``age`` in years::

    minimum  15.0 - 0.25 age
    mean     18.5 - 0.30 age
    maximum  25.0 - 0.40 age

clamped at 0 (absolute presbyopia).  Duane's own table is not reproduced here.  Cycloplegia
(e.g. cyclopentolate) and absolute presbyopia both mean an amplitude of 0.  The accommodative
pupil constriction of the near triad is *not* modelled: the pupil is a separate input.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

from vissim.checks import finite_number
from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import Prescription, as_prescription

__all__ = ["HOFSTETTER_1950", "Accommodation", "accommodation_for_target", "amplitude_from_age_diopters",
           "clear_vision_range_m", "object_proximity_diopters", "required_accommodation_diopters"]

log = logging.getLogger(__name__)

#: Hofstetter (1950), amplitude = intercept - slope * age (dioptres, age in years).
HOFSTETTER_1950 = {"minimum": (15.0, 0.25), "mean": (18.5, 0.30), "maximum": (25.0, 0.40)}


def _check_amplitude(amplitude_diopters) -> float:
    amplitude = finite_number(amplitude_diopters, "amplitude of accommodation", "dioptres", allow_inf=True)
    if amplitude < 0.0:
        raise VissimInputError(f"amplitude of accommodation must be >= 0 dioptres, got {amplitude_diopters!r} D")
    return amplitude


def object_proximity_diopters(distance_m, name: str = "target distance") -> float:
    """``1/d`` for an object ``d`` metres away (0 at infinity): the minus of its vergence."""
    distance = finite_number(distance_m, name, "metres", allow_inf=True)
    if distance <= 0.0:
        raise VissimInputError(f"{name} must be a positive number of metres (or inf), got {distance_m!r} m")
    return 0.0 if math.isinf(distance) else 1.0 / distance


def amplitude_from_age_diopters(age_years, statistic: str = "mean") -> float:
    """Amplitude of accommodation at ``age_years`` (Hofstetter 1950), clamped at 0 D."""
    age = finite_number(age_years, "age", "years")
    if not 0.0 <= age <= 130.0:
        raise VissimInputError(f"age must be within 0-130 years, got {age_years!r} years")
    if statistic not in HOFSTETTER_1950:
        raise VissimInputError(
            f"Hofstetter statistic must be one of {', '.join(HOFSTETTER_1950)}, got {statistic!r}"
        )
    intercept, slope = HOFSTETTER_1950[statistic]
    return max(0.0, intercept - slope * age)


@dataclass(frozen=True)
class Accommodation:
    """An eye's amplitude of accommodation in dioptres, with where the number came from.

    Build it with `from_age`, `cycloplegic`, `absolute_presbyopia`, or
    directly with a measured amplitude (``Accommodation(3.0)``).
    """

    amplitude_diopters: float
    source: str = "given"

    def __post_init__(self) -> None:
        object.__setattr__(self, "amplitude_diopters", _check_amplitude(self.amplitude_diopters))
        if not isinstance(self.source, str):
            raise VissimInputError(f"accommodation source must be text, got {self.source!r}")

    @classmethod
    def from_age(cls, age_years: float, statistic: str = "mean") -> Accommodation:
        amplitude = amplitude_from_age_diopters(age_years, statistic)
        return cls(amplitude, f"Hofstetter 1950 {statistic} at {float(age_years):g} years")

    @classmethod
    def cycloplegic(cls) -> Accommodation:
        """Accommodation paralysed (e.g. cyclopentolate): amplitude 0."""
        return cls(0.0, "cycloplegia")

    @classmethod
    def absolute_presbyopia(cls) -> Accommodation:
        """No accommodation left with age: amplitude 0."""
        return cls(0.0, "absolute presbyopia")

    def for_target(self, eye_rx: Prescription, target_distance_m: float) -> float:
        """Accommodation this eye exerts to look at a target (see `accommodation_for_target`)."""
        return accommodation_for_target(eye_rx, target_distance_m, self.amplitude_diopters)


def required_accommodation_diopters(eye_rx: Prescription, target_distance_m: float) -> float:
    """Unclamped accommodation ``M + 1/d`` that focuses the target (negative: beyond the far point)."""
    rx = as_prescription(eye_rx)
    return rx.spherical_equivalent_diopters + object_proximity_diopters(target_distance_m)


def accommodation_for_target(eye_rx: Prescription, target_distance_m: float, amplitude_diopters: float) -> float:
    """The accommodation (D) an eye with prescription ``eye_rx`` exerts to look at a target.

    The eye focuses where it can: the need ``M + 1/d`` (``M`` the spherical equivalent of the
    correcting lens) clamped to ``[0, amplitude_diopters]``.  An uncorrected -2 D myope exerts 0 D
    for targets at or beyond 0.5 m and ``1/d - 2`` D nearer; a +1 D hyperope exerts 1 D at
    infinity.
    """
    need = required_accommodation_diopters(eye_rx, target_distance_m)
    amplitude = _check_amplitude(amplitude_diopters)
    exerted = min(max(need, 0.0), amplitude)
    if need > amplitude:
        log.info("target at %s m needs %.3f D of accommodation; only %.3f D available", target_distance_m, need, amplitude)
    return exerted


def clear_vision_range_m(eye_rx: Prescription, amplitude_diopters: float) -> tuple[float, float] | None:
    """``(near_point_m, far_point_m)`` of the eye that ``eye_rx`` corrects (spherical equivalent).

    Objects at proximity ``1/d`` in ``[-M, amplitude - M]`` (and >= 0) can be focused.  The far
    point is ``inf`` for emmetropes and hyperopes; ``None`` means no real object can be
    focused (a hyperope whose amplitude is below its prescription).
    """
    rx = as_prescription(eye_rx)
    amplitude = _check_amplitude(amplitude_diopters)
    m = rx.spherical_equivalent_diopters
    far_proximity = max(0.0, -m)
    near_proximity = amplitude - m
    if near_proximity < far_proximity:
        return None
    far_m = math.inf if far_proximity == 0.0 else 1.0 / far_proximity
    near_m = math.inf if near_proximity == 0.0 else (0.0 if math.isinf(near_proximity) else 1.0 / near_proximity)
    return near_m, far_m
