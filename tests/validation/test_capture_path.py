"""The RAW path end to end: a virtual capture (render -> Bayer -> noise -> DNG) as ground truth."""

import numpy as np
import pytest
from fake_bench import fake_render
from provenance_walk import image_provenance

from vissim.charts import optotype_tile
from vissim.validation.engine.loader import load_campaign
from vissim.validation.dslr.captures import capture_tile, file_sha256, load_manifest
from vissim.imaging.raw import camera_arcmin_per_px
from vissim.bench.dslr.bench import DslrBench
from vissim.validation.dslr.renders import RenderSpec, build_dslr
from vissim.validation.dslr.report import metrics_rows
from vissim.validation.engine.report import load_results
from vissim.validation.engine.runner import run_campaign
from vissim.imaging.virtual_capture import add_sensor_noise, mosaic_bayer, quantise, write_dng

SENSOR_PX = 128
GAINS = np.array([0.55, 1.0, 0.45])  # a warm light: the channels see different levels


def virtual_dng(path, lenses, seed):
    """A capture of the letter: rendered at the camera's own sampling, then through a sensor."""
    scale = camera_arcmin_per_px(5.2, 18.0, object_distance_m=0.9144)
    spec = RenderSpec(DslrBench(lenses=lenses, arcmin_per_px=scale, size_px=(SENSOR_PX, SENSOR_PX), spp=4, seed=seed),
                      "K", 0.7, "black-on-white")
    radiance = fake_render(spec).astype(np.float64) / 0.9 * 0.6  # paper at 60 % of full scale
    mosaic = mosaic_bayer(radiance[..., None] * GAINS, "RGGB")
    noisy = add_sensor_noise(mosaic, full_well_electrons=30000, read_noise_electrons=2.0, rng=seed)
    write_dng(path, quantise(noisy, black_level=2048, white_level=15000), black_level=2048, white_level=15000, pattern="RGGB")
    return path


@pytest.fixture
def capture_campaign(tmp_path):
    settings_probe = load_campaign_text(tmp_path, manifest=False)
    lenses = build_dslr(settings_probe.configurations[0], settings_probe.settings).lenses
    files = {
        "k-plus2": virtual_dng(tmp_path / "k_plus2.dng", lenses, 11),
        "k-plus2-repeat": virtual_dng(tmp_path / "k_plus2_b.dng", lenses, 12),
        "k-plain": virtual_dng(tmp_path / "k_plain.dng", (), 13),
    }
    centre = SENSOR_PX / 2
    entries = []
    for capture_id, path in files.items():
        lens_line = "lenses = [2.0]" if "plus2" in capture_id else "lenses = []"
        entries.append(
            f'[[capture]]\nid = "{capture_id}"\nfile = "{path.name}"\nsha256 = "{file_sha256(path)}"\n'
            f'letter = "K"\nlogmar = 0.7\n{lens_line}\nletter_center_px = [{centre}, {centre}]\n'
            f'no_lens_capture = "k-plain"\nrepeat_capture = "{"k-plus2-repeat" if capture_id == "k-plus2" else ""}"\n'
        )
    (tmp_path / "manifest.toml").write_text("\n".join(entries).replace('repeat_capture = ""\n', ""))
    return load_campaign_text(tmp_path, manifest=True)


def load_campaign_text(tmp_path, manifest):
    text = '[campaign]\nname = "captures"\nspp = 4\ntile_px = [64, 64]\nsimulations = ["geometric", "wave"]\n'
    if manifest:
        text += 'manifest = "manifest.toml"\n'
    text += '[[item]]\nname = "render"\nletter = "K"\nlogmar = 0.7\nlenses = [2.0]\n'
    if manifest:
        text += '[[item]]\nname = "capture"\nletter = "K"\nlogmar = 0.7\nlenses = [2.0]\ncapture = "k-plus2"\n'
        text += '[[item]]\nname = "absent"\nletter = "N"\nlogmar = 0.7\ncapture = "nowhere"\n'
    path = tmp_path / "captures.toml"
    path.write_text(text)
    return load_campaign(path)


def test_virtual_capture_tile_reproduces_the_linear_image(capture_campaign, tmp_path):
    captures = load_manifest(tmp_path / "manifest.toml")
    tile = capture_tile(captures["k-plain"], 1.0, (64, 64))
    reference = fake_render(RenderSpec(DslrBench(size_px=(64, 64), spp=4, seed=99), "K", 0.7, "black-on-white"))
    # paper and ink levels come back (linear, gains removed); shot + read + render noise ~0.01
    assert np.median(tile[:8]) == pytest.approx(0.9, abs=0.01)
    assert np.percentile(tile, 1) == pytest.approx(0.04, abs=0.03)
    assert abs(float(tile.mean()) - float(reference.mean())) < 0.02


def test_paper_ring_is_measured_on_the_sky_for_a_long_lens(tmp_path):
    # 68 mm at 3 m: 0.257 arcmin per sensor px, four times finer than the campaign's 1 arcmin/px.
    # The letter O (LogMAR 0.7: 25 arcmin, ink between 7.5 and 12.5 arcmin from its centre) fills a
    # ring of 0.75-1.5 tile half-widths counted in sensor px (6-12 arcmin: 84 % ink); counted on
    # the sky (24-48 arcmin) the ring is all paper, so the paper comes back at 0.9.
    scale = camera_arcmin_per_px(5.2, 68.0, object_distance_m=3.0)
    chart = optotype_tile("O", 0.7, arcmin_per_px=scale, size_px=(416, 416), viewing_distance_m=3.0,
                          snap_to_pixels=False).pixels.astype(np.float64) / 0.9 * 0.6
    noisy = add_sensor_noise(mosaic_bayer(chart[..., None] * GAINS, "RGGB"), full_well_electrons=30000,
                             read_noise_electrons=2.0, rng=5)
    write_dng(tmp_path / "o.dng", quantise(noisy, black_level=2048, white_level=15000), black_level=2048,
              white_level=15000, pattern="RGGB")
    (tmp_path / "manifest.toml").write_text(
        '[[capture]]\nid = "o"\nfile = "o.dng"\nfocal_length_mm = 68.0\nchart_distance_m = 3.0\n'
        'letter = "O"\nlogmar = 0.7\nletter_center_px = [208.0, 208.0]\n')
    tile = capture_tile(load_manifest(tmp_path / "manifest.toml")["o"], 1.0, (64, 64))
    reference = optotype_tile("O", 0.7, arcmin_per_px=1.0, size_px=(64, 64), viewing_distance_m=3.0,
                              snap_to_pixels=False).pixels
    assert np.median(tile[:8]) == pytest.approx(0.9, abs=0.01)
    assert np.percentile(tile, 1) == pytest.approx(0.04, abs=0.03)
    assert abs(float(tile.mean()) - float(reference.mean())) < 0.02


def test_campaign_with_captures_and_an_absent_one(capture_campaign, tmp_path):
    run_dir = tmp_path / "run"
    summary = run_campaign(capture_campaign, run_dir, render=fake_render, show_progress=False)
    assert len(summary.skipped) == 1 and "nowhere" in summary.skipped[0]
    rows = {(r["configuration"], r["simulation"], r["input"]): r for r in metrics_rows(load_results(run_dir))}
    from_capture = rows[("capture", "geometric", "synthetic")]
    from_render = rows[("render", "geometric", "synthetic")]
    # The capture path (sensor noise, quantisation, resampling from 0.974 arcmin/px) agrees with
    # the simulation about as well as the render path does: within 6 dB, and far above chance.
    assert from_capture["psnr_db"] > 30 and from_capture["ssim"] > 0.95
    assert from_capture["psnr_db"] > from_render["psnr_db"] - 6
    assert np.isfinite(from_capture["noise_floor_psnr_db"])  # from the repeat exposure
    captured = [prov["inputs"] for prov in image_provenance(run_dir).values()
                if prov["inputs"].get("source", {}).get("ground_truth") == "capture"]
    assert captured and all(inputs["render_provenance"]["truth_a"]["sha256"] for inputs in captured)


def test_each_capture_file_is_checked_and_decoded_once_per_run(capture_campaign, tmp_path, monkeypatch):
    # Two captured items share the no-lens capture, and one's repeat is the other's truth: 3 files, not 5 reads.
    from vissim.validation.dslr import capture_plans
    from vissim.validation.dslr.captures import open_capture

    text = (tmp_path / "captures.toml").read_text()
    text += '[[item]]\nname = "capture b"\nletter = "K"\nlogmar = 0.7\nlenses = [2.0]\ncapture = "k-plus2-repeat"\n'
    (tmp_path / "twice.toml").write_text(text)
    campaign = load_campaign(tmp_path / "twice.toml")
    opened = []
    monkeypatch.setattr(capture_plans, "open_capture", lambda c: opened.append(c.id) or open_capture(c))
    todo = [(c.name, i) for i, c in enumerate(campaign.configurations) if c.capture]
    plans, skipped = capture_plans.capture_item_plans(campaign, todo)
    assert sorted(plans) == ["capture", "capture b"] and len(skipped) == 1
    assert sorted(opened) == ["k-plain", "k-plus2", "k-plus2-repeat"]  # each read (and hashed) once
    # every item holds its own copy, equal to the tile read afresh
    captures = load_manifest(tmp_path / "manifest.toml")
    first, second = (plans[name].given["no_lens"] for name in ("capture", "capture b"))
    assert first is not second
    assert np.array_equal(first, capture_tile(captures["k-plain"], 1.0, (64, 64))) and np.array_equal(first, second)
    assert np.array_equal(plans["capture b"].given["truth_a"], plans["capture"].given["truth_b"])
