"""Depth-scene chart textures: each panel's linear-reflectance raster.

A fronto panel is printed for its own distance (`vissim.charts.render_chart_print`), a
tilted chart anamorphically in visual angle (`vissim.charts.render_chart_angular`); both are
padded with blank paper to the panel's `PanelGeometry` texture
shape.  Rasters are cached per chart spec and resolution.
"""

from __future__ import annotations

import functools

import numpy as np

from vissim.bench.depth.scene import PanelGeometry
from vissim.charts import MM_PER_INCH, ChartSpec, render_chart_angular, render_chart_print
from vissim.errors import VissimInputError

__all__ = ["panel_texture"]


@functools.lru_cache(maxsize=32)
def _chart_raster(spec: ChartSpec, kind: str, resolution: float) -> np.ndarray:
    chart = render_chart_print(spec, resolution) if kind == "panel" else render_chart_angular(spec, resolution)
    chart.pixels.setflags(write=False)
    return chart.pixels


def panel_texture(geometry: PanelGeometry) -> np.ndarray:
    """The panel's linear-reflectance raster (rows top first, columns to the observer's right)."""
    if geometry.kind == "panel":
        raster = _chart_raster(geometry.spec, "panel", MM_PER_INCH / geometry.mm_per_texel)
    else:
        raster = _chart_raster(geometry.spec, "tilted", geometry.texel_arcmin)
    pad = geometry.padding_texels
    out = np.pad(raster, pad, constant_values=geometry.spec.background_reflectance) if pad else raster
    if out.shape != geometry.texture_shape:  # pragma: no cover - layout and rendering share layout_chart
        raise VissimInputError(f"panel texture {out.shape} != its layout {geometry.texture_shape} (texels)")
    return np.ascontiguousarray(out, dtype=np.float32)
