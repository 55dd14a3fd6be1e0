"""Records of the ATV participant data (thesis Appendix A): frozen dataclasses validated on construction.

Each record checks its own ranges and raises `VissimInputError` naming the
field, the value and its unit; `vissim.atv.schema` adds the file and the JSON path.
Public names are re-exported by `vissim.atv.data`.
"""

from __future__ import annotations

import datetime as _dt
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

from vissim.checks import (AUTOREFRACTOR_CYLINDER_RANGE_DIOPTERS, AUTOREFRACTOR_SPHERE_RANGE_DIOPTERS,
                           AUTOREFRACTOR_VERTEX_RANGE_MM, AXIS_RANGE_DEG, DISPLAY_CODE_RANGE,
                           EXAMINATION_DURATION_RANGE_S, ILLUMINANCE_RANGE_LX, PUPIL_DISTANCE_RANGE_MM,
                           TRIAL_LENS_RANGE_DIOPTERS, TRIAL_TIME_RANGE_S, number_within)
from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import Prescription

__all__ = ["Autorefraction", "AutorefractorEye", "Discrepancy", "EYES", "Examination", "SubjectData",
           "SummaryRow", "THESIS_TRIAL_LENSES_DIOPTERS", "Trial"]

EYES = ("R", "L")
#: Thesis §5.1 (line 860): integer lenses -5 ... +5 D plus ±0.25, ±0.5 and ±1.5 D.
THESIS_TRIAL_LENSES_DIOPTERS = (-5.0, -4.0, -3.0, -2.0, -1.5, -1.0, -0.5, -0.25, 0.0, 0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0)


def _eye(value: str, name: str = "eye") -> str:
    if value not in EYES:
        raise VissimInputError(f"{name} must be 'R' or 'L', got {value!r}")
    return value


def _quarter_diopters(value: float, name: str) -> float:
    number_within(value, name, "D", TRIAL_LENS_RANGE_DIOPTERS)
    if abs(value * 4 - round(value * 4)) > 1e-9:
        raise VissimInputError(f"{name} must be a multiple of 0.25 D (a trial lens), got {value:g} D")
    return value


@dataclass(frozen=True)
class AutorefractorEye:
    """One eye's autorefraction as printed (minus cylinder; SE as printed, rounded)."""

    sphere_diopters: float
    cylinder_diopters: float
    axis_deg: float
    spherical_equivalent_diopters: float
    line: int | None = None

    def __post_init__(self) -> None:
        number_within(self.sphere_diopters, "sphere_diopters", "D", AUTOREFRACTOR_SPHERE_RANGE_DIOPTERS)
        number_within(self.cylinder_diopters, "cylinder_diopters", "D", AUTOREFRACTOR_CYLINDER_RANGE_DIOPTERS)
        number_within(self.axis_deg, "axis_deg", "deg", AXIS_RANGE_DEG)
        number_within(self.spherical_equivalent_diopters, "spherical_equivalent_diopters", "D",
                AUTOREFRACTOR_SPHERE_RANGE_DIOPTERS)

    @property
    def computed_spherical_equivalent_diopters(self) -> float:
        """S + C/2 (thesis Eq. 5.1), unrounded."""
        return self.sphere_diopters + self.cylinder_diopters / 2.0

    def prescription(self) -> Prescription:
        """The correcting lens the autorefractor reports (at its vertex distance)."""
        return Prescription(self.sphere_diopters, self.cylinder_diopters, self.axis_deg)


@dataclass(frozen=True)
class Autorefraction:
    date: _dt.date
    eye_drops: bool
    vertex_distance_mm: float
    cylinder_sign: str
    pupil_distance_mm: float
    right: AutorefractorEye
    left: AutorefractorEye
    lines: tuple[int, int] | None = None

    def __post_init__(self) -> None:
        number_within(self.vertex_distance_mm, "vertex_distance_mm", "mm", AUTOREFRACTOR_VERTEX_RANGE_MM)
        number_within(self.pupil_distance_mm, "pupil_distance_mm", "mm", PUPIL_DISTANCE_RANGE_MM)
        if self.cylinder_sign not in ("-", "+"):
            raise VissimInputError(f"cylinder_sign must be '-' or '+', got {self.cylinder_sign!r}")

    def eye(self, eye: str) -> AutorefractorEye:
        return self.right if _eye(eye) == "R" else self.left


@dataclass(frozen=True)
class Trial:
    """One threshold measurement: a trial lens in front of one eye."""

    trial_lens_diopters: float
    eye: str
    minimum_visible_code: float  # display code value in [0, 1] (ERRATA item 9)
    elapsed_time_s: float
    lux_mean_lx: float
    line: int | None = None

    def __post_init__(self) -> None:
        _quarter_diopters(self.trial_lens_diopters, "trial_lens_diopters")
        _eye(self.eye)
        number_within(self.minimum_visible_code, "minimum_visible_code", "(display code value)", DISPLAY_CODE_RANGE)
        number_within(self.elapsed_time_s, "elapsed_time_s", "s", TRIAL_TIME_RANGE_S)
        number_within(self.lux_mean_lx, "lux_mean_lx", "lx", ILLUMINANCE_RANGE_LX)


@dataclass(frozen=True)
class Examination:
    number: int
    date: _dt.date
    eye_drops: bool
    duration_s: float
    lens_sequence_diopters: tuple[float, ...]
    trials: tuple[Trial, ...]
    lines: tuple[int, int] | None = None

    def __post_init__(self) -> None:
        if self.number < 1:
            raise VissimInputError(f"number must be >= 1, got {self.number}")
        number_within(self.duration_s, "duration_s", "s", EXAMINATION_DURATION_RANGE_S)
        for i, lens in enumerate(self.lens_sequence_diopters):
            _quarter_diopters(lens, f"lens_sequence_diopters[{i}]")
        if not self.trials:
            raise VissimInputError("trials is empty; an examination needs at least one trial")

    def value(self, lens_diopters: float, eye: str) -> float | None:
        for t in self.trials:
            if t.trial_lens_diopters == lens_diopters and t.eye == eye:
                return t.minimum_visible_code
        return None


@dataclass(frozen=True)
class SummaryRow:
    trial_lens_diopters: float
    eye: str
    mean_code: float
    max_code: float
    diff_code: float
    line: int | None = None

    def __post_init__(self) -> None:
        _quarter_diopters(self.trial_lens_diopters, "trial_lens_diopters")
        _eye(self.eye)
        for name in ("mean_code", "max_code", "diff_code"):
            number_within(getattr(self, name), name, "(display code value)", DISPLAY_CODE_RANGE)


@dataclass(frozen=True)
class Discrepancy:
    """Where the data disagree with a number the thesis printed (or with its protocol)."""

    kind: str  # spherical_equivalent | summary_mean | summary_max | summary_diff | summary_row | duration | missing_trial | ...
    where: str
    message: str
    printed: float | str | None = None
    computed: float | str | None = None

    def as_json(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class SubjectData:
    subject_id: str
    path: Path | None
    birthdate: _dt.date | None
    gender: str | None
    source: Mapping[str, Any]
    notes: tuple[str, ...]
    autorefraction: tuple[Autorefraction, ...]
    examinations: tuple[Examination, ...]
    summary_without_drops: tuple[SummaryRow, ...]
    discrepancies: tuple[Discrepancy, ...] = field(default=())

    def __post_init__(self) -> None:
        if not self.subject_id:
            raise VissimInputError("subject_id is empty")
        if not self.examinations:
            raise VissimInputError("examinations is empty; a subject needs at least one examination")
        object.__setattr__(self, "source", MappingProxyType(dict(self.source)))

    def cycloplegic_autorefraction(self) -> Autorefraction | None:
        """The autorefraction with eye drops (the latest, if several)."""
        found = [a for a in self.autorefraction if a.eye_drops]
        return found[-1] if found else None

    def measured_se_diopters(self, eye: str) -> float | None:
        """S + C/2 of the cycloplegic autorefraction (unrounded), or ``None`` without one."""
        ar = self.cycloplegic_autorefraction()
        return None if ar is None else ar.eye(eye).computed_spherical_equivalent_diopters

    def sessions(self, eye_drops: bool) -> tuple[Examination, ...]:
        return tuple(e for e in self.examinations if e.eye_drops == eye_drops)

    def minimum_visible(self, eye: str, eye_drops: bool) -> dict[float, tuple[float, ...]]:
        """Printed minimum-visible values per trial lens (D), one per session that has them."""
        values: dict[float, list[float]] = {}
        for exam in self.sessions(eye_drops):
            for t in exam.trials:
                if t.eye == _eye(eye):
                    values.setdefault(t.trial_lens_diopters, []).append(t.minimum_visible_code)
        return {lens: tuple(v) for lens, v in sorted(values.items())}
