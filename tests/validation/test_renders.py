"""A campaign render's EXR header records the spp asked and taken, the variant, seeds and passes."""

from __future__ import annotations

from vissim.imageio import read_image, write_image
from vissim.validation.renders import RenderSpec, render_spec
from vissim.validation.runner import render_file_provenance


def test_render_header_records_spp_used_and_variant(tmp_path):
    spec = RenderSpec("K", 1.0, "black-on-white", (), 5.0, 18.0, 0.9144, 10.0, 1.0, (12, 16), 128, 1)
    result = render_spec(spec)
    assert result.pixels.shape == (12, 16) and result.pixels.dtype.name == "float32"
    write_image(tmp_path / "render.exr", result.pixels, provenance=render_file_provenance(spec, result))
    header = read_image(tmp_path / "render.exr").provenance
    assert header["inputs"]["render"] == spec.as_json()  # the spec is kept
    record = header["inputs"]["mitsuba_render"]
    assert record["spp_requested"] == 128 and record["spp_used"] == 132 == header["spp_used"]  # multijitter 11 x 12
    assert record["variant"] == header["variant"] == result.variant
    assert record["seed"] == 1 and record["pass_seeds"] == [1] and record["passes"] == 1
    assert record["deterministic"] is (not result.variant.startswith("cuda_"))
