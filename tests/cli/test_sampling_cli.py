"""Images carry their angular sampling: what each command writes, ``blur`` reads without --arcmin-per-px."""

from __future__ import annotations

import numpy as np
import pytest

from vissim.cli import main
from vissim.imageio import read_image, write_image


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _blur(capsys, source, target):
    return run(capsys, "blur", source, "-o", target, "--rx", "-1.00 DS", "--pupil-mm", "3")


@pytest.mark.parametrize("suffix", [".exr", ".png"])
def test_blur_reads_the_sampling_of_a_chart(capsys, tmp_path, suffix):
    chart = tmp_path / f"chart{suffix}"
    assert run(capsys, "chart", "--logmar", "1", "--letters", "NCKZO", "--arcmin-per-px", "0.75", "-o", chart)[0] == 0
    assert read_image(chart).arcmin_per_px == 0.75
    target = tmp_path / "blurred.exr"
    code, _, err = _blur(capsys, chart, target)
    assert code == 0, err
    blurred = read_image(target)
    assert blurred.arcmin_per_px == 0.75  # and the output carries it on
    assert blurred.provenance["inputs"]["arcmin_per_px"] == 0.75
    again = tmp_path / "again.exr"
    assert _blur(capsys, target, again)[0] == 0  # a blurred image blurs again with its own sampling
    assert read_image(again).arcmin_per_px == 0.75


def test_blur_reads_the_sampling_of_a_chart_written_before_the_sampling_key(capsys, tmp_path):
    old = tmp_path / "old.exr"
    write_image(old, np.full((40, 40), 0.5, np.float32),
                provenance={"inputs": {"command": "vissim chart", "options": {"arcmin_per_px": 2.0}}})
    code, _, err = _blur(capsys, old, tmp_path / "o.exr")
    assert code == 0, err
    assert read_image(tmp_path / "o.exr").arcmin_per_px == 2.0


def test_psf_records_its_sampling(capsys, tmp_path):
    code, _, _ = run(capsys, "psf", "--rx", "-1", "--pupil-mm", "3", "--arcmin-per-px", "0.5", "--size", "64",
                     "-o", tmp_path / "p.png")
    assert code == 0
    assert read_image(tmp_path / "p.exr").arcmin_per_px == 0.5
    assert read_image(tmp_path / "p.png").arcmin_per_px == 0.5


def test_an_image_without_sampling_asks_for_arcmin_per_px(capsys, tmp_path):
    bare = tmp_path / "bare.png"
    write_image(bare, np.full((32, 32), 0.5, np.float32))
    for command in (["blur", bare, "-o", tmp_path / "x.exr", "--rx", "-2", "--pupil-mm", "3"],
                    ["blur-depth", bare, tmp_path / "d.npy", "-o", tmp_path / "y.exr", "--rx", "-2", "--pupil-mm", "3"]):
        np.save(tmp_path / "d.npy", np.full((32, 32), 2.0))
        code, out, err = run(capsys, *command)
        lines = [line for line in err.splitlines() if line.strip()]
        assert code == 2 and len(lines) == 1, err
        assert "carries no angular sampling" in lines[0] and "--arcmin-per-px" in lines[0]
        assert not (tmp_path / "x.exr").exists() and not (tmp_path / "y.exr").exists()
    code, _, err = run(capsys, "blur", bare, "-o", tmp_path / "x.exr", "--rx", "-2", "--pupil-mm", "3",
                       "--arcmin-per-px", "1")
    assert code == 0, err
    assert read_image(tmp_path / "x.exr").arcmin_per_px == 1.0


def _jit_mitsuba() -> bool:
    try:
        from vissim.render.backend import choose_variant

        return not choose_variant("mono").variant.startswith("scalar")
    except Exception:  # no Mitsuba at all
        return False


@pytest.mark.skipif(not _jit_mitsuba(), reason="no JIT Mitsuba variant")
def test_blur_reads_the_sampling_of_a_bench_render(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("VISSIM_CACHE_DIR", str(tmp_path / "cache"))
    render = tmp_path / "bench.exr"
    code, _, err = run(capsys, "render", "bench", "--letter", "C", "--size", "21x21", "--spp", "4",
                       "--arcmin-per-px", "1.5", "-o", render)
    assert code == 0, err
    assert read_image(render).arcmin_per_px == 1.5
    target = tmp_path / "blurred.exr"
    code, _, err = _blur(capsys, render, target)
    assert code == 0, err
    assert read_image(target).arcmin_per_px == 1.5
