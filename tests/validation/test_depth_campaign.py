"""The depth campaign: masks, a tiny campaign rendered with Mitsuba, resuming, reports, dispatch.

Expectations: where the render is the single-depth blur of one panel (the interiors of
vissim.validation.depth.masks) the geometric blur_depth is as good as the single-plane harness:
its PSNR against the render is at least the render's noise floor (two seeds) minus 1 dB, and a
perfect simulation would score the floor + 3 dB (MSE sigma^2 against 2 sigma^2).  Occlusion
bands are measured and must be reported (finite numbers, a row of their own); no threshold is
placed on them -- they measure blur_depth's compositing, whose numbers go to the report.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from fake_bench import fake_render, refuse
from provenance_walk import image_provenance, json_without_provenance

from tests.bench.depth_scenes import default_panels_scene
from vissim.bench.depth.scene import panel_geometries
from vissim.bench.depth.viewers import CameraViewer, EyeViewer
from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import Prescription
from vissim.render.backend import choose_variant
from vissim.validation.engine import runner
from vissim.validation.engine.loader import load_campaign
from vissim.validation.depth.masks import depth_regions
from vissim.validation.depth.report import depth_rows
from vissim.validation.engine.report import load_results
from vissim.validation.engine.runner import run_campaign
from vissim.validation.engine.validate import rebuild_report, validate

ROOT = Path(__file__).resolve().parents[2]
needs_jit = pytest.mark.skipif(choose_variant("mono").variant.startswith("scalar"), reason="no JIT Mitsuba variant")

TINY_SCENE = """
[image]
arcmin_per_px = 1.0
size_px = [56, 112]
[sampling]
sampler = "multijitter"
[eye]
prescription = "-1.00 DS"
pupil_diameter_mm = 3.0
[[panel]]
distance_m = 3.0
center_arcmin = [16.0, 0.0]
letters = "H"
logmar = 0.5
padding_arcmin = 6.0
[[panel]]
distance_m = 1.0
center_arcmin = [-24.0, 0.0]
letters = "Z"
logmar = 0.5
padding_arcmin = 6.0
"""

TINY_CAMPAIGN = """
[campaign]
kind = "depth"
name = "tiny depth"
spp = 32
aux_spp = 16
seeds = [5, 6]
aux_seed = 7

[[config]]
name = "myope"
scene = "scene.toml"

[[config]]
name = "DSLR at 3 m"
scene = "scene.toml"
camera = { f_number = 5.0, focus_distance_m = 3.0 }
"""


@pytest.fixture(autouse=True)
def _mesh_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("VISSIM_CACHE_DIR", str(tmp_path / "cache"))


@pytest.fixture
def tiny(tmp_path):
    (tmp_path / "scene.toml").write_text(TINY_SCENE)
    path = tmp_path / "tiny.toml"
    path.write_text(TINY_CAMPAIGN)
    return path


def test_shipped_depth_campaign_loads():
    campaign = load_campaign(ROOT / "validation" / "depth.toml")
    assert len(campaign.configurations) == 7 and campaign.settings.seeds == (1, 2)
    viewers = [c.viewer for c in campaign.configurations]
    assert viewers[0] == EyeViewer(Prescription(-2.0), 4.0, 0.0)
    assert isinstance(viewers[-1], CameraViewer) and viewers[-1].lenses[0].sphere_diopters == 1.0
    assert len({campaign.item_key(c) for c in campaign.configurations}) == 7


@pytest.mark.parametrize("text, fragment", [
    ("[campaign]\nkind = 'depth'\nspp = 0\n", "spp"),
    ("[campaign]\nkind = 'depth'\nseeds = [1, 1]\n[[config]]\nscene = 'scene.toml'\n", "two different integer seeds"),
    ("[campaign]\nkind = 'depth'\n[[config]]\nname = 'x'\n", "needs scene"),
    ("[campaign]\nkind = 'depth'\n[[config]]\nscene = 'scene.toml'\nprescription = 'plano'\ncamera = { f_number = 4.0 }\n", "not both"),
    ("[campaign]\nkind = 'depth'\nsimulations = ['thesis']\n", "choose from geometric, wave"),
    ("[campaign]\nkind = 'depth'\n", "no configurations"),
    ("[campaign]\nname = 'flat'\n[[config]]\nscene = 'scene.toml'\n", "add kind = \"depth\" to \\[campaign\\]"),
    ("[campaign]\nkind = 'depth'\n[[item]]\nletter = 'K'\n", "unknown table"),
    ("[campaign]\nkind = 'cyclops'\n", "unknown bench kind 'cyclops'"),
])
def test_bad_depth_campaign_files_get_clear_errors(tmp_path, text, fragment):
    (tmp_path / "scene.toml").write_text(TINY_SCENE)
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(VissimInputError, match=fragment):
        load_campaign(path)


def test_interiors_keep_one_blur_radius_from_depth_edges_and_a_slope_is_no_edge():
    """Two flat depths side by side and a gradual ramp: the band around the step is its blur + margin."""
    scene = default_panels_scene((6.0, 0.5))
    far, near = panel_geometries(scene)
    proximity = np.full((40, 120), 1.0 / 6.0)
    proximity[:, 60:] = 2.0
    radius = {1.0 / 6.0: 8.0, 2.0: 3.0}

    def radius_px(p):
        return np.where(p < 1.0, radius[1.0 / 6.0], radius[2.0])

    masks = depth_regions(proximity, [far, near], radius_px, pupil_diameter_mm=4.0, arcmin_per_px=1.0, margin_px=1.0)
    assert set(masks.interiors) == {far.name, near.name}
    band_cols = np.flatnonzero(masks.boundary[20])
    assert band_cols.min() == 59 - 9 and band_cols.max() == 60 + 9  # the larger blur radius + 1 px, either side
    assert masks.frame[:, :9].all() and not masks.frame[20, 30]
    assert not (masks.boundary & masks.frame).any() and not (masks.interiors[far.name] & masks.boundary).any()
    ramp = np.tile(np.linspace(2.0, 0.34, 120), (40, 1))  # 0.014 D per pixel: a tilted chart
    sloped = depth_regions(ramp, [far, near], lambda p: np.full(np.shape(p), 2.0), pupil_diameter_mm=4.0,
                           arcmin_per_px=1.0)
    # the jump threshold is one pixel of blur step: theta / pupil = 1 arcmin / 4 mm = 0.0727 D
    one_pixel_d = math.radians(1.0 / 60.0) / 4e-3
    assert not sloped.discontinuities.any() and sloped.jump_diopters == pytest.approx(one_pixel_d, rel=1e-9)


@needs_jit
def test_tiny_depth_campaign_runs_resumes_and_reports(tiny, tmp_path):
    run_dir = tmp_path / "run"
    done = validate(tiny, run_dir, show_progress=False)
    # per config: two truths, all-in-focus and depth, and each of the two panels' radiance and coverage
    assert done.kind == "depth" and done.summary.items_total == 2 and done.summary.renders_made == 16
    names = {p.name for p in done.report_files}
    assert {"metrics.json", "metrics.csv", "tables.md", "report.html", "figure_depth_geometric_layered.png",
            "figure_depth_geometric_rgbd.png"} <= names
    rows = depth_rows(load_results(run_dir))
    for row in rows:
        if row["region"].startswith("panel"):
            assert row["n_px"] > 100
            floor = row["noise_floor_psnr_db"]
            assert row["psnr_db"] >= min(floor, 60.0) - 1.0, row  # as good as the render noise allows
        if row["simulation"] == "geometric layered" and row["region"] in ("all", "boundary", "frame"):
            # the layered input knows what lies behind edges and beyond the frame: the noise floor everywhere
            assert row["psnr_db"] >= row["noise_floor_psnr_db"] - 1.0, row
    boundary = [r for r in rows if r["region"] == "boundary"]
    assert len(boundary) == 8 and all(r["n_px"] > 100 and math.isfinite(r["psnr_db"]) for r in boundary)
    for image, provenance in image_provenance(run_dir).items():  # every image, with its renders' variant and spp
        if image.parent.name == "renders":
            assert provenance["variant"] and provenance["spp_used"] >= provenance["inputs"]["render"]["spp"]
        elif image.parent.parent.name == "items":
            renders = provenance["inputs"]["render_provenance"]
            assert set(renders) == {"truth_0", "truth_1", "all_in_focus", "proximity", "layer_0", "coverage_0",
                                    "layer_1", "coverage_1"}
            assert all(r["variant"] and r["spp_used"] for r in renders.values())
    assert json_without_provenance(run_dir) == []
    tables = (run_dir / "tables.md").read_text()
    assert "| boundary |" in tables and "panel 3 m" in tables and "DSLR at 3 m" in tables
    page = (run_dir / "report.html").read_text()  # reads on its own: code spans, alt text, no issue numbers
    assert "`" not in page and "<code>boundary</code>" in page
    figures = len(list(run_dir.glob("figure_depth_*.png")))
    assert page.count("<img ") == len(re.findall(r"<img [^>]*alt='[^']{60,}'", page)) == figures >= 2
    assert not re.search(r"\b[Ii]ssues? \d+", tables + page)
    before = (run_dir / "metrics.json").read_text()
    again = run_campaign(load_campaign(tiny), run_dir, render=refuse, show_progress=False)
    assert again.items_reused == 2 and again.renders_made == 0
    assert json.loads(before)["rows"] == json.loads((run_dir / "metrics.json").read_text())["rows"]
    written, lines = rebuild_report(run_dir)  # vissim report RUN: no rendering
    assert (run_dir / "report.html") in written and any("boundary" in line for line in lines)
    item = json.loads(next((run_dir / "items").glob("*/result.json")).read_text())
    assert item["masks"]["regions"][-2:] == ["boundary", "frame"] and item["equivalent_eye"]["pupil_diameter_mm"] > 0


def test_validate_runs_dslr_campaigns_too(tmp_path, monkeypatch):
    path = tmp_path / "flat.toml"
    path.write_text("[campaign]\nname = 'flat'\nspp = 4\ntile_px = [64, 64]\nsimulations = ['geometric']\n"
                    "inputs = ['render']\n[[item]]\nletter = 'K'\nlogmar = 0.7\nlenses = [2.0]\n")
    monkeypatch.setattr(runner, "render_any", fake_render)
    done = validate(path, tmp_path / "run", show_progress=False)
    assert done.kind == "dslr" and done.summary.items_total == 1 and "PSNR" in done.text()
    written, lines = rebuild_report(tmp_path / "run")
    # header, the one comparison, and the geometric self-check (the wave bench is on by default)
    assert (tmp_path / "run" / "tables.md") in written and len(lines) == 3


@needs_jit
@pytest.mark.slow
def test_shipped_depth_campaign_interiors_match_to_the_noise_floor(tmp_path):
    """validation/depth.toml (about two minutes on 2 cores): every panel interior, both optics and inputs;
    the layered geometric simulation at the noise floor everywhere: whole image, occlusion bands, frame."""
    done = validate(ROOT / "validation" / "depth.toml", tmp_path / "run", show_progress=False)
    rows = depth_rows(load_results(tmp_path / "run"))
    interiors = [r for r in rows if r["region"].startswith(("panel", "tilted"))]
    assert len(interiors) == 4 * (4 * 4 + 3)  # (geometric, wave) x (layered, rgbd)
    for row in interiors:
        floor = min(row["noise_floor_psnr_db"], 60.0)  # noise-free renders: float32 rounding only
        assert row["psnr_db"] >= floor - (1.0 if row["simulation"].startswith("geometric") else 1.5), row
    layered = [r for r in rows if r["simulation"] == "geometric layered" and r["region"] in ("all", "boundary", "frame")
               and r["n_px"] > 0]
    assert len(layered) == 7 * 3 - 1  # the tilted DSLR view has no boundary band outside the frame
    for row in layered:  # issue 15: within 3 dB of the floor, aiming at 1 dB; measured >= +1.2 dB
        assert row["psnr_db"] >= min(row["noise_floor_psnr_db"], 60.0) - 1.0, row
    boundary = [r for r in rows if r["region"] == "boundary" and r["n_px"] > 1000]
    assert boundary and all(math.isfinite(r["psnr_db"]) for r in boundary)
    assert done.summary.items_total == 7
