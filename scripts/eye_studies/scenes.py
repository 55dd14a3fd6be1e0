"""Scenes for the eye studies: `vissim.render.eye_render`'s scene with its chart or lens changed, and the
chart as the schematic-eye sensor's pixels see it before any blur.

* **Charts** are functions of the chart plane (world x, y in mm, z = the chart's distance; world +x is
  the observer's left, +y up: Mitsuba's camera frame), rasterised onto the scene's emitting rectangle
  (`chart_emitter`: Mitsuba's ``bitmap``, nearest texel, row 0 at the rectangle's v = 0, its bottom; the
  rectangle's local +x runs along world −x, as `vissim.bench.scene_parts.chart_emitter` lays the benches' chart).
* **A pixel's direction** (`pixel_directions`): the sensor's map (`vissim.render.schematic_eye_sensor`):
  the pixel at film position (u, v) is at the field angle ``(field_x − (u − ½) W a, field_y + (½ − v) H a)``
  degrees (OSA's frame: x the observer's left, y up), whose direction in the eye's frame is
  (tan x, tan y, 1) turned by the model's visual axis (`vissim.optics.eyes.traced_wavefront.field_direction`,
  vectorised here and pinned to it by a test), then into the world by
  `vissim.bench.eye.scene.eye_to_world`.  Seen from the corneal vertex: the entrance pupil's
  few mm of parallax are below 1e-5 deg for the far charts the studies use (1 km).
* **The ideal image** (`ideal_image`): the chart's texels looked up, as Mitsuba looks them up, along
  ``oversample``² directions per pixel (a box filter, the film's), averaged.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from vissim.errors import VissimInputError

__all__ = ["ChartRaster", "chart_emitter", "with_chart", "pixel_directions",
           "ideal_image", "render_settings"]

#: A chart: (world x mm, world y mm) arrays -> reflectance (0-1).
ChartFunction = Callable[[np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True, eq=False)
class ChartRaster:
    """A chart rasterised on a ``width_mm`` x ``height_mm`` rectangle centred on the world z axis at
    ``distance_mm``, turned ``roll_deg`` about that axis; ``data`` in Mitsuba's bitmap order (module doc)."""

    data: np.ndarray
    width_mm: float
    height_mm: float
    distance_mm: float
    roll_deg: float = 0.0

    @classmethod
    def from_function(cls, chart: ChartFunction, width_mm: float, height_mm: float, distance_mm: float,
                      texel_mm: float) -> "ChartRaster":
        cols, rows = (max(1, int(math.ceil(s / texel_mm))) for s in (width_mm, height_mm))
        u = (np.arange(cols) + 0.5) / cols
        v = (np.arange(rows) + 0.5) / rows
        x_mm = (0.5 - u) * width_mm
        y_mm = (v - 0.5) * height_mm
        data = chart(x_mm[None, :], y_mm[:, None]).astype(np.float32)
        return cls(np.broadcast_to(data, (rows, cols)).copy(), float(width_mm), float(height_mm), float(distance_mm))

    def to_world(self) -> list[list[float]]:
        c, s = math.cos(math.radians(self.roll_deg)), math.sin(math.radians(self.roll_deg))
        scale = np.diag([-0.5 * self.width_mm, 0.5 * self.height_mm, -1.0])
        rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        out = np.eye(4)
        out[:3, :3] = rotation @ scale
        out[2, 3] = self.distance_mm
        return out.tolist()

    def lookup(self, x_mm: np.ndarray, y_mm: np.ndarray) -> np.ndarray:
        """The texel values at world points of the chart plane (nearest texel, clamped, as the scene's bitmap)."""
        c, s = math.cos(math.radians(self.roll_deg)), math.sin(math.radians(self.roll_deg))
        lx = (c * x_mm + s * y_mm) / (-0.5 * self.width_mm)  # undo the roll, then the scale
        ly = (-s * x_mm + c * y_mm) / (0.5 * self.height_mm)
        rows, cols = self.data.shape
        j = np.clip(np.floor(0.5 * (lx + 1.0) * cols), 0, cols - 1).astype(int)
        k = np.clip(np.floor(0.5 * (ly + 1.0) * rows), 0, rows - 1).astype(int)
        return self.data[k, j]


def chart_emitter(raster: ChartRaster, white_radiance: float) -> dict:
    """The scene's chart entry: the rectangle emitting ``raster`` x ``white_radiance``."""
    return {"type": "rectangle", "to_world": raster.to_world(),
            "emitter": {"type": "area",
                        "radiance": {"type": "bitmap", "data": raster.data[:, :, None] * np.float32(white_radiance),
                                     "raw": True, "filter_type": "nearest", "wrap_mode": "clamp"}}}


def with_chart(scene: dict, raster: ChartRaster) -> dict:
    """``scene`` (an `eye_scene_dict`) with its chart replaced by ``raster``, at the same white radiance."""
    white = float(np.max(scene["chart"]["emitter"]["radiance"]["data"]))
    if not white > 0.0:
        raise VissimInputError("the scene's chart has no white to take the radiance scale from")
    return {**scene, "chart": chart_emitter(raster, white)}


def pixel_directions(eye, size_px: tuple[int, int], arcmin_per_px: float, field_deg, oversample: int = 1) -> np.ndarray:
    """World unit directions (rows·k, cols·k, 3) of the ``oversample``² sub-pixel centres of a render of the
    `SchematicEye` ``eye`` (module doc)."""
    from vissim.optics.eyes.field_blur import node_field_deg
    from vissim.optics.eyes.traced_wavefront import field_direction
    from vissim.bench.eye.scene import eye_to_world

    rows, cols = size_px
    k = int(oversample)
    r, q = np.indices((rows * k, cols * k))
    local = field_direction(eye, node_field_deg(r, q, (rows * k, cols * k), arcmin_per_px / k, field_deg))
    rotation = np.asarray(eye_to_world(eye, field_deg))[:3, :3]
    return local @ rotation.T


def ideal_image(raster: ChartRaster, eye, size_px: tuple[int, int], arcmin_per_px: float, field_deg,
                oversample: int = 4) -> np.ndarray:
    """The chart's reflectance per pixel, unblurred, on the sensor's grid (module doc): float64 (H, W)."""
    d = pixel_directions(eye, size_px, arcmin_per_px, field_deg, oversample)
    t = raster.distance_mm / d[..., 2]
    values = raster.lookup(t * d[..., 0], t * d[..., 1])
    rows, cols = size_px
    return values.reshape(rows, oversample, cols, oversample).mean(axis=(1, 3))


def render_settings(settings, scene: dict):
    """Render an edited `eye_scene_dict` of ``settings`` (an `EyeRender`) as `render_eye` renders it; the
    `vissim.render.run.RenderResult`."""
    from vissim.render.backend import choose_variant, mitsuba
    from vissim.render.run import render_scene
    from vissim.render.schematic_eye_sensor import register_schematic_eye_sensor

    chosen = choose_variant("spectral" if settings.spectrum == "photopic" else "mono", None).variant
    register_schematic_eye_sensor(mitsuba("mono", chosen))
    return render_scene(scene, kind="mono", spp=settings.spp, seed=settings.seed, variant=chosen)

