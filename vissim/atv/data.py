"""Participant data of the absolute-threshold-for-vision (ATV) experiment (thesis Appendix A).

One JSON file per subject (``subject_<id>.json``, schema ``vissim.atv.subject`` version 1;
``validation/atv/subject_001.json`` is the thesis's subject 001).  `load_subject` checks
the schema (required fields, types, ranges) and stops at the first problem with one line that
names the file, the field (a JSON path such as ``examinations[2].trials[5].minimum_visible_code``),
the bad value and its unit.

It then recomputes what the thesis derived from its own numbers -- the spherical equivalents,
the examination durations (sum of the elapsed times), the summary table of the sessions without
eye drops (mean, max and ``Diff`` = max - min per lens and eye) -- and compares them with what
is printed.  Disagreements are *reported*, never fixed: each becomes a `Discrepancy` in
``SubjectData.discrepancies`` and a logged warning; ``strict=True`` raises
`AtvDataDiscrepancyError` instead.

Tolerances (printed values are rounded): spherical equivalent 0.005 D (two decimals); summary
mean and Diff 1e-4 code values (the mean of 4-decimal inputs, printed to 4 decimals: up to half
a unit from each rounding); max exact (rounding is monotone, so the printed max is one of the
printed values); duration 1 s (elapsed times are whole seconds).
"""
from __future__ import annotations

import json
import logging
from dataclasses import replace
from pathlib import Path

import numpy as np

from vissim.atv.records import (EYES, THESIS_TRIAL_LENSES_DIOPTERS, Autorefraction, AutorefractorEye,
                                Discrepancy, Examination, SubjectData, SummaryRow, Trial)
from vissim.atv.schema import SCHEMA, SCHEMA_VERSION, parse_subject
from vissim.checks import counted, path_arg
from vissim.errors import VissimInputError

__all__ = ["AtvDataDiscrepancyError", "Autorefraction", "AutorefractorEye", "Discrepancy", "Examination",
           "EYES", "SCHEMA", "SCHEMA_VERSION", "SubjectData", "SummaryRow", "THESIS_TRIAL_LENSES_DIOPTERS",
           "Trial", "check_subject", "compute_summary_without_drops", "load_directory", "load_subject",
           "parse_subject"]

log = logging.getLogger(__name__)

SE_TOLERANCE_DIOPTERS = 0.005 + 1e-9
MEAN_TOLERANCE_CODE = 1e-4 + 1e-9
MAX_TOLERANCE_CODE = 1e-9
DURATION_TOLERANCE_S = 1


class AtvDataDiscrepancyError(VissimInputError):
    """Strict loading found the data disagreeing with the thesis's own derived numbers."""


# -- consistency -----------------------------------------------------------------------------


def _lens(lens: float) -> str:
    return f"{lens:+.2f} D" if lens else "0.00 D"


def _at(line: int | None) -> str:
    return f" (line {line})" if line is not None else ""


def compute_summary_without_drops(subject: SubjectData) -> tuple[SummaryRow, ...]:
    """Mean, max and max - min of the sessions without drops, per lens and eye (R before L)."""
    rows = []
    lenses = sorted({t.trial_lens_diopters for e in subject.sessions(False) for t in e.trials}, reverse=True)
    for lens in lenses:
        for eye in EYES:
            values = subject.minimum_visible(eye, False).get(lens)
            if values:
                rows.append(SummaryRow(lens, eye, float(np.mean(values)), max(values), max(values) - min(values)))
    return tuple(rows)


def _check_examination(exam: Examination) -> list[Discrepancy]:
    found: list[Discrepancy] = []
    where = f"examination {exam.number}"
    seen: dict[tuple[float, str], Trial] = {}
    for t in exam.trials:
        key = (t.trial_lens_diopters, t.eye)
        if key in seen:
            found.append(Discrepancy("duplicate_trial", where, f"{where}: two rows for {_lens(key[0])} {key[1]}{_at(t.line)}"))
        seen[key] = t
    sequence = exam.lens_sequence_diopters
    if sequence:
        if len(set(sequence)) != len(sequence):
            found.append(Discrepancy("lens_sequence", where, f"{where}: the lens sequence repeats a lens"))
        if sorted(sequence) != sorted(THESIS_TRIAL_LENSES_DIOPTERS):
            found.append(Discrepancy("lens_sequence", where, f"{where}: the lens sequence is not the thesis's 17-lens set"))
        for lens in sequence:
            for eye in EYES:
                if (lens, eye) not in seen:
                    found.append(Discrepancy(
                        "missing_trial", where, f"{where}: no row for the {_lens(lens)} lens, eye {eye}, "
                        "although the lens is in its sequence", printed=None, computed=f"{_lens(lens)} {eye}",
                    ))
        for lens, eye in seen:
            if lens not in sequence:
                found.append(Discrepancy("lens_sequence", where, f"{where}: a row for {_lens(lens)} {eye} is not in the lens sequence"))
    total = sum(t.elapsed_time_s for t in exam.trials)
    if abs(total - exam.duration_s) > DURATION_TOLERANCE_S:
        found.append(Discrepancy(
            "duration", where,
            f"{where}: printed duration {exam.duration_s:g} s, the printed elapsed times sum to {total:g} s "
            f"({exam.duration_s - total:+g} s unaccounted)",
            printed=exam.duration_s, computed=total,
        ))
    return found


def _check_summary(subject: SubjectData) -> list[Discrepancy]:
    found: list[Discrepancy] = []
    n_sessions = len(subject.sessions(False))
    computed = {(r.trial_lens_diopters, r.eye): r for r in compute_summary_without_drops(subject)}
    printed = {}
    for row in subject.summary_without_drops:
        key = (row.trial_lens_diopters, row.eye)
        where = f"summary {_lens(key[0])} {key[1]}{_at(row.line)}"
        printed[key] = row
        values = subject.minimum_visible(row.eye, False).get(row.trial_lens_diopters, ())
        calc = computed.get(key)
        if calc is None:
            found.append(Discrepancy("summary_row", where, f"{where}: printed, but no session without drops has this lens and eye"))
            continue
        if abs(calc.mean_code - row.mean_code) > MEAN_TOLERANCE_CODE:
            message = (
                f"{where}: printed mean {row.mean_code:.4f} but the {counted(len(values), 'printed session value')} "
                f"(of {n_sessions} without drops) give {calc.mean_code:.4f}"
            )
            missing = n_sessions - len(values)
            if missing > 0:
                implied_sum = n_sessions * row.mean_code - sum(values)
                message += (
                    f"; printed mean x {n_sessions} minus the printed values implies the {counted(missing, 'missing value')} "
                    f"sum to {implied_sum:.4f}, and Max - Diff implies a minimum of {row.max_code - row.diff_code:.4f}"
                )
            found.append(Discrepancy("summary_mean", where, message, printed=row.mean_code, computed=calc.mean_code))
        if abs(calc.max_code - row.max_code) > MAX_TOLERANCE_CODE:
            found.append(Discrepancy(
                "summary_max", where, f"{where}: printed max {row.max_code:.4f}, the sessions give {calc.max_code:.4f}",
                printed=row.max_code, computed=calc.max_code,
            ))
        if abs(calc.diff_code - row.diff_code) > MEAN_TOLERANCE_CODE:
            found.append(Discrepancy(
                "summary_diff", where,
                f"{where}: printed Diff {row.diff_code:.4f}, max - min of the sessions is {calc.diff_code:.4f}",
                printed=row.diff_code, computed=calc.diff_code,
            ))
    if subject.summary_without_drops:
        for key in computed.keys() - printed.keys():
            found.append(Discrepancy("summary_row", f"summary {_lens(key[0])} {key[1]}",
                                     f"summary: no printed row for {_lens(key[0])} {key[1]}, which the sessions measured"))
    return found


def check_subject(subject: SubjectData) -> tuple[Discrepancy, ...]:
    """Everything the thesis derived from its own numbers, recomputed and compared."""
    found: list[Discrepancy] = []
    for i, ar in enumerate(subject.autorefraction):
        for eye in EYES:
            reading = ar.eye(eye)
            se = reading.computed_spherical_equivalent_diopters
            if abs(se - reading.spherical_equivalent_diopters) > SE_TOLERANCE_DIOPTERS:
                where = f"autorefraction[{i}] eye {eye}{_at(reading.line)}"
                found.append(Discrepancy(
                    "spherical_equivalent", where,
                    f"{where}: printed S.E. {reading.spherical_equivalent_diopters:+.2f} D but S + C/2 = {se:+.3f} D",
                    printed=reading.spherical_equivalent_diopters, computed=se,
                ))
    numbers = [e.number for e in subject.examinations]
    if numbers != list(range(1, len(numbers) + 1)):
        found.append(Discrepancy("examination_numbers", "examinations", f"examinations are numbered {numbers}, not 1..{len(numbers)}"))
    for exam in subject.examinations:
        found.extend(_check_examination(exam))
    found.extend(_check_summary(subject))
    # Protocol (thesis §5.1, lines 849-856): the cycloplegic evaluation came first, right after the
    # cycloplegic autorefraction; the others followed at intervals of at least one day.
    with_drops = subject.sessions(True)
    without = subject.sessions(False)
    if with_drops and without:
        first_drops = min(e.date for e in with_drops)
        earlier = [e for e in without if e.date < first_drops]
        if earlier:
            found.append(Discrepancy(
                "protocol_date_order", "examinations",
                f"the session with eye drops is dated {first_drops.isoformat()}, after the "
                f"{'session' if len(earlier) == 1 else 'sessions'} without drops "
                f"dated {', '.join(e.date.isoformat() for e in earlier)}; thesis §5.1 says the cycloplegic session came first",
                printed=first_drops.isoformat(), computed=min(e.date for e in without).isoformat(),
            ))
    return tuple(found)


# -- loading ---------------------------------------------------------------------------------


def _report(subject: SubjectData, strict: bool) -> SubjectData:
    found = check_subject(subject)
    origin = str(subject.path) if subject.path is not None else f"subject {subject.subject_id}"
    if found and strict:
        raise AtvDataDiscrepancyError(
            f"{origin}: {counted(len(found), 'disagreement')} with the thesis's own numbers; first: {found[0].message}"
        )
    for d in found:
        log.warning("%s: %s", origin, d.message)
    return replace(subject, discrepancies=found)


def load_subject(path: str | Path, *, strict: bool = False) -> SubjectData:
    """Read, validate and check one subject file; see the module docstring.

    Parameters
    ----------
    path : str or Path
        A subject file (JSON, schema ``vissim.atv.subject`` version 1).
    strict : bool
        Raise `AtvDataDiscrepancyError` when a printed value disagrees with what the
        thesis's own numbers give; by default each disagreement is logged and kept in
        ``SubjectData.discrepancies``.

    Returns
    -------
    SubjectData
        The subject: autorefractions, examinations (each trial's lens in dioptres and minimum
        visible code value), the printed summary without eye drops, and the discrepancies found.

    Raises
    ------
    VissimInputError
        An unreadable file, invalid JSON, or a field that breaks the schema (the message names
        the file, the field's JSON path, the value and its unit).
    AtvDataDiscrepancyError
        With ``strict=True``, the first discrepancy.

    Examples
    --------
    >>> import vissim
    >>> subject = vissim.load_subject("validation/atv/subject_001.json")  # doctest: +SKIP
    >>> subject.subject_id, len(subject.examinations)  # doctest: +SKIP
    ('001', 4)
    """
    path = path_arg(path, "load_subject's path")
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise VissimInputError(f"cannot read ATV subject file {path}: {exc.strerror or exc}") from None
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as exc:
        raise VissimInputError(f"{path}: not valid JSON: {exc.msg} at line {exc.lineno} column {exc.colno}") from None
    return _report(parse_subject(obj, str(path), path), strict)


def load_directory(directory: str | Path, *, strict: bool = False, pattern: str = "subject_*.json") -> tuple[SubjectData, ...]:
    """All subject files in ``directory`` (not recursive), sorted by subject id.

    Parameters
    ----------
    directory : str or Path
        The folder holding the subject files.
    strict : bool
        As in `load_subject`.
    pattern : str
        Glob of the subject files' names.

    Returns
    -------
    tuple of SubjectData
        One per file, sorted by ``subject_id``.

    Raises
    ------
    VissimInputError
        No such folder, no file matching ``pattern``, a file `load_subject` refuses, or two
        files with one subject id.

    Examples
    --------
    >>> import vissim
    >>> [s.subject_id for s in vissim.load_directory("validation/atv")]  # doctest: +SKIP
    ['001']
    """
    directory = path_arg(directory, "load_directory's directory")
    if not directory.is_dir():
        raise VissimInputError(f"ATV data directory {directory} does not exist or is not a directory")
    files = sorted(directory.glob(pattern))
    if not files:
        raise VissimInputError(f"{directory}: no ATV subject files matching {pattern!r}")
    subjects = [load_subject(p, strict=strict) for p in files]
    ids: dict[str, Path] = {}
    for s in subjects:
        if s.subject_id in ids:
            raise VissimInputError(f"{s.path}: subject_id {s.subject_id!r} is also used by {ids[s.subject_id]}")
        ids[s.subject_id] = s.path
    return tuple(sorted(subjects, key=lambda s: s.subject_id))
