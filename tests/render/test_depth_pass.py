"""The RGB-D depth pass holds each pixel's nearest surface, not the mean over the pixel.

Scene: a 0.5 m panel in front of a 2 m panel that fills the frame.  The near panel's right edge
runs down the middle of a pixel column (the pixel half on each panel) and its top edge across a
pixel row, a quarter of it on the near panel.  Proximity 1/z is 2 D on the near panel and 0.5 D on the far one, both
exact in float32, so the nearest-surface depth of a straddling pixel is exactly 0.5 m; the mean
proximity would give 1 / (0.5 x 2 + 0.5 x 0.5) = 0.8 m.  A box filter keeps each sample in its
own pixel, so the next column, wholly on the far panel, stays exactly 2 m.  Tolerance 1e-6
relative: float32 round-off of 1 / proximity.
"""

from __future__ import annotations

import numpy as np
import pytest

from vissim.bench.depth.scene import ChartPanel, DepthScene, PanelChart, panel_geometries
from vissim.bench.depth.viewers import EyeViewer
from vissim.render.backend import choose_variant
from vissim.render.depth_render import render_depth, render_view

NEAR_M, FAR_M = 0.5, 2.0
SEED = 5


@pytest.fixture(autouse=True)
def _mesh_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("VISSIM_CACHE_DIR", str(tmp_path / "cache"))


def near_over_far(size_px=(64, 64)) -> DepthScene:
    return DepthScene((ChartPanel(FAR_M, (0.0, 0.0), PanelChart("H", 1.0)),
                       ChartPanel(NEAR_M, (-20.25, -0.5), PanelChart("Z", 0.5))), size_px=size_px)


def edge_pixels(scene: DepthScene):
    """The near panel's right edge: its straddling column, the near fraction of it and the next column;
    the rows wholly inside the panel's height; its top edge: the straddling row and the near fraction."""
    far, near = panel_geometries(scene)
    rows, cols = scene.size_px
    right = near.box_tan[1] / scene.tan_pitch + 0.5 * cols  # in pixel-edge coordinates
    top, bottom = (0.5 * rows - t / scene.tan_pitch for t in (near.box_tan[3], near.box_tan[2]))
    assert far.box_tan[1] / scene.tan_pitch > 0.5 * cols and far.box_tan[3] / scene.tan_pitch > 0.5 * rows
    column = int(np.floor(right))
    clear = np.arange(max(int(np.ceil(top)), 0), min(int(np.floor(bottom)), rows))
    return column, right - column, column + 1, clear, int(np.floor(top)), np.ceil(top) - top


@pytest.mark.skipif(choose_variant("mono").variant.startswith("scalar"), reason="no JIT Mitsuba variant")
def test_depth_pass_gives_a_straddling_pixel_the_nearest_surface():
    scene = near_over_far()
    column, fraction, beyond, clear, top_row, top_fraction = edge_pixels(scene)
    assert fraction == pytest.approx(0.5, abs=1e-3) and top_fraction == pytest.approx(0.25, abs=1e-3)
    result = render_depth(scene, EyeViewer(), spp=16, seed=SEED, blurred=False, depth=True)
    depth = result.depth_m
    np.testing.assert_allclose(depth[clear, column], NEAR_M, rtol=1e-6)  # half on each panel: the near one
    np.testing.assert_allclose(depth[clear, beyond], FAR_M, rtol=1e-6)  # wholly far: untouched by the edge
    np.testing.assert_allclose(depth[top_row, :column], NEAR_M, rtol=1e-6)  # a quarter near: still near
    np.testing.assert_allclose(depth[:top_row, :], FAR_M, rtol=1e-6)
    record = result.provenance["inputs"]["renders"]["proximity"]
    assert record["pixel_statistic"] == "nearest_surface"
    assert "nearest surface" in result.provenance["inputs"]["depth_definition"]
    # The same samples averaged: the straddling pixels' mean proximity, 2 x 0.5 + 0.5 x 0.5 = 1.25 D (0.8 m),
    # to the 4 x 4 multijitter's placement of the edge (a quarter column: +-0.19 D).
    mean = render_view(scene, EyeViewer(), view="all_in_focus", content="proximity", spp=16, seed=SEED + 2).pixels
    assert np.abs(mean[clear, column].mean() - 1.25) < 0.05
    assert np.all(1.0 / mean[clear, column] > 1.2 * NEAR_M)


def test_scalar_variant_takes_the_samples_from_one_sample_renders():
    """scalar_rgb (the fallback without LLVM) reduces ``spp`` one-sample renders the same way."""
    scene = near_over_far((12, 16))  # the near panel's right edge, half a pixel in, down every row
    column, _, beyond, clear, _, _ = edge_pixels(scene)
    assert len(clear) == 12
    # 24 independent one-sample renders: all on the far half with probability 2^-24 per pixel
    nearest = render_view(scene, EyeViewer(), view="all_in_focus", content="surface_proximity", spp=24, seed=SEED,
                          variant="scalar_rgb", statistic="nearest_surface")
    assert nearest.statistic == "nearest_surface" and nearest.spp == 24
    np.testing.assert_allclose(nearest.pixels[:, column], 1.0 / NEAR_M, rtol=1e-6)
    np.testing.assert_allclose(nearest.pixels[:, beyond], 1.0 / FAR_M, rtol=1e-6)
