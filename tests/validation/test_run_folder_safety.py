"""A campaign run hides no result and shares its folder with no one.

* Two configurations with one name would show as one row in tables.md and report.html: refused
  at load, naming both (where they are and what they compare).
* Two runs into one folder at once: the second is refused at once, naming the process that holds it.
* A run folder that holds the campaign's inputs is refused (an output never replaces an input).
"""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from fake_bench import fake_render

import vissim
from vissim.cli import main
from vissim.errors import VissimInputError
from vissim.validation.engine import runner
from vissim.validation.engine.configurations import sweep_combinations
from vissim.validation.engine.loader import load_campaign
from vissim.validation.engine.run_lock import LOCK_FILE_NAME, run_folder_lock

HEAD = "[campaign]\nname = 'tiny'\nspp = 4\ntile_px = [64, 64]\nsimulations = ['geometric']\ninputs = ['render']\n"
SCENE = ("[image]\narcmin_per_px = 1.0\nsize_px = [32, 32]\n[eye]\nprescription = '-1.00 DS'\npupil_diameter_mm = 3.0\n"
         "[[panel]]\nletters = 'N'\ndistance_m = 1.0\nlogmar = 1.0\n")


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("vissim: error: "), err
    return err[0]


def test_two_items_with_one_name_are_refused_naming_both(tmp_path):
    path = tmp_path / "twins.toml"
    path.write_text(HEAD + "[[item]]\nname = 'K'\nletter = 'K'\nlogmar = 0.7\nlenses = [2.0]\n"
                           "[[item]]\nname = 'K'\nletter = 'K'\nlogmar = 0.7\nlenses = [1.0]\n")
    with pytest.raises(VissimInputError, match=r"item\[0\] and item\[1\]: two configurations named 'K'") as err:
        load_campaign(path, check_memory=False)
    assert "+2.00" in str(err.value) and "+1.00" in str(err.value)  # what each compares


def test_a_sweep_whose_labels_round_to_one_name_is_refused(tmp_path):
    """LogMAR 1.0 and 1.04 both print as '+1.0' in the generated name."""
    path = tmp_path / "sweep.toml"
    path.write_text(HEAD + "[[sweep]]\nletter = ['N']\nlogmar = [1.0, 1.04]\n")
    with pytest.raises(VissimInputError, match=r"sweep\[0\] #1 and sweep\[0\] #2") as err:
        load_campaign(path, check_memory=False)
    assert "LogMAR 1," in str(err.value) and "LogMAR 1.04," in str(err.value)


def test_the_same_configuration_twice_still_runs_once(tmp_path):
    path = tmp_path / "again.toml"
    item = "[[item]]\nname = 'K'\nletter = 'K'\nlogmar = 0.7\nlenses = [2.0]\n"
    path.write_text(HEAD + item + item)
    assert len(load_campaign(path, check_memory=False).configurations) == 1


def test_two_depth_configurations_with_one_name_are_refused(tmp_path):
    (tmp_path / "scene.toml").write_text(SCENE)
    path = tmp_path / "depth.toml"
    path.write_text("[campaign]\nkind = 'depth'\n[[config]]\nname = 'eye'\nscene = 'scene.toml'\nprescription = '-1.00 DS'\n"
                    "[[config]]\nname = 'eye'\nscene = 'scene.toml'\nprescription = '-2.00 DS'\n")
    with pytest.raises(VissimInputError, match=r"config\[0\] and config\[1\]: two configurations named 'eye'"):
        load_campaign(path, check_memory=False)


def test_two_eye_items_with_one_name_are_refused_naming_both(tmp_path):
    """The eye kind calls the engine's one check: an item and a sweep's combination that share a name."""
    path = tmp_path / "eye.toml"
    path.write_text("[campaign]\nkind = 'eye'\n[[item]]\nname = 'p, 6 mm pupil'\npupil_diameter_mm = 3.0\n"
                    "[[sweep]]\nname = 'p'\npupil_diameter_mm = [4.0, 6.0]\n")
    with pytest.raises(VissimInputError, match=r"item\[0\] and sweep\[0\] p, 6 mm pupil: two configurations named "
                                               r"'p, 6 mm pupil'") as err:
        load_campaign(path, check_memory=False)
    assert "pupil 3 mm" in str(err.value) and "pupil 6 mm" in str(err.value)  # what each compares
    assert "\n" not in str(err.value)


def test_a_sweep_s_combinations_vary_the_last_axis_fastest():
    combinations = sweep_combinations({"letter": ["K", "N"], "logmar": [1.0], "lenses": [[], [2.0]]})
    assert combinations == [{"letter": "K", "logmar": 1.0, "lenses": []}, {"letter": "K", "logmar": 1.0, "lenses": [2.0]},
                            {"letter": "N", "logmar": 1.0, "lenses": []}, {"letter": "N", "logmar": 1.0, "lenses": [2.0]}]


def test_validate_refuses_duplicate_names_in_one_line(tmp_path, capsys):
    path = tmp_path / "twins.toml"
    path.write_text(HEAD + "[[item]]\nname = 'K'\nletter = 'K'\nlogmar = 0.7\n[[item]]\nname = 'K'\nletter = 'N'\n"
                           "logmar = 0.7\n")
    assert main(["validate", str(path), "-o", str(tmp_path / "run")]) == 2
    assert "two configurations named 'K'" in one_error_line(capsys)
    assert not (tmp_path / "run").exists()


@pytest.fixture
def held(tmp_path):
    """A run folder locked by another process (started here, stopped at the end); yields (folder, its pid)."""
    run = tmp_path / "run"
    package_root = str(Path(vissim.__file__).resolve().parents[1])  # this vissim, however pytest found it
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [package_root, os.environ.get("PYTHONPATH")]))}
    holder = subprocess.Popen([sys.executable, "-c", textwrap.dedent(f"""
        import sys, time
        from vissim.validation.engine.run_lock import run_folder_lock
        with run_folder_lock({str(run)!r}):
            print("held", flush=True)
            sys.stdin.read()  # until the test closes our stdin
    """)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
    try:
        assert holder.stdout.readline().strip() == "held"
        yield run, holder.pid
    finally:
        holder.stdin.close()
        holder.wait(timeout=30)


def test_a_second_run_into_a_held_folder_is_refused_naming_the_holder(tmp_path, capsys, monkeypatch, held):
    run, pid = held
    monkeypatch.setattr(runner, "render_any", fake_render)
    path = tmp_path / "tiny.toml"
    path.write_text(HEAD + "[[item]]\nletter = 'K'\nlogmar = 0.7\nlenses = [2.0]\n")
    assert main(["validate", str(path), "-o", str(run)]) == 2
    line = one_error_line(capsys)
    assert f"run folder {run} is in use by process {pid}" in line, line
    assert sorted(p.name for p in run.iterdir()) == [LOCK_FILE_NAME]  # the refused run wrote nothing
    (run / "campaign.json").write_text("{}")
    assert main(["report", str(run)]) == 2 and f"process {pid}" in one_error_line(capsys)  # nor a rebuild


def test_the_folder_is_free_again_after_the_holder_ends(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(runner, "render_any", fake_render)
    path = tmp_path / "tiny.toml"
    path.write_text(HEAD + "[[item]]\nletter = 'K'\nlogmar = 0.7\nlenses = [2.0]\n")
    run = tmp_path / "run"
    with pytest.raises(KeyboardInterrupt):
        with run_folder_lock(run):
            raise KeyboardInterrupt
    assert not run.exists()  # created by the lock, empty: removed again
    assert main(["validate", str(path), "-o", str(run)]) == 0
    assert (run / "report.html").exists() and not (run / LOCK_FILE_NAME).exists()


def test_a_run_folder_holding_the_manifest_is_refused(tmp_path, capsys):
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "manifest.toml").write_text("")
    path = tmp_path / "captures.toml"
    path.write_text(HEAD + "manifest = 'data/manifest.toml'\n[[item]]\nletter = 'K'\nlogmar = 0.7\ncapture = 'x'\n")
    assert main(["validate", str(path), "-o", str(tmp_path / "data")]) == 2
    line = one_error_line(capsys)
    assert f"output folder {tmp_path / 'data'} holds input {tmp_path / 'data' / 'manifest.toml'}" in line, line


def test_report_refuses_a_run_folder_that_now_holds_its_campaign_file(tmp_path, capsys, monkeypatch):
    # A rebuilt report writes tables.md, metrics.*, figures into the folder: never over the campaign file.
    monkeypatch.setattr(runner, "render_any", fake_render)
    run = tmp_path / "run"
    path = tmp_path / "tiny.toml"
    path.write_text(HEAD + "[[item]]\nletter = 'K'\nlogmar = 0.7\nlenses = [2.0]\n")
    assert main(["validate", str(path), "-o", str(run)]) == 0
    capsys.readouterr()
    moved = run / "tables.md"  # the user keeps the campaign file where the report writes
    os.replace(path, moved)
    record = (run / "campaign.json").read_text().replace(str(path), str(moved))
    (run / "campaign.json").write_text(record)
    before = moved.read_bytes()
    assert main(["report", str(run)]) == 2
    assert f"output folder {run} holds input {moved}" in one_error_line(capsys)
    assert moved.read_bytes() == before
