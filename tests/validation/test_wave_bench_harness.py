"""The wave bench as a campaign truth (issue 13, harness): rows, tables, residual causes, caching.

A tiny campaign with the stand-in bench (no Mitsuba); the wave bench itself is the real trace
(vissim.bench.dslr.wave_truth), so its numbers are physics, not plumbing.
"""

import json
import math

import pytest
from fake_bench import fake_render, refuse, write_campaign

from vissim.errors import VissimInputError
from vissim.validation.dslr.report import metrics_rows, summary_lines
from vissim.validation.engine.report import load_results, write_report
from vissim.validation.engine.runner import run_campaign
from vissim.validation.dslr.wave_bench import TRACED_RAYS, WAVE_BENCH, WAVE_BENCH_NOTE

TINY = """
[campaign]
name = "tiny"
spp = 4
seeds = [1, 2]
tile_px = [64, 64]
wavelength_nm = 550.0
simulations = ["wave", "geometric", "thesis"]
inputs = ["render", "synthetic"]
{extra}

[[item]]
name = "plus two"
letter = "K"
logmar = 0.7
lenses = [2.0]

[[item]]
name = "no lens"
letter = "K"
logmar = 0.7
"""


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    tmp_path = tmp_path_factory.mktemp("wave_bench")
    tiny = write_campaign(tmp_path, TINY.format(extra=""))
    run_dir = tmp_path / "run"
    run_campaign(tiny, run_dir, render=fake_render, show_progress=False)
    write_report(run_dir)
    return tiny, run_dir


def test_wave_and_thesis_of_the_synthetic_chart_are_compared_with_the_wave_bench_without_a_floor(run):
    _, run_dir = run
    rows = [r for r in metrics_rows(load_results(run_dir)) if r["reference"] == WAVE_BENCH_NOTE]
    # wave and thesis (wave optics), synthetic input only; geometric stays with the render
    assert sorted((r["configuration"], r["simulation"], r["input"]) for r in rows) == [
        ("no lens", "thesis", "synthetic"), ("no lens", "wave", "synthetic"),
        ("plus two", "thesis", "synthetic"), ("plus two", "wave", "synthetic")]
    assert all(math.isnan(r["noise_floor_psnr_db"]) and math.isnan(r["noise_floor_ssim"]) for r in rows)
    metrics = json.loads((run_dir / "metrics.json").read_text())
    json_rows = [r for r in metrics["rows"] if r["reference"] == WAVE_BENCH_NOTE]
    assert len(json_rows) == 4 and all(r["noise_floor_psnr_db"] is None for r in json_rows)
    assert (run_dir / "metrics.csv").read_text().count(WAVE_BENCH_NOTE) == 4
    # the terminal summary judges them apart from the render's floor: one line, PSNR alone, the lenses' only
    lines = [line for line in summary_lines(metrics_rows(load_results(run_dir))) if "wave bench" in line]
    lowest = min(r["psnr_db"] for r in rows if r["simulation"] == "wave" and r["configuration"] != "no lens")
    assert lines == [line for line in lines if line.startswith("wave optics against the noise-free wave bench")]
    assert len(lines) == 1 and f"PSNR {lowest:.1f} dB or more" in lines[0]


def test_wave_simulation_reaches_60_db_against_the_wave_bench(run):
    # Issue 13: >= 50 dB, aim 60. At 550 nm the residual is the glass's dispersion (measured 66 dB
    # on the quick campaign's +2 D letters); with no lens only float32 rounding is left.
    _, run_dir = run
    psnr = {r["configuration"]: r["psnr_db"] for r in metrics_rows(load_results(run_dir))
            if r["reference"] == WAVE_BENCH_NOTE and r["simulation"] == "wave"}
    assert psnr["plus two"] >= 60.0, psnr
    assert psnr["no lens"] >= 100.0, psnr


def test_tables_have_the_wave_bench_summary_and_name_each_groups_cause(run):
    _, run_dir = run
    text = (run_dir / "tables.md").read_text()
    header = next(line for line in text.splitlines() if line.startswith("| group") and "wave bench" in line)
    cells = [c.strip() for c in header.strip("|").split("|")]
    assert "wave / wave bench" in cells and "thesis / wave bench" in cells
    residuals = text.split("### Residuals against the wave bench, explained")[1].split("###")[0]
    row = next(line for line in residuals.splitlines() if line.startswith("| plus two (1) |"))
    assert "| dispersion (1) |" in row
    # the tables against the render are unchanged: no wave-bench column there
    render_summary = text.split("### Summary: PSNR against the wave bench")[0].split("### Summary: median PSNR")[1]
    assert "wave bench" not in render_summary
    assert "against the wave bench" in (run_dir / "report.html").read_text()


def test_the_geometric_self_check_has_its_summary_with_no_lens_configurations_apart(run):
    _, run_dir = run
    rows = [r for r in metrics_rows(load_results(run_dir)) if r["simulation"] == TRACED_RAYS]
    # one row per rendered item: the synthetic chart against the render, with its geometric floor
    assert sorted((r["configuration"], r["input"], r["reference"]) for r in rows) == [
        ("no lens", "synthetic", "render (no diffraction)"), ("plus two", "synthetic", "render (no diffraction)")]
    assert all(r["noise_floor_psnr_db"] > 0 for r in rows)
    text = (run_dir / "tables.md").read_text()
    section = text.split("### Summary: the geometric self-check")[1].split("###")[0]
    assert "| plus two (1) |" in section and "Without lenses (1):" in section and "| no lens (" not in section
    # the first summary (the simulations) has no traced-rays column
    assert TRACED_RAYS not in text.split("### Summary: the geometric self-check")[0]


def test_residual_explanation_is_in_numbers_and_plausible(run):
    _, run_dir = run
    budgets = {r["configuration"]["name"]: r["wave_bench"] for r in load_results(run_dir)}
    plus = budgets["plus two"]
    # vergence theory of the rendered thick lens is the d-line trace (tests/bench/test_lens_trace.py: 1.5e-5 D)
    assert abs(plus["vergence_approximation_diopters"]) < 0.01 * 0.01
    # crown glass (n_d 1.523, V_d 58.6) is denser at 550 nm: the lens adds ~0.37 % more (docs/conventions.md)
    assert plus["index_difference"][0] == pytest.approx(0.00191, abs=2e-5)
    assert plus["dispersion_diopters"] == pytest.approx(0.0037 * 2.0, rel=0.05)
    assert plus["power_difference_diopters"] == pytest.approx(plus["dispersion_diopters"], abs=1e-4)
    assert abs(plus["spherical_aberration_um"]) < 1e-4 and plus["obliquity_rms_um"] < 1e-3
    assert plus["thickness_diopters"] != 0.0  # the thick lens's own vergence, in both
    assert plus["cause"] == "dispersion"
    assert budgets["no lens"]["cause"] == "none"


def test_the_wave_truth_is_an_item_image_with_provenance(run):
    from vissim.imageio import read_image

    _, run_dir = run
    result = next(r for r in load_results(run_dir) if r["configuration"]["name"] == "plus two")
    image = read_image(run_dir / result["images"]["wave_truth"])
    assert image.pixels.shape[:2] == (64, 64)
    truth = image.provenance["wave_truth"]
    assert truth["kind"] == "bench wave truth" and truth["traced"][0]["wavelength_nm"] == 550.0
    comp = next(c for c in result["comparisons"] if c["reference_kind"] == WAVE_BENCH and c["simulation"] == "wave")
    assert comp["reference_image"] == "wave_truth" and result["noise_floor"][WAVE_BENCH] is None


def test_a_rerun_reuses_every_item(run):
    tiny, run_dir = run
    def numbers():
        return [(r["configuration"], r["simulation"], r["reference"], r["psnr_db"])
                for r in metrics_rows(load_results(run_dir))]

    before = numbers()
    summary = run_campaign(tiny, run_dir, render=refuse, show_progress=False)
    assert summary.items_reused == summary.items_total == 2 and summary.renders_made == 0
    assert numbers() == before


@pytest.mark.slow  # a whole campaign or fit: run with -m slow
def test_wave_truth_false_skips_the_wave_bench_and_keys_the_items_apart(run, tmp_path):
    tiny, _ = run
    off = write_campaign(tmp_path, TINY.format(extra="wave_truth = false"))
    assert off.settings.wave_truth is False and tiny.settings.wave_truth is True
    assert {off.item_key(c) for c in off.configurations}.isdisjoint(tiny.item_key(c) for c in tiny.configurations)
    quiet = tmp_path / "off"
    run_campaign(off, quiet, render=fake_render, show_progress=False)
    write_report(quiet)
    assert not any(r["reference"] == WAVE_BENCH_NOTE or r["simulation"] == TRACED_RAYS
                   for r in metrics_rows(load_results(quiet)))
    assert "wave bench" not in (quiet / "tables.md").read_text()
    assert "geometric self-check" not in (quiet / "tables.md").read_text()


def test_wave_truth_must_be_a_boolean(tmp_path):
    with pytest.raises(VissimInputError, match="campaign.wave_truth"):
        write_campaign(tmp_path, TINY.format(extra='wave_truth = "yes"'))
