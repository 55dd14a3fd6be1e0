"""The pieces of a chart-bench scene dict that the DSLR and the eye bench share: integrator, film, chart.

World frame (millimetres): the viewer at z = 0 looking along +z, +y up, world x the examiner's
right; the chart at z = ``distance_mm``, facing the viewer.

* **Chart**: a self-emitting rectangle whose radiance is the chart's linear reflectance (times
  ``radiance_scale``): emission is deterministic along every path, so the only noise is the
  sensor's sampling (`vissim.bench.dslr.bench`'s module doc says why).
* **Texture**: the print raster, ``nearest`` filtered (the printed raster exactly, piecewise
  constant), cropped around the axis or padded with its edge values to `chart_texture_shape`: the
  magnified field, the blur and a margin, an even number of texels so the centre stays on a texel
  corner.
* **Film**: Mitsuba's float32 ``hdrfilm``, box filter (a pixel integrates its solid angle).
* **Integrator**: ``path`` to `MAX_DEPTH` bounces: refractions through three lenses plus total
  internal reflections.

Nothing here imports Mitsuba.
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np

from vissim.checks import check_allocation, size_text
from vissim.errors import VissimInputError
from vissim.units import REC709_LUMINANCE

__all__ = ["MAX_DEPTH", "TEXTURE_BYTES_PER_TEXEL", "path_integrator", "hdr_film", "checked_chart_pixels",
           "chart_texture_shape", "chart_texture", "chart_emitter"]

log = logging.getLogger(__name__)

#: Path length limits: refractions through three lenses plus total internal reflections.
MAX_DEPTH = 64
#: Peak bytes per texel and channel of the chart texture: float32 raster, its padded copy, Mitsuba's bitmap.
TEXTURE_BYTES_PER_TEXEL = 3 * 4


def path_integrator() -> dict[str, Any]:
    """Mitsuba's ``path`` integrator to `MAX_DEPTH`, the chart (an emitter) visible."""
    return {"type": "path", "max_depth": MAX_DEPTH, "rr_depth": MAX_DEPTH, "hide_emitters": False}


def hdr_film(size_px: tuple[int, int], kind: str) -> dict[str, Any]:
    """Mitsuba's float32 ``hdrfilm`` of ``size_px`` (rows, cols); box filter: a pixel integrates its solid angle."""
    rows, cols = size_px
    return {"type": "hdrfilm", "width": cols, "height": rows, "rfilter": {"type": "box"},
            "pixel_format": "rgb" if kind == "rgb" else "luminance", "component_format": "float32",
            "sample_border": False}


def checked_chart_pixels(chart_pixels) -> np.ndarray:
    """``chart_pixels`` as float32 linear reflectance, (H, W) or (H, W, 3), refused unless finite and >= 0."""
    pixels = np.asarray(chart_pixels, dtype=np.float32)
    if pixels.ndim not in (2, 3) or (pixels.ndim == 3 and pixels.shape[2] not in (1, 3)) or min(pixels.shape[:2]) < 1:
        raise VissimInputError(f"chart pixels must be (H, W) or (H, W, 3), got shape {pixels.shape}")
    if not np.all(np.isfinite(pixels)) or pixels.min() < 0.0:
        raise VissimInputError("chart pixels must be finite, non-negative linear reflectance")
    return pixels


def chart_texture_shape(size_px: tuple[int, int], pitch_mm: float, blur_px: float, magnification: float,
                        mm_per_texel: float) -> tuple[int, int]:
    """(rows, cols) texels the chart texture needs for a ``size_px`` image of ``pitch_mm`` pixels on the chart:
    the field magnified by ``magnification`` (at least 1) and 5 %, a blur of ``blur_px`` pixels and two pixels more,
    each side."""
    blur_mm = blur_px * pitch_mm
    need_mm = [0.5 * n * pitch_mm * max(magnification, 1.0) * 1.05 + blur_mm + 2.0 * pitch_mm for n in size_px]
    rows, cols = (2 * math.ceil(h / mm_per_texel) for h in need_mm)  # even; centre stays on a texel corner
    return rows, cols


def chart_texture(pixels: np.ndarray, need_px: tuple[int, int], mm_per_px: float,
                  what: str) -> tuple[np.ndarray, float, float]:
    """Crop/pad ``pixels`` (centred on the axis) to ``need_px`` texels; (texture, height_mm, width_mm).
    ``what`` names the texture in the memory check's refusal."""
    channels = pixels.shape[2] if pixels.ndim == 3 else 1
    check_allocation(TEXTURE_BYTES_PER_TEXEL * channels * need_px[0] * need_px[1],
                     f"the bench's {size_text(need_px, 'texel')} chart texture ({what})")
    out = pixels
    for axis, need in enumerate(need_px):
        have = out.shape[axis]
        if have > need:
            start = (have - need) // 2
            out = np.take(out, np.arange(start, start + need), axis=axis)
        elif have < need:
            before = (need - have) // 2
            pad = [(0, 0)] * out.ndim
            pad[axis] = (before, need - have - before)
            out = np.pad(out, pad, mode="edge")
    if (pixels.shape[0] - out.shape[0]) % 2 or (pixels.shape[1] - out.shape[1]) % 2:
        log.debug("chart raster of odd size: its centre moved by half a texel (%.3g mm)", 0.5 * mm_per_px)
    return np.ascontiguousarray(out, dtype=np.float32), out.shape[0] * mm_per_px, out.shape[1] * mm_per_px


def chart_emitter(texture: np.ndarray, height_mm: float, width_mm: float, distance_mm: float, *, kind: str = "mono",
                  radiance_scale: float = 1.0) -> dict[str, Any]:
    """The chart as Mitsuba's emitting ``rectangle`` ``distance_mm`` in front of the viewer, facing it: radiance
    ``texture`` (linear reflectance; luminance unless ``kind`` is ``"rgb"``) x ``radiance_scale``."""
    if texture.ndim == 2:
        texture = texture[:, :, None]
    if kind != "rgb" and texture.shape[2] == 3:
        texture = texture @ np.array(REC709_LUMINANCE, dtype=np.float32)[:, None]
    # The rectangle spans [-1, 1]^2 with normal +z; turned 180 deg about y it faces the viewer
    # (-z) and its local +x (texture u) runs along world -x, the viewer's image right.  Mitsuba
    # puts bitmap row 0 at v = 0, local y = -1 (the bottom), so the raster goes in upside down.
    # Pinned by tests/render/test_dslr_render.py::test_letters_are_neither_mirrored_nor_upside_down.
    to_world = [[-0.5 * width_mm, 0.0, 0.0, 0.0], [0.0, 0.5 * height_mm, 0.0, 0.0],
                [0.0, 0.0, -1.0, distance_mm], [0.0, 0.0, 0.0, 1.0]]
    radiance = {"type": "bitmap", "data": texture[::-1] * np.float32(radiance_scale), "raw": True,
                "filter_type": "nearest", "wrap_mode": "clamp"}
    return {"type": "rectangle", "to_world": to_world, "emitter": {"type": "area", "radiance": radiance}}
