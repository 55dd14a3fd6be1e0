"""``vissim render bench``: a tiny render to EXR with provenance; bad input exits 2 with one line."""

from __future__ import annotations

from pathlib import Path

import pytest

from vissim.cli import main
from vissim.imageio import read_image
from vissim.render.backend import choose_variant

SCENE = Path(__file__).resolve().parents[2] / "scenes" / "dslr_bench.toml"


@pytest.fixture(autouse=True)
def _mesh_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("VISSIM_CACHE_DIR", str(tmp_path / "cache"))


@pytest.mark.skipif(choose_variant("mono").variant.startswith("scalar"), reason="no JIT Mitsuba variant")
def test_render_bench_writes_a_linear_exr_with_provenance(tmp_path, capsys):
    out = tmp_path / "bench.exr"
    args = ["render", "bench", "--scene", str(SCENE), "--sphere", "-2", "--cylinder", "1", "--axis", "30",
            "--letter", "C", "--spp", "4", "--size", "31x27", "-o", str(out)]
    assert main(args) == 0
    assert "wrote" in capsys.readouterr().out
    image = read_image(out)
    assert image.pixels.shape == (31, 27) and 0.04 <= image.pixels.min() and image.pixels.max() <= 0.9 + 1e-5
    inputs = image.provenance["inputs"]
    assert inputs["spp"] == 4 and inputs["seed"] == 0 and inputs["variant"].endswith("_mono")
    assert inputs["bench"]["lenses"][0]["sphere_diopters"] == -2.0 and inputs["mitsuba_version"]
    assert main(args) == 2  # exists: refused before rendering
    assert "already exists" in capsys.readouterr().err


@pytest.mark.parametrize("extra, message", [
    (["--cylinder", "1"], "needs --axis"),
    (["--letter", "E"], "Sloan letter"),
    (["--size", "big"], "ROWSxCOLS"),
])
def test_bad_render_input_exits_2_with_one_line(tmp_path, capsys, extra, message):
    assert main(["render", "bench", *extra, "-o", str(tmp_path / "x.exr")]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not (tmp_path / "x.exr").exists()


def test_render_bench_refuses_non_exr_output(tmp_path, capsys):
    assert main(["render", "bench", "-o", str(tmp_path / "x.png")]) == 2
    assert ".exr" in capsys.readouterr().err
