"""Every file a campaign writes carries provenance; item images carry their renders' (variant, spp used)."""

from dataclasses import dataclass

import numpy as np
import pytest
from fake_bench import fake_render
from provenance_walk import image_provenance, json_without_provenance

from vissim.cli import main
from vissim.validation.engine import runner

CAMPAIGN = '[campaign]\nname = "provenance"\nspp = 4\ntile_px = [48, 48]\nsimulations = ["geometric", "wave"]\n' \
           '[[item]]\nname = "plus two"\nletter = "K"\nlogmar = 0.5\nlenses = [2.0]\n'


@dataclass(frozen=True)
class FakeResult:
    """What a renderer returns besides pixels (as vissim.render.run.RenderResult does)."""

    pixels: np.ndarray
    variant: str
    spp: int
    provenance: dict


def render_with_provenance(spec):
    pixels = fake_render(spec)
    return FakeResult(pixels, "fake_variant", spec.bench.spp + 1, {"inputs": {"sampler": "fake"}, "renderer": "fake"})


@pytest.mark.slow  # a whole campaign or fit: run with -m slow
def test_every_image_of_a_run_has_provenance_with_its_renders(tmp_path, monkeypatch, capsys):
    path = tmp_path / "provenance.toml"
    path.write_text(CAMPAIGN)
    monkeypatch.setattr(runner, "render_any", render_with_provenance)
    run_dir = tmp_path / "run"
    assert main(["validate", str(path), "-o", str(run_dir)]) == 0
    found = image_provenance(run_dir)
    kinds = {p.relative_to(run_dir).parts[0] for p in found}
    assert kinds == {"renders", "items", "figure_geometric.png", "figure_wave.png", "figure_wave_wave_bench.png",
                     "figure_geometric_synthetic.png", "figure_wave_synthetic.png",
                     "figure_psf.png", "figure_mtf.png", "figure_through_focus.png"}
    for image, provenance in found.items():
        where = image.relative_to(run_dir).parts[0]
        if where == "renders":  # the renderer's record is kept: variant, spp used, its own keys
            assert provenance["variant"] == "fake_variant" and provenance["spp_used"] == 5
            assert provenance["renderer"] == "fake" and provenance["inputs"]["sampler"] == "fake"
            assert provenance["inputs"]["render"]["bench"]["spp"] == 4
        elif where == "items":  # passed through as the renders wrote it
            renders = provenance["inputs"]["render_provenance"]
            assert set(renders) == {"truth_a", "truth_b", "no_lens"}, image
            assert all(r["variant"] == "fake_variant" and r["spp_used"] == 5 for r in renders.values())
            assert provenance["image"] == image.name.split(".")[0]
        else:
            assert provenance["inputs"]["campaign"] == "provenance" and provenance["figure"]
            renders = provenance["inputs"]["renders"]  # the distinct render records behind the figure
            assert {(r["variant"], r["spp_used"]) for r in renders} == {("fake_variant", 5)}
    assert any(p.suffix == ".png" for p in found) and any(p.suffix == ".exr" for p in found)
    assert json_without_provenance(run_dir) == []
    tables = (run_dir / "tables.md").read_text()
    # the page cites only what lies beside it when committed: metrics.csv and the figures' sidecars
    assert "### How this page was built" in tables and "metrics.csv" in tables
    assert "provenance in metrics.json" not in tables and "not copied here" in tables
