"""The campaign harness on tiny campaigns, with a stand-in bench (no Mitsuba)."""

import json
import shutil

import pytest
from fake_bench import fake_render, refuse

from vissim.cli import main
from vissim.errors import VissimInputError
from vissim.validation.engine import runner
from vissim.validation.engine.loader import load_campaign
from vissim.validation.dslr.report import metrics_rows
from vissim.validation.engine.report import load_results, write_report
from vissim.validation.engine.runner import run_campaign

TINY = """
[campaign]
name = "tiny"
spp = 4
seeds = [1, 2]
tile_px = [64, 64]
simulations = ["wave", "geometric", "thesis"]
inputs = ["render", "synthetic"]

[[item]]
name = "plus two"
letter = "K"
logmar = 0.7
lenses = [2.0]

[[item]]
name = "cylinder"
letter = "N"
logmar = 0.7
lenses = [{ cylinder_diopters = 2.0, axis_deg = 90 }]
"""


@pytest.fixture
def tiny(campaign_file):
    return campaign_file(TINY)


def numbers(run_dir):
    return [(r["configuration"], r["simulation"], r["input"], r["ssim"], r["psnr_db"]) for r in metrics_rows(load_results(run_dir))]


def test_a_tiny_campaign_runs_and_reports(tiny, tmp_path):
    run_dir = tmp_path / "run"
    summary = run_campaign(tiny, run_dir, render=fake_render, show_progress=False)
    assert summary.items_total == 2 and summary.renders_made == 6
    written, _ = write_report(run_dir)
    names = {p.name for p in written}
    assert {"metrics.json", "metrics.csv", "tables.md", "report.html", "figure_wave.png"} <= names
    rows = metrics_rows(load_results(run_dir))
    # 3 simulations x 2 inputs against the render, wave and thesis against the wave bench, and
    # the geometric self-check (traced rays on the synthetic chart against the render)
    assert len(rows) == 2 * (3 * 2 + 2 + 1)
    # The stand-in bench *is* geometric optics on the synthetic chart plus noise of sigma 0.005:
    # the geometric simulation of the synthetic input, and the trace's ray optics, must reach the
    # noise limit (floor + ~3 dB).
    for r in rows:
        if r["simulation"] in ("geometric", "traced_rays") and r["input"] == "synthetic":
            assert r["psnr_db"] > r["noise_floor_psnr_db"] + 2.0
            assert abs(r["shift_rows_px"]) < 0.05 and abs(r["shift_cols_px"]) < 0.05
    assert "plus two" in (run_dir / "tables.md").read_text()
    assert "data:image/png;base64," in (run_dir / "report.html").read_text()


def test_resumed_run_equals_uninterrupted_run_without_rendering(tiny, tmp_path):
    full = tmp_path / "full"
    run_campaign(tiny, full, render=fake_render, show_progress=False)
    # an interrupted run: one item unfinished (no result.json), its renders done
    partial = tmp_path / "partial"
    shutil.copytree(full, partial)
    victim = sorted((partial / "items").iterdir())[0]
    (victim / "result.json").unlink()
    summary = run_campaign(tiny, partial, render=refuse, show_progress=False)
    assert summary.renders_made == 0 and summary.items_reused == 1
    assert numbers(partial) == numbers(full)
    # and a finished run redoes nothing at all
    summary = run_campaign(tiny, full, render=refuse, show_progress=False)
    assert summary.items_reused == 2 and summary.renders_made == 0


def test_parallel_workers_give_the_same_numbers(tiny, tmp_path):
    serial, parallel = tmp_path / "serial", tmp_path / "parallel"
    run_campaign(tiny, serial, render=fake_render, show_progress=False)
    run_campaign(tiny, parallel, render=fake_render, workers=2, show_progress=False)
    assert numbers(parallel) == numbers(serial)


def test_items_shared_with_a_helper_process_give_the_same_numbers(tiny, tmp_path, monkeypatch):
    # The campaign's helper process computes items from the end of the list while this process takes them from
    # the front: every item's numbers are those of a run without it.
    from vissim.validation.engine import helper_process

    monkeypatch.setattr(helper_process, "available_cores", lambda: helper_process.HELPER_CORES)
    alone, shared = tmp_path / "alone", tmp_path / "shared"
    run_campaign(tiny, alone, render=fake_render, show_progress=False)
    with helper_process.campaign_helper("vissim.validation.dslr.item"):
        summary = run_campaign(tiny, shared, render=fake_render, show_progress=False)
    assert numbers(shared) == numbers(alone)
    assert sorted(key for key, _ in summary.item_seconds) == sorted(tiny.item_key(c) for c in tiny.configurations)


@pytest.mark.slow  # a local dask cluster takes ~5 s to start; the process-pool test above covers parallel runs by default
def test_dask_local_cluster_gives_the_same_numbers(tiny, tmp_path):
    distributed = pytest.importorskip("distributed")
    serial, remote = tmp_path / "serial", tmp_path / "dask"
    run_campaign(tiny, serial, render=fake_render, show_progress=False)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        run_campaign(tiny, remote, render=fake_render, scheduler=cluster.scheduler_address, show_progress=False)
    assert numbers(remote) == numbers(serial)


@pytest.mark.slow  # a whole campaign or fit: run with -m slow
def test_cli_validate_and_report(tiny, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(runner, "render_any", fake_render)
    run_dir = tmp_path / "cli_run"
    assert main(["validate", tiny.source, "-o", str(run_dir), "--spp", "2"]) == 0
    out = capsys.readouterr().out
    assert "report:" in out and "plus two" in out
    (run_dir / "report.html").unlink()
    assert main(["report", str(run_dir)]) == 0
    assert (run_dir / "report.html").exists()
    assert main(["report", str(tmp_path)]) == 2


@pytest.mark.parametrize(
    "text, fragment",
    [
        ('[campaign]\nspp = 0\n[[item]]\nletter = "K"\n', "campaign.spp"),
        ('[[item]]\nletter = "E"\n', "Sloan letters"),
        ('[[item]]\nletter = "K"\nlenses = [{ cylinder_diopters = 1.0 }]\n', "axis"),
        ('[[item]]\nletter = "K"\nlenses = [1, 2, 3, 4]\n', "at most 3"),
        ('[campaign]\nseeds = [1, 1]\n[[item]]\nletter = "K"\n', "seeds"),
        ("[campaign]\n", "no configurations"),
        ("[campaign\n", "not valid TOML"),
    ],
)
def test_bad_campaign_files_get_clear_errors(tmp_path, text, fragment):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(VissimInputError, match=fragment):
        load_campaign(path)


def test_shipped_campaigns_load():
    quick = load_campaign("validation/quick.toml")
    thesis = load_campaign("validation/thesis.toml")
    assert 3 <= len(quick.configurations) <= 8 and len(thesis.configurations) > 50
    keys = [thesis.item_key(c) for c in thesis.configurations]
    assert len(set(keys)) == len(keys)
    json.dumps([c.as_json() for c in quick.configurations])


GROUPS = """
[campaign]
name = "groups"
spp = 4
seeds = [1, 2]
tile_px = [64, 64]
simulations = ["geometric"]
inputs = ["synthetic"]
wave_truth = false

[[sweep]]
name = "myopia"
letter = ["K"]
logmar = [0.7]
lens = [0.5, 1.0]

[[item]]
name = "myopia: not in the sweep"
letter = "K"
logmar = 0.7
lenses = [2.0]
"""


def test_rows_are_grouped_by_the_configurations_group_field_not_by_their_names(campaign_file, tmp_path):
    from dataclasses import replace

    campaign = campaign_file(GROUPS)
    groups = {c.name: c.group for c in campaign.configurations}
    assert groups.pop("myopia: not in the sweep") == "myopia: not in the sweep"  # an item is its own group
    assert set(groups.values()) == {"myopia"} and len(groups) == 2
    for c in campaign.configurations:  # a label: the item keys do not see it
        assert campaign.item_key(replace(c, group="another")) == campaign.item_key(c)
    run_dir = tmp_path / "run"
    run_campaign(campaign, run_dir, render=fake_render, show_progress=False)
    write_report(run_dir)
    rows = metrics_rows(load_results(run_dir))
    assert {r["configuration"]: r["group"] for r in rows} == {c.name: c.group for c in campaign.configurations}
    tables = (run_dir / "tables.md").read_text()
    assert "| myopia (2) |" in tables and "| myopia: not in the sweep (1) |" in tables
