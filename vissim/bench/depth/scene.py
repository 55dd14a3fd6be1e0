"""Depth scenes: letter charts at several distances and a tilted chart, as Mitsuba scene dicts.

World frame (millimetres), the one of `vissim.bench.dslr.bench`: the observer's pupil (the
DSLR's entrance pupil, or the eye's) at z = 0 looking along +z with +y up; world x is the
examiner's right (TABO), so the observer's image right is world -x.  Directions in the view
are *image tangents* ``(right, up)``: a pixel's centre looks along ``(-tx, ty, 1)``, and
pixels are uniform in tangent with pitch ``tan(arcmin_per_px)`` (as in the DSLR bench).

What is in a scene:

* **Chart panels** (`ChartPanel`): a letter chart printed for *its own* distance (letters
  ``letter_height_mm(logmar, distance)`` tall, `vissim.acuity.letter_height_mm`),
  ETDRS-spaced, with an optional blank paper border, on a self-emitting rectangle facing the
  observer (as the DSLR bench's chart: radiance = linear reflectance, no lamp noise).  Panels
  may overlap in the view; the nearer one occludes the farther, by geometry.
* **Tilted charts** (`TiltedChart`): a plane rotated about the vertical axis whose axial
  distance runs from ``distance_left_m`` at its left edge to ``distance_right_m`` at its right
  edge (continuous depth).  Its print is *anamorphic*: letters keep their LogMAR size in visual
  angle at every depth, so the observer sees an ordinary chart whose depth varies.  On a plane,
  ``1/z`` is linear in the image tangent, so the board is the trapezoid whose image is the
  chart's angular rectangle; it is a PLY mesh whose texture coordinates are image tangents,
  with columns at most half a pixel apart (texture error < 0.01 px).

Observers (a ``viewer``, `vissim.bench.depth.viewers`): an ``EyeViewer`` -- Mitsuba
sensor ``vissim_eye`` (`vissim.render.eye_sensor`), an ideal thin lens at the pupil
focusing the vergence matrix ``K = A I - Rx``, so an object at axial distance ``z`` is blurred
by ``pupil x (K - I/z)``: the defocus ``Rx + 1/z - A`` of
`vissim.optics.rx.viewing_setup.ViewingSetup.eye`, cylinders and hyperopia (focus "beyond infinity",
``K < 0``) included, which a Mitsuba ``thinlens`` (focus distance > 0, no astigmatism) cannot
express -- or a ``CameraViewer``, the DSLR bench camera (``thinlens``, f/N entrance pupil)
with optional trial lenses, taken from `vissim.bench.dslr.bench.dslr_scene` itself.

The scene dicts are `vissim.bench.depth.scene_dict`, the chart textures
`vissim.bench.depth.textures`.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Union

import numpy as np

from vissim.bench.dslr.bench import SAMPLERS
from vissim.charts import (INK_REFLECTANCE, MM_PER_INCH, PAPER_REFLECTANCE, POLARITIES, ChartRow, ChartSpec,
                           layout_chart)
from vissim.checks import PANEL_PADDING_RANGE_ARCMIN, TEXELS_PER_PX_RANGE, finite_number, number_within, positive_number
from vissim.checks import size_px as check_size_px
from vissim.errors import VissimInputError
from vissim.units import arcmin_to_rad, m_to_mm, rad_to_arcmin

__all__ = ["PanelChart", "ChartPanel", "TiltedChart", "DepthScene", "PanelGeometry",
           "panel_geometries", "pixel_tangents", "axial_depth_map"]


def _point(value, name: str) -> tuple[float, float]:
    try:
        right, up = (finite_number(v, name, "arcmin") for v in value)
    except (TypeError, ValueError):
        raise VissimInputError(f"{name} must be [right, up] in arcmin, got {value!r}") from None
    return right + 0.0, up + 0.0


# -- what the scene holds ---------------------------------------------------------------
@dataclass(frozen=True)
class PanelChart:
    """What a panel shows: rows of Sloan letters (separated by spaces) at one LogMAR, ETDRS-spaced.

    ``padding_arcmin`` adds blank paper (the background reflectance) around the printed chart.
    """

    letters: str = "R"
    logmar: float = 0.7
    polarity: str = "black-on-white"
    paper_reflectance: float = PAPER_REFLECTANCE
    ink_reflectance: float = INK_REFLECTANCE
    padding_arcmin: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "logmar", finite_number(self.logmar, "chart LogMAR", "LogMAR"))
        padding = number_within(self.padding_arcmin, "panel padding", "arcmin", PANEL_PADDING_RANGE_ARCMIN,
                                " (paper around the chart, within the half of the view a panel can fill)")
        object.__setattr__(self, "padding_arcmin", padding)
        if self.polarity not in POLARITIES:
            raise VissimInputError(f"polarity must be one of {', '.join(POLARITIES)}, got {self.polarity!r}")
        self.spec(1.0)  # validates letters and reflectances

    def spec(self, viewing_distance_m: float) -> ChartSpec:
        rows = tuple(ChartRow(self.logmar, row) for row in str(self.letters).split())
        if not rows:
            raise VissimInputError(f"a panel needs at least one Sloan letter, got letters={self.letters!r}")
        return ChartSpec(rows, viewing_distance_m=viewing_distance_m, polarity=self.polarity,
                         paper_reflectance=self.paper_reflectance, ink_reflectance=self.ink_reflectance)

    @property
    def background_reflectance(self) -> float:
        return self.paper_reflectance if self.polarity == "black-on-white" else self.ink_reflectance


@dataclass(frozen=True)
class ChartPanel:
    """A chart facing the observer at axial ``distance_m``; its centre at ``center_arcmin`` (right, up)."""

    distance_m: float
    center_arcmin: tuple[float, float] = (0.0, 0.0)
    chart: PanelChart = field(default_factory=PanelChart)

    def __post_init__(self) -> None:
        object.__setattr__(self, "distance_m", positive_number(self.distance_m, "panel distance", "m"))
        object.__setattr__(self, "center_arcmin", _point(self.center_arcmin, "panel centre"))
        if not isinstance(self.chart, PanelChart):
            raise VissimInputError(f"a panel's chart must be a PanelChart, got {type(self.chart).__name__}")


@dataclass(frozen=True)
class TiltedChart:
    """A chart on a plane turned about the vertical axis: axial distance from left edge to right edge."""

    distance_left_m: float = 0.5
    distance_right_m: float = 3.0
    center_arcmin: tuple[float, float] = (0.0, 0.0)
    chart: PanelChart = field(default_factory=lambda: PanelChart("HVZDS", 0.5))

    def __post_init__(self) -> None:
        for name in ("distance_left_m", "distance_right_m"):
            object.__setattr__(self, name, positive_number(getattr(self, name), name.replace("_", " "), "m"))
        object.__setattr__(self, "center_arcmin", _point(self.center_arcmin, "tilted chart centre"))
        if not isinstance(self.chart, PanelChart):
            raise VissimInputError(f"a tilted chart's chart must be a PanelChart, got {type(self.chart).__name__}")


Panel = Union[ChartPanel, TiltedChart]


@dataclass(frozen=True)
class DepthScene:
    """Panels, the image grid (``size_px`` = (rows, cols)) and the chart texel density."""

    panels: tuple[Panel, ...]
    arcmin_per_px: float = 1.0
    size_px: tuple[int, int] = (128, 192)
    texels_per_px: float = 4.0
    radiance_scale: float = 1.0
    sampler: str = "multijitter"

    def __post_init__(self) -> None:
        panels = (self.panels,) if isinstance(self.panels, (ChartPanel, TiltedChart)) else tuple(self.panels)
        if not panels or not all(isinstance(p, (ChartPanel, TiltedChart)) for p in panels):
            raise VissimInputError(f"a depth scene needs ChartPanel/TiltedChart panels, got {self.panels!r}")
        object.__setattr__(self, "panels", panels)
        for name, unit in (("arcmin_per_px", "arcmin/px"), ("radiance_scale", "(relative)")):
            object.__setattr__(self, name, positive_number(getattr(self, name), name.replace("_", " "), unit))
        object.__setattr__(self, "texels_per_px", number_within(self.texels_per_px, "texels per px",
                                                                "texels per pixel", TEXELS_PER_PX_RANGE))
        object.__setattr__(self, "size_px", check_size_px(self.size_px))
        if self.sampler not in SAMPLERS:
            raise VissimInputError(f"sampler must be one of {', '.join(SAMPLERS)}, got {self.sampler!r}")

    @property
    def tan_pitch(self) -> float:
        """Pixel pitch in image tangent (pixels are uniform in tan(angle))."""
        return math.tan(arcmin_to_rad(self.arcmin_per_px))

    def fov_x_deg(self) -> float:
        return math.degrees(2.0 * math.atan(0.5 * self.size_px[1] * self.tan_pitch))

    def far_distance_m(self) -> float:
        return max(max(getattr(p, n, 0.0) for n in ("distance_m", "distance_left_m", "distance_right_m"))
                   for p in self.panels)

    def distances_m(self) -> tuple[float, ...]:
        """Every panel's axial distances (a tilted chart's two ends): where blur is largest."""
        return tuple(getattr(p, n) for p in self.panels for n in ("distance_m", "distance_left_m", "distance_right_m")
                     if hasattr(p, n))

    def with_margin(self, margin_px: int) -> DepthScene:
        """The same view on a grid ``margin_px`` larger on every side (same pixel centres, inner frame unchanged).

        Pixel centres sit at ``(i + 0.5 - n/2)`` pitches from the axis, so adding ``2 m`` rows and
        columns moves every original pixel to ``[i + m, j + m]`` exactly.
        """
        m = int(margin_px)
        if m != margin_px or m < 0:
            raise VissimInputError(f"a frame margin must be a whole number of pixels >= 0, got {margin_px!r} px")
        if m == 0:
            return self
        rows, cols = self.size_px
        return dataclasses.replace(self, size_px=(rows + 2 * m, cols + 2 * m))


# -- geometry ---------------------------------------------------------------------------
@dataclass(frozen=True)
class PanelGeometry:
    """Where a panel is: its image rectangle in tangents and its axial distance across it.

    ``box_tan`` = (left, right, bottom, top) image tangents (right and up positive).  Fronto
    panels have ``size_mm`` (height, width) and ``mm_per_texel``; both kinds have a texture of
    ``texture_shape`` (rows, cols), row 0 at the top, columns to the observer's right.
    """

    index: int
    name: str
    kind: str  # "panel" or "tilted"
    box_tan: tuple[float, float, float, float]
    distance_left_m: float
    distance_right_m: float
    texture_shape: tuple[int, int]
    padding_texels: int
    spec: ChartSpec
    texel_arcmin: float
    mm_per_texel: float | None = None
    size_mm: tuple[float, float] | None = None
    letter_height_mm: float | None = None

    @property
    def box_arcmin(self) -> tuple[float, float, float, float]:
        return tuple(float(rad_to_arcmin(math.atan(v))) for v in self.box_tan)

    @property
    def proximity_range_diopters(self) -> tuple[float, float]:
        values = (1.0 / self.distance_left_m, 1.0 / self.distance_right_m)
        return min(values), max(values)

    def axial_distance_m(self, tx) -> np.ndarray:
        """Axial distance of the panel's plane along image tangent ``tx``: 1/z is linear in ``tx``."""
        left, right = self.box_tan[:2]
        if self.distance_left_m == self.distance_right_m:
            return np.full(np.shape(tx), self.distance_left_m)
        t = (np.asarray(tx, dtype=float) - left) / (right - left)
        return 1.0 / ((1.0 - t) / self.distance_left_m + t / self.distance_right_m)


def _geometry(scene: DepthScene, index: int, panel: Panel) -> PanelGeometry:
    texel_tan = scene.tan_pitch / scene.texels_per_px
    texel_arcmin = float(rad_to_arcmin(math.atan(texel_tan)))
    padding = panel.chart.padding_arcmin
    pad = int(round(math.tan(arcmin_to_rad(padding)) / texel_tan)) if padding > 0 else 0
    cx, cy = (math.tan(arcmin_to_rad(v)) for v in panel.center_arcmin)
    fronto = isinstance(panel, ChartPanel)
    left_m, right_m = (panel.distance_m,) * 2 if fronto else (panel.distance_left_m, panel.distance_right_m)
    spec = panel.chart.spec(min(left_m, right_m))
    mm_per_texel = m_to_mm(left_m) * texel_tan
    sampling = {"dpi": MM_PER_INCH / mm_per_texel} if fronto else {"arcmin_per_px": texel_arcmin}
    layout = layout_chart(spec, **sampling)
    shape = (layout.shape_px[0] + 2 * pad, layout.shape_px[1] + 2 * pad)
    half_w, half_h = 0.5 * shape[1] * texel_tan, 0.5 * shape[0] * texel_tan
    box = (cx - half_w, cx + half_w, cy - half_h, cy + half_h)
    if not fronto:
        name = f"tilted {left_m:g}-{right_m:g} m"
        return PanelGeometry(index, name, "tilted", box, left_m, right_m, shape, pad, spec, texel_arcmin)
    top, _, bottom, _ = layout.letters[0].box_mm
    return PanelGeometry(index, f"panel {left_m:g} m", "panel", box, left_m, right_m, shape, pad, spec, texel_arcmin,
                         mm_per_texel, (shape[0] * mm_per_texel, shape[1] * mm_per_texel), bottom - top)


def panel_geometries(scene: DepthScene) -> tuple[PanelGeometry, ...]:
    """Every panel's `PanelGeometry`, in the scene's order."""
    return tuple(_geometry(scene, i, p) for i, p in enumerate(scene.panels))


def pixel_tangents(scene: DepthScene) -> tuple[np.ndarray, np.ndarray]:
    """(tx per column, ty per row) of the pixel centres: right and up image tangents."""
    rows, cols = scene.size_px
    pitch = scene.tan_pitch
    return (np.arange(cols) + 0.5 - 0.5 * cols) * pitch, (0.5 * rows - np.arange(rows) - 0.5) * pitch


def axial_depth_map(scene: DepthScene) -> tuple[np.ndarray, np.ndarray]:
    """Exact (axial depth m, panel index) at the pixel centres by ray casting; inf and -1 for sky.

    No lenses: this is the geometry the pinhole sees, the reference for the rendered depth pass.
    """
    tx, ty = pixel_tangents(scene)
    depth = np.full(scene.size_px, np.inf)
    label = np.full(scene.size_px, -1, dtype=np.int32)
    for g in panel_geometries(scene):
        left, right, bottom, top = g.box_tan
        inside = ((ty > bottom) & (ty <= top))[:, None] & ((tx >= left) & (tx < right))[None, :]
        z = np.broadcast_to(g.axial_distance_m(tx)[None, :], depth.shape)
        nearer = inside & (z < depth)
        depth[nearer] = z[nearer]
        label[nearer] = g.index
    return depth, label
