"""``vissim atv analyze | simulate | run`` as a user runs them."""

import json
import sys
from pathlib import Path

import pytest

from vissim.cli import main

DATA_DIR = Path(__file__).resolve().parents[2] / "validation" / "atv"


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_analyze_writes_fits_figures_and_reports(capsys, tmp_path):
    out_dir = tmp_path / "atv"
    code, out, _ = run(capsys, "atv", "analyze", str(DATA_DIR), "-o", str(out_dir))
    assert code == 0
    names = {p.name for p in out_dir.iterdir()}
    assert {"report.md", "report.html", "analysis.json", "subject_001_fits.png", "subject_001_overview.png"} <= names
    assert "subject 001 R with drops (all lenses): vertex +0.11 D" in out
    report = (out_dir / "report.md").read_text(encoding="utf-8")
    assert "| 001 | right eye | with drops | all lenses |" in report and "summary -5.00 D L" in report
    record = json.loads((out_dir / "analysis.json").read_text())
    assert len(record["curves"]) == 8 and len(record["subjects"][0]["discrepancies"]) == 7
    code, _, err = run(capsys, "atv", "analyze", str(DATA_DIR), "-o", str(out_dir))
    assert code == 2 and "already exists" in err


def test_analyze_strict_fails_with_one_line(capsys, tmp_path):
    code, out, err = run(capsys, "atv", "analyze", str(DATA_DIR), "-o", str(tmp_path / "x"), "--strict")
    assert code == 2 and err.startswith("vissim: error:") and err.count("\n") == 1
    assert "disagreements with the thesis's own numbers" in err and "(s)" not in err


def test_simulate_a_cyclopleged_hyperope(capsys, tmp_path):
    code, out, _ = run(
        capsys, "atv", "simulate", "--rx", "+1.25 DS", "--pupil-mm", "4", "--cycloplegia", "--seed", "3",
        "--lenses", "-2,-1,0,0.5,1,1.5,2,3,4", "-o", str(tmp_path / "sim"),
    )
    assert code == 0 and "fit over ±2.5 D window: vertex" in out
    record = json.loads((tmp_path / "sim" / "analysis.json").read_text())
    assert record["inputs"]["experiment"]["subject"]["cycloplegia"] is True
    assert len(record["inputs"]["experiment"]["trials"]) == 9
    assert (tmp_path / "sim" / "curve.png").stat().st_size > 1000


def test_simulate_rejects_a_bad_pupil(capsys, tmp_path):
    code, _, err = run(capsys, "atv", "simulate", "--rx", "-2.00 DS", "--pupil-mm", "-3", "-o", str(tmp_path / "s"))
    assert code == 2 and "--pupil-mm must be > 0 mm, got '-3'" in err


def test_run_with_a_simulated_observer_writes_the_result(capsys, tmp_path):
    target = tmp_path / "result.json"
    code, out, _ = run(capsys, "atv", "run", "--threshold", "0.0669", "--code-value-slope", "inf", "--seed", "2", "-o", str(target))
    assert code == 0 and "threshold 0.06" in out
    result = json.loads(target.read_text())["result"]
    assert result["interval_code"][0] < 0.0669 <= result["interval_code"][1]
    assert result["config"]["phase2_method"] == "bisection"


def test_run_with_a_person_at_the_terminal(capsys, tmp_path, monkeypatch):
    answers = []

    def fake_input(prompt):
        intensity = float(prompt.split("code value ")[1].split(";")[0])
        answers.append(intensity)
        return "y" if intensity >= 0.42 else "n"

    monkeypatch.setattr("builtins.input", fake_input)
    target = tmp_path / "person.json"
    code, out, _ = run(capsys, "atv", "run", "--observer", "person", "--display", "terminal", "--eye-side", "R",
                       "--sphere", "-1.5", "-o", str(target))
    assert code == 0
    record = json.loads(target.read_text())
    assert abs(record["result"]["threshold_code"] - 0.42) <= 0.0005
    assert record["inputs"]["trial_lens_diopters"] == -1.5 and len(answers) == len(record["result"]["presentations"])


def test_a_person_sees_each_prompt_before_answering_it(capsys, tmp_path, monkeypatch):
    # The command prints live for a person (prints_live): its other output waits for its files, its prompts do not.
    shown = []

    def person(prompt):
        sys.stdout.write(prompt)  # where builtins.input writes its prompt
        shown.append(prompt in capsys.readouterr().out)
        return "y" if float(prompt.split("code value ")[1].split(";")[0]) >= 0.42 else "n"

    monkeypatch.setattr("builtins.input", person)
    code, _, _ = run(capsys, "atv", "run", "--observer", "person", "--display", "terminal", "-o", str(tmp_path / "p.json"))
    assert code == 0 and shown and all(shown)


def test_run_person_quitting_leaves_no_file(capsys, tmp_path, monkeypatch):
    monkeypatch.setattr("builtins.input", lambda prompt: "q")
    target = tmp_path / "person.json"
    code, _, err = run(capsys, "atv", "run", "--observer", "person", "--display", "terminal", "-o", str(target))
    assert code == 2 and "quit" in err and not target.exists()


@pytest.mark.parametrize("argv, message", [
    (["atv", "run", "--threshold", "-1", "-o", "x.json"], "threshold must be a positive display code value"),
    (["atv", "run", "--resolution", "0.5", "-o", "x.json"], "phase-2 resolution must be within"),
])
def test_run_bad_input_is_one_line(capsys, tmp_path, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    code, _, err = run(capsys, *argv)
    assert code == 2 and message in err and err.count("\n") == 1


def test_a_window_of_zero_skips_the_local_parabola_as_its_help_says():
    from vissim.cli import build_parser
    from vissim.cli.atv import _window

    args = build_parser().parse_args(["atv", "analyze", "x", "-o", "y", "--window-diopters", "0"])
    assert args.window_diopters == 0.0 and _window(args.window_diopters) is None
    assert "0 to skip" in " ".join(build_parser()._subparsers._group_actions[0].choices["atv"]
                                   ._subparsers._group_actions[0].choices["analyze"].format_help().split())
