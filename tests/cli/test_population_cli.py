"""``vissim population``: its files, and one error line for each bad input."""

import csv
import json

import pytest

from vissim.cli import build_parser, main
from vissim.optics.eyes.measured.datasets import DATASET_NAMES


def test_the_command_line_names_what_the_library_has():
    parser = next(a for a in build_parser()._actions if a.__class__.__name__ == "_SubParsersAction").choices
    dataset = next(a for a in parser["population"]._actions if a.dest == "dataset")
    assert tuple(dataset.choices) == DATASET_NAMES


def test_a_small_population_writes_its_files(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["population", "jaeken-artal-2012", "--subjects", "1,2", "--pupil-mm", "3",
                 "--field-deg", "0,0;-15,0;10,0", "--mtf-cyc-per-deg", "10,30", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "field 0,0 deg, 555 nm, sphero-cylinder: 4 of 4 eyes" in printed
    rows = list(csv.DictReader((out / "eyes.csv").open()))
    assert {r["eye"] for r in rows} == {f"jaeken-artal-2012:{s}:{e}" for s in (1, 2) for e in ("right", "left")}
    assert all(0.0 < float(r["mtf_30_cyc_per_deg"]) < float(r["mtf_10_cyc_per_deg"]) <= 1.0 for r in rows)
    summary = json.loads((out / "quantiles.json").read_text())
    assert summary["frequencies_cyc_per_deg"] == [10.0, 30.0] and summary["provenance"]["inputs"]["command"] == "population"
    gap = (out / "gap.md").read_text()
    assert "Watson 2013" in gap and "Artal & Navarro 1994" in gap and "navarro-1985 schematic eye" in gap
    for figure in ("figure_mtf.png", "figure_astigmatism.png", "figure_letters.png"):  # three fields on the meridian: the second
        assert (out / figure).stat().st_size > 1000 and (out / f"{figure}.json").is_file()
    assert main(["population", "jaeken-artal-2012", "--subjects", "1", "--pupil-mm", "3", "-o", str(out)]) == 2
    assert "exists" in capsys.readouterr().err


@pytest.mark.parametrize("extra, words", [
    (["--pupil-mm", "5"], "measured over a 4 mm pupil"),
    (["--correction", "contacts"], "--correction: a correction is uncorrected or sphero-cylinder or accommodating or the spectacles worn"),
    (["--correction", ""], "--correction is empty"),
    (["--field-deg", ";"], "--field-deg is empty"),
    (["--workers", "0"], "--workers must be > 0 worker processes, got '0'"),
    (["--subjects", "x"], "--subjects takes whole numbers"),
    (["--subjects", "500"], "has subjects 1-130, got 500"),
    (["--foveal-se-diopters", "1"], "--foveal-se-diopters takes LOW,HIGH"),
    (["--field-deg", "42,0"], "measured at field x -40 to 40 deg, got 42 deg"),
    (["--field-deg", "50,0"], "--field-deg x must be within -45 to 45 deg (an eye's field), got 50 deg"),
])
def test_bad_input_gets_one_error_line(tmp_path, capsys, extra, words):
    argv = ["population", "jaeken-artal-2012", "--subjects", "1", "-o", str(tmp_path / "run"), *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("vissim: error:") and words in err[0], err
    assert not (tmp_path / "run" / "eyes.csv").exists()


def test_accommodating_eyes_need_their_amplitude(tmp_path, capsys):
    assert main(["population", "jaeken-artal-2012", "--subjects", "1", "--pupil-mm", "3", "--correction",
                 "accommodating", "-o", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "needs an accommodation amplitude > 0 D" in err and "got 0 D" in err
    assert not (tmp_path / "run").exists()
