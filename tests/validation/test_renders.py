"""A campaign render's EXR header records the spp asked and taken, the variant, seeds and passes."""

from __future__ import annotations

import numpy as np
import pytest

from vissim.bench.dslr.bench import dslr_scene
from vissim.imageio import read_image, write_image
from vissim.validation.dslr.schema import CampaignSettings, Configuration
from vissim.validation.engine.fields import LensSpec
from vissim.bench.dslr.bench import DslrBench
from vissim.validation.dslr.renders import RenderSpec, build_dslr, render_dslr_spec, truth_specs
from vissim.validation.dslr.simulate import simulation_setup
from vissim.validation.engine.renders import render_file_provenance


def test_render_header_records_spp_used_and_variant(tmp_path):
    spec = RenderSpec(DslrBench(size_px=(12, 16), spp=128, seed=1), "K", 1.0, "black-on-white")
    result = render_dslr_spec(spec)
    assert result.pixels.shape == (12, 16) and result.pixels.dtype.name == "float32"
    write_image(tmp_path / "render.exr", result.pixels, provenance=render_file_provenance(spec, result))
    header = read_image(tmp_path / "render.exr").provenance
    assert header["inputs"]["render"] == spec.as_json()  # the spec is kept
    record = header["inputs"]["mitsuba_render"]
    assert record["spp_requested"] == 128 and record["spp_used"] == 132 == header["spp_used"]  # multijitter 11 x 12
    assert record["variant"] == header["variant"] == result.variant
    assert record["seed"] == 1 and record["pass_seeds"] == [1] and record["passes"] == 1
    assert record["deterministic"] is (not result.variant.startswith("cuda_"))


@pytest.mark.parametrize("lenses", [(), (LensSpec(2.0),), (LensSpec(-3.0),), (LensSpec(0.0, -2.0, 90.0),),
                                    (LensSpec(1.0, -0.5, 30.0), LensSpec(-2.0))],
                         ids=["no lens", "+2 DS", "-3 DS", "-2 DC x 90", "+1 -0.5 x 30 and -2 DS"])
@pytest.mark.parametrize("kind", ["wave", "geometric"])
def test_the_simulation_assumes_the_setup_the_bench_renders(tmp_path, lenses, kind):
    """A configuration is built once: the bench its renders use is the one its simulations assume."""
    settings = CampaignSettings()
    configuration = Configuration("c", "K", 1.0, lenses=lenses)
    built = build_dslr(configuration, settings)
    rendered = truth_specs(built, settings)[0].bench  # the DslrBench the render is made with
    simulated = simulation_setup(kind, built.setup, built.lenses, configuration, settings)
    assert simulated.setup == built.setup == rendered.viewing_setup(settings.wavelength_nm)
    scene = dslr_scene(rendered, np.ones((8, 8), np.float32), 1.0, mesh_cache_dir=tmp_path)
    assert scene["camera"]["aperture_radius"] == 0.5 * simulated.setup.pupil_diameter_mm
