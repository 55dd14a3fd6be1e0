"""Parsing of ATV subject files (schema ``vissim.atv.subject`` version 1) into records.

Errors stop at the first problem with one line naming the file, the JSON path of the field
(e.g. ``examinations[2].trials[5].minimum_visible_code``), the bad value and its unit.
"""

from __future__ import annotations

import datetime as _dt
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from vissim.atv.records import Autorefraction, AutorefractorEye, Examination, SubjectData, SummaryRow, Trial
from vissim.errors import VissimInputError

__all__ = ["SCHEMA", "SCHEMA_VERSION", "parse_subject"]

SCHEMA = "vissim.atv.subject"
SCHEMA_VERSION = 1


class _Reader:
    """Typed access to a JSON object with errors naming the file and the JSON path."""

    def __init__(self, origin: str):
        self.origin = origin

    def fail(self, where: str, message: str) -> VissimInputError:
        return VissimInputError(f"{self.origin}: {where}: {message}")

    def fail_at(self, where: str, key: str, message: str) -> VissimInputError:
        """`fail` at field ``key`` of the object at ``where``."""
        return self.fail(f"{where}.{key}" if where else key, message)

    def get(self, obj: Any, key: str, where: str, *, optional: bool = False) -> Any:
        if not isinstance(obj, Mapping):
            raise self.fail(where, f"must be a JSON object, got {type(obj).__name__}")
        if key not in obj:
            if optional:
                return None
            raise self.fail_at(where, key, "required field is missing")
        return obj[key]

    def number(self, obj: Any, key: str, where: str, unit: str, *, optional: bool = False) -> float | None:
        value = self.get(obj, key, where, optional=optional)
        if value is None and optional:
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail_at(where, key, f"must be a number in {unit}, got {value!r}")
        if not math.isfinite(value):
            raise self.fail_at(where, key, f"must be a finite number in {unit}, got {value!r}")
        return float(value)

    def integer(self, obj: Any, key: str, where: str, unit: str, *, optional: bool = False) -> int | None:
        value = self.number(obj, key, where, unit, optional=optional)
        if value is None:
            return None
        if value != int(value):
            raise self.fail_at(where, key, f"must be a whole number of {unit}, got {value!r}")
        return int(value)

    def boolean(self, obj: Any, key: str, where: str) -> bool:
        value = self.get(obj, key, where)
        if not isinstance(value, bool):
            raise self.fail_at(where, key, f"must be true or false, got {value!r}")
        return value

    def text(self, obj: Any, key: str, where: str, *, optional: bool = False) -> str | None:
        value = self.get(obj, key, where, optional=optional)
        if value is None and optional:
            return None
        if not isinstance(value, str):
            raise self.fail_at(where, key, f"must be text, got {value!r}")
        return value

    def date(self, obj: Any, key: str, where: str, *, optional: bool = False) -> _dt.date | None:
        value = self.text(obj, key, where, optional=optional)
        if value is None:
            return None
        try:
            return _dt.date.fromisoformat(value)
        except ValueError:
            raise self.fail_at(where, key, f"must be an ISO date YYYY-MM-DD, got {value!r}") from None

    def array(self, obj: Any, key: str, where: str, *, optional: bool = False) -> list:
        value = self.get(obj, key, where, optional=optional)
        if value is None and optional:
            return []
        if not isinstance(value, list):
            raise self.fail_at(where, key, f"must be a JSON array, got {type(value).__name__}")
        return value

    def lines(self, obj: Any, key: str, where: str) -> tuple[int, int] | None:
        value = self.get(obj, key, where, optional=True)
        if value is None:
            return None
        if not (isinstance(value, list) and len(value) == 2 and all(isinstance(v, int) and not isinstance(v, bool) for v in value)):
            raise self.fail(f"{where}.{key}", f"must be [first, last] source line numbers, got {value!r}")
        return (value[0], value[1])

    def build(self, cls, where: str, **kwargs):
        try:
            return cls(**kwargs)
        except VissimInputError as exc:
            raise self.fail(where, str(exc)) from None


_CODE = "display code value 0-1"
#: The fields of the flat records, in the order they are read: name and unit (None: text).  Each may
#: also give its source ``line``.
_RECORD_FIELDS = {
    AutorefractorEye: (("sphere_diopters", "D"), ("cylinder_diopters", "D"), ("axis_deg", "deg"),
                       ("spherical_equivalent_diopters", "D")),
    Trial: (("trial_lens_diopters", "D"), ("eye", None), ("minimum_visible_code", _CODE), ("elapsed_time_s", "s"),
            ("lux_mean_lx", "lx")),
    SummaryRow: (("trial_lens_diopters", "D"), ("eye", None), ("mean_code", _CODE), ("max_code", _CODE),
                 ("diff_code", _CODE)),
}


def _parse_record(r: _Reader, cls, obj: Any, where: str):
    """One of the flat records of `_RECORD_FIELDS`."""
    values = {name: r.text(obj, name, where) if unit is None else r.number(obj, name, where, unit)
              for name, unit in _RECORD_FIELDS[cls]}
    return r.build(cls, where, **values, line=r.integer(obj, "line", where, "(line number)", optional=True))


def _parse_autorefraction(r: _Reader, obj: Any, where: str) -> Autorefraction:
    return r.build(
        Autorefraction,
        where,
        date=r.date(obj, "date", where),
        eye_drops=r.boolean(obj, "eye_drops", where),
        vertex_distance_mm=r.number(obj, "vertex_distance_mm", where, "mm"),
        cylinder_sign=r.text(obj, "cylinder_sign", where),
        pupil_distance_mm=r.number(obj, "pupil_distance_mm", where, "mm"),
        right=_parse_record(r, AutorefractorEye, r.get(obj, "right", where), f"{where}.right"),
        left=_parse_record(r, AutorefractorEye, r.get(obj, "left", where), f"{where}.left"),
        lines=r.lines(obj, "lines", where),
    )


def _parse_examination(r: _Reader, obj: Any, where: str) -> Examination:
    sequence = r.array(obj, "lens_sequence_diopters", where, optional=True)
    lenses = []
    for i, value in enumerate(sequence):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise r.fail(f"{where}.lens_sequence_diopters[{i}]", f"must be a number in D, got {value!r}")
        lenses.append(float(value))
    trials = tuple(_parse_record(r, Trial, t, f"{where}.trials[{i}]")
                   for i, t in enumerate(r.array(obj, "trials", where)))
    return r.build(
        Examination,
        where,
        number=r.integer(obj, "number", where, "(examination number)"),
        date=r.date(obj, "date", where),
        eye_drops=r.boolean(obj, "eye_drops", where),
        duration_s=r.number(obj, "duration_s", where, "s"),
        lens_sequence_diopters=tuple(lenses),
        trials=trials,
        lines=r.lines(obj, "lines", where),
    )


def parse_subject(obj: Any, origin: str = "<subject>", path: Path | None = None) -> SubjectData:
    """Validate a decoded subject JSON object and build `SubjectData` (no consistency checks)."""
    r = _Reader(origin)
    if not isinstance(obj, Mapping):
        raise VissimInputError(f"{origin}: the file must hold a JSON object, got {type(obj).__name__}")
    schema = r.text(obj, "schema", "")
    if schema != SCHEMA:
        raise r.fail("schema", f"must be {SCHEMA!r}, got {schema!r}")
    version = r.integer(obj, "schema_version", "", "(version)")
    if version != SCHEMA_VERSION:
        raise r.fail("schema_version", f"this vissim reads version {SCHEMA_VERSION}, got {version}")
    subject_id = r.text(obj, "subject_id", "")
    source = r.get(obj, "source", "", optional=True) or {}
    if not isinstance(source, Mapping):
        raise r.fail("source", f"must be a JSON object, got {type(source).__name__}")
    notes = r.array(obj, "notes", "", optional=True)
    if not all(isinstance(n, str) for n in notes):
        raise r.fail("notes", "must be an array of text")
    summary = r.get(obj, "summary_without_drops", "", optional=True) or {"rows": []}
    rows = tuple(
        _parse_record(r, SummaryRow, row, f"summary_without_drops.rows[{i}]")
        for i, row in enumerate(r.array(summary, "rows", "summary_without_drops"))
    )
    return r.build(
        SubjectData,
        "subject",
        subject_id=subject_id,
        path=path,
        birthdate=r.date(obj, "birthdate", "", optional=True),
        gender=r.text(obj, "gender", "", optional=True),
        source=source,
        notes=tuple(notes),
        autorefraction=tuple(
            _parse_autorefraction(r, a, f"autorefraction[{i}]") for i, a in enumerate(r.array(obj, "autorefraction", ""))
        ),
        examinations=tuple(
            _parse_examination(r, e, f"examinations[{i}]") for i, e in enumerate(r.array(obj, "examinations", ""))
        ),
        summary_without_drops=rows,
    )
