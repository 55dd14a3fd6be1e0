"""The transcription of thesis Appendix A and the loader's schema and consistency checks.

Expected values are read off /work/shared/reference/krueger2015-thesis.txt at the quoted lines.
"""

import copy
import json
import logging
from pathlib import Path

import pytest

from vissim.atv.data import (
    THESIS_TRIAL_LENSES_DIOPTERS,
    AtvDataDiscrepancyError,
    check_subject,
    compute_summary_without_drops,
    load_directory,
    load_subject,
    parse_subject,
)
from vissim.errors import VissimInputError

SUBJECT_001 = Path(__file__).resolve().parents[2] / "validation" / "atv" / "subject_001.json"


@pytest.fixture(scope="module")
def raw():
    return json.loads(SUBJECT_001.read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def subject():
    return load_subject(SUBJECT_001)


def write(tmp_path, obj, name="subject_001.json"):
    path = tmp_path / name
    path.write_text(json.dumps(obj), encoding="utf-8")
    return path


def test_transcription_has_every_printed_row(subject):
    # Four examinations of 17 lenses x 2 eyes; exams 3 and 4 print no -5.00 D left-eye row.
    assert [len(e.trials) for e in subject.examinations] == [34, 34, 33, 33]
    assert [e.eye_drops for e in subject.examinations] == [True, False, False, False]
    assert len(subject.summary_without_drops) == 34
    for exam in subject.examinations:
        assert sorted(exam.lens_sequence_diopters) == sorted(THESIS_TRIAL_LENSES_DIOPTERS)


def test_transcribed_values_match_the_thesis_lines(subject):
    first = subject.examinations[0].trials[0]  # line 1152: "+ 5,00 | <R> | 0,3522 | 18s | 338 lx"
    assert (first.trial_lens_diopters, first.eye, first.minimum_visible_code, first.elapsed_time_s, first.lux_mean_lx, first.line) == (
        5.0, "R", 0.3522, 18, 338, 1152)
    last = subject.examinations[3].trials[-1]  # line 1350: "- 5,00 | <R> | 0,0560 | 16s | 245 lx"
    assert (last.trial_lens_diopters, last.minimum_visible_code, last.line) == (-5.0, 0.0560, 1350)
    row = subject.summary_without_drops[-1]  # line 1405: "| <L> | 0,0613 | 0,0664 | 0,0092 |"
    assert (row.trial_lens_diopters, row.eye, row.mean_code, row.max_code, row.diff_code) == (-5.0, "L", 0.0613, 0.0664, 0.0092)
    drops = subject.cycloplegic_autorefraction()  # lines 1093/1096
    assert (drops.right.sphere_diopters, drops.right.cylinder_diopters, drops.right.axis_deg) == (1.25, -0.25, 7)
    assert drops.right.spherical_equivalent_diopters == 1.13 and drops.left.spherical_equivalent_diopters == 1.25
    assert drops.vertex_distance_mm == 12.0 and drops.pupil_distance_mm == 61.0
    assert subject.examinations[1].lens_sequence_diopters[:3] == (1.5, 4.0, -0.5)  # line 1115-1117, 2nd column


def test_measured_se_is_s_plus_half_c_of_the_cycloplegic_reading(subject):
    assert subject.measured_se_diopters("R") == pytest.approx(1.125)
    assert subject.measured_se_diopters("L") == pytest.approx(1.25)


def test_subject_001_discrepancies_are_reported_not_hidden(subject, caplog):
    kinds = sorted(d.kind for d in subject.discrepancies)
    assert kinds == sorted([
        "missing_trial", "missing_trial", "duration", "duration", "summary_mean", "summary_diff", "protocol_date_order",
    ])
    mean = next(d for d in subject.discrepancies if d.kind == "summary_mean")
    assert mean.printed == 0.0613 and mean.computed == pytest.approx(0.0664)
    assert "0.1175" in mean.message and "0.0572" in mean.message  # what the printed summary implies
    durations = {d.where: (d.printed, d.computed) for d in subject.discrepancies if d.kind == "duration"}
    assert durations == {"examination 3": (836, 804), "examination 4": (623, 604)}
    with caplog.at_level(logging.WARNING, logger="vissim.atv.data"):
        load_subject(SUBJECT_001)
    assert sum("summary -5.00 D L" in r.getMessage() for r in caplog.records) == 2


def test_every_other_summary_row_follows_from_the_sessions(subject):
    computed = {(r.trial_lens_diopters, r.eye): r for r in compute_summary_without_drops(subject)}
    flagged = {d.where.split(" (")[0] for d in subject.discrepancies if d.kind.startswith("summary")}
    assert flagged == {"summary -5.00 D L"}
    for row in subject.summary_without_drops:
        if (row.trial_lens_diopters, row.eye) != (-5.0, "L"):
            calc = computed[(row.trial_lens_diopters, row.eye)]
            assert abs(calc.mean_code - row.mean_code) <= 1e-4 and calc.max_code == row.max_code


def test_strict_mode_raises_on_the_first_discrepancy():
    with pytest.raises(AtvDataDiscrepancyError, match=r"subject_001.json: 7 disagreement"):
        load_subject(SUBJECT_001, strict=True)


def test_injected_summary_inconsistency_is_found(raw, tmp_path):
    bad = copy.deepcopy(raw)
    row = bad["summary_without_drops"]["rows"][0]  # +5.00 D R: mean 0.3633, max 0.3886 (line 1372)
    row["mean_code"] = 0.3700
    row["max_code"] = 0.3900
    found = load_subject(write(tmp_path, bad)).discrepancies
    assert {d.kind for d in found if d.where.startswith("summary +5.00 D R")} == {"summary_mean", "summary_max"}


def test_injected_se_and_session_changes_are_found(raw, tmp_path):
    bad = copy.deepcopy(raw)
    bad["autorefraction"][0]["right"]["spherical_equivalent_diopters"] = 1.25  # S + C/2 = 1.125
    bad["examinations"][1]["trials"][0]["minimum_visible_code"] = 0.3000  # 2nd exam +5.00 R, changes the mean
    kinds = [d.kind for d in check_subject(parse_subject(bad, "bad.json"))]
    assert "spherical_equivalent" in kinds and kinds.count("summary_mean") == 2


@pytest.mark.parametrize(
    "mutate, message",
    [
        (lambda d: d["examinations"][0]["trials"][3].pop("minimum_visible_code"),
         r"examinations\[0\]\.trials\[3\]\.minimum_visible_code: required field is missing"),
        (lambda d: d["examinations"][2]["trials"][5].__setitem__("minimum_visible_code", "0,0862"),
         r"examinations\[2\]\.trials\[5\]\.minimum_visible_code: must be a number in display code value 0-1, got '0,0862'"),
        (lambda d: d["examinations"][1].__setitem__("eye_drops", "NO"),
         r"examinations\[1\]\.eye_drops: must be true or false, got 'NO'"),
        (lambda d: d["examinations"][1]["trials"][0].__setitem__("eye", "X"),
         r"examinations\[1\]\.trials\[0\]: eye must be 'R' or 'L', got 'X'"),
        (lambda d: d["examinations"][0]["trials"][0].__setitem__("minimum_visible_code", 35.22),
         r"minimum_visible_code must be within 0-1 \(display code value\), got 35.22"),
        (lambda d: d["examinations"][0]["trials"][0].__setitem__("trial_lens_diopters", 0.3),
         r"trial_lens_diopters must be a multiple of 0.25 D"),
        (lambda d: d["autorefraction"][0]["right"].__setitem__("axis_deg", 200),
         r"autorefraction\[0\]\.right: axis_deg must be within 0-180 deg"),
        (lambda d: d["autorefraction"][0].__setitem__("date", "27/11/2014"),
         r"autorefraction\[0\]\.date: must be an ISO date YYYY-MM-DD, got '27/11/2014'"),
        (lambda d: d.__setitem__("examinations", {}), r"examinations: must be a JSON array"),
        (lambda d: d.__setitem__("schema_version", 2), r"schema_version: this vissim reads version 1"),
    ],
)
def test_loader_rejects_a_corrupted_file_naming_file_and_field(raw, tmp_path, mutate, message):
    bad = copy.deepcopy(raw)
    mutate(bad)
    path = write(tmp_path, bad)
    with pytest.raises(VissimInputError, match=message) as info:
        load_subject(path)
    text = str(info.value)
    assert text.startswith(str(path)) and "\n" not in text


def test_loader_rejects_invalid_json(tmp_path):
    path = tmp_path / "subject_x.json"
    path.write_text('{"schema": "vissim.atv.subject",', encoding="utf-8")
    with pytest.raises(VissimInputError, match=r"subject_x.json: not valid JSON"):
        load_subject(path)


def test_directory_loader_reads_one_file_per_subject(raw, tmp_path):
    other = copy.deepcopy(raw)
    other["subject_id"] = "011"
    write(tmp_path, raw, "subject_001.json")
    write(tmp_path, other, "subject_011.json")
    (tmp_path / "report").mkdir()
    (tmp_path / "report" / "analysis.json").write_text("{}")  # not a subject file: ignored
    assert [s.subject_id for s in load_directory(tmp_path)] == ["001", "011"]
    write(tmp_path, raw, "subject_001b.json")
    with pytest.raises(VissimInputError, match="subject_id '001' is also used by"):
        load_directory(tmp_path)


def test_directory_loader_refuses_an_empty_directory(tmp_path):
    with pytest.raises(VissimInputError, match="no ATV subject files"):
        load_directory(tmp_path)
