"""Depth scenes: letter charts at several distances and a tilted chart, as Mitsuba scene dicts.

World frame (millimetres), the one of :mod:`vissim.bench.dslr`: the observer's pupil (the
DSLR's entrance pupil, or the eye's) at z = 0 looking along +z with +y up; world x is the
examiner's right (TABO), so the observer's image right is world -x.  Directions in the view
are *image tangents* ``(right, up)``: a pixel's centre looks along ``(-tx, ty, 1)``, and
pixels are uniform in tangent with pitch ``tan(arcmin_per_px)`` (as in the DSLR bench).

What is in a scene:

* **Chart panels** (:class:`ChartPanel`): a letter chart printed for *its own* distance (letters
  ``letter_height_mm(logmar, distance)`` tall, :func:`vissim.acuity.letter_height_mm`),
  ETDRS-spaced, with an optional blank paper border, on a self-emitting rectangle facing the
  observer (as the DSLR bench's chart: radiance = linear reflectance, no lamp noise).  Panels
  may overlap in the view; the nearer one occludes the farther, by geometry.
* **Tilted charts** (:class:`TiltedChart`): a plane rotated about the vertical axis whose axial
  distance runs from ``distance_left_m`` at its left edge to ``distance_right_m`` at its right
  edge (continuous depth).  Its print is *anamorphic*: letters keep their LogMAR size in visual
  angle at every depth, so the observer sees an ordinary chart whose depth varies.  On a plane,
  ``1/z`` is linear in the image tangent, so the board is the trapezoid whose image is the
  chart's angular rectangle; it is a PLY mesh whose texture coordinates are image tangents,
  with columns at most half a pixel apart (texture error < 0.01 px).

Observers (a ``viewer``, :mod:`vissim.bench.depth_viewers`, re-exported here): an
:class:`EyeViewer` -- Mitsuba sensor ``vissim_eye`` (:mod:`vissim.render.eye_sensor`), an ideal
thin lens at the pupil focusing the vergence matrix ``K = A I - Rx``, so an object at axial
distance ``z`` is blurred by ``pupil x (K - I/z)``: the defocus ``Rx + 1/z - A`` of
:func:`vissim.optics.depth.effective_prescription`, cylinders and hyperopia (focus "beyond infinity",
``K < 0``) included, which a Mitsuba ``thinlens`` (focus distance > 0, no astigmatism) cannot
express -- or a :class:`CameraViewer`, the DSLR bench camera (``thinlens``, f/N entrance pupil)
with optional trial lenses, taken from :func:`vissim.bench.dslr.dslr_scene` itself.

Views and contents (:func:`depth_scene_dict`): ``view="blurred"`` uses the observer's optics,
``"all_in_focus"`` a pinhole (``perspective``) at the pupil centre with the same film and the
same lenses, so both images share one pixel grid.  ``content="proximity"`` replaces every
panel's radiance by its proximity ``1000 / z_mm`` dioptres (``z`` axial), a *depth pass*: a
pinhole render of it gives each pixel's mean proximity (0 for empty sky), which
:func:`vissim.render.depth_render.render_depth` turns into the axial depth in metres that
:func:`vissim.optics.depth.blur_depth` expects.  Axial, because these thin lenses have flat focal
planes: the blur is exactly ``pupil x |K - 1/z|`` at every field angle.

Nothing here imports Mitsuba; dicts hold plain values (``to_world`` as nested lists, bitmap
``data`` as float32 arrays), converted by :func:`vissim.render.run.to_mitsuba_dict`.
"""

from __future__ import annotations

import functools
import hashlib
import logging
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Union

import numpy as np

from vissim.atomic import atomic_output
from vissim.bench.depth_viewers import (
    CameraViewer,
    EyeViewer,
    Viewer,
    blur_diameter_arcmin,
    equivalent_eye,
    focus_matrix_diopters,
)
from vissim.bench.dslr import MAX_DEPTH, NEAR_CLIP_MM, SAMPLERS, dslr_scene
from vissim.bench.lens_mesh import mesh_cache_dir
from vissim.charts import (
    INK_REFLECTANCE,
    MM_PER_INCH,
    PAPER_REFLECTANCE,
    POLARITIES,
    ChartRow,
    ChartSpec,
    layout_chart,
    render_chart_angular,
    render_chart_print,
)
from vissim.checks import finite_number, positive_number
from vissim.errors import VissimInputError
from vissim.units import arcmin_to_rad, rad_to_arcmin

__all__ = [
    "EYE_SENSOR", "VIEWS", "CONTENTS", "DEFAULT_DISTANCES_M", "PanelChart", "ChartPanel", "TiltedChart",
    "DepthScene", "EyeViewer", "CameraViewer", "PanelGeometry", "panel_geometries", "panel_texture",
    "pixel_tangents", "axial_depth_map", "focus_matrix_diopters", "equivalent_eye", "blur_diameter_arcmin",
    "depth_scene_dict", "tilted_mesh", "default_panels_scene", "default_tilted_scene",
]

log = logging.getLogger(__name__)

#: Plugin name of the eye sensor; equals :data:`vissim.render.eye_sensor.EYE_SENSOR`.
EYE_SENSOR = "vissim_eye"
VIEWS = ("blurred", "all_in_focus")
CONTENTS = ("radiance", "proximity")
#: The issue's chart distances: near work, the thesis's 3 ft, across the room, far.
DEFAULT_DISTANCES_M = (0.4, 0.9144, 2.0, 6.0)
#: Texels of a tilted chart's proximity ramp (bilinear; error <= slope x 0.5 / texels at the rim).
PROXIMITY_TEXELS = 1024
_MESH_SCHEMA = "vissim.tilted-chart-mesh/1"
_FAR_CLIP_FACTOR = 10.0


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
        padding = finite_number(self.padding_arcmin, "panel padding", "arcmin")
        if padding < 0.0:
            raise VissimInputError(f"panel padding must be >= 0 arcmin, got {padding:g} arcmin")
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
        for name, unit in (("arcmin_per_px", "arcmin/px"), ("texels_per_px", "texels per pixel"),
                           ("radiance_scale", "(relative)")):
            object.__setattr__(self, name, positive_number(getattr(self, name), name.replace("_", " "), unit))
        try:
            size = tuple(int(v) for v in self.size_px)
        except (TypeError, ValueError):
            size = ()
        if len(size) != 2 or min(size) < 1 or tuple(self.size_px) != size:
            raise VissimInputError(f"size_px must be (rows, cols) in whole pixels >= 1, got {self.size_px!r}")
        object.__setattr__(self, "size_px", size)
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
    def proximity_range_d(self) -> tuple[float, float]:
        values = (1.0 / self.distance_left_m, 1.0 / self.distance_right_m)
        return min(values), max(values)

    def axial_distance_m(self, tx) -> np.ndarray:
        """Axial distance of the panel's plane along image tangent ``tx``: 1/z is linear in ``tx``."""
        left, right = self.box_tan[:2]
        if self.distance_left_m == self.distance_right_m:
            return np.full(np.shape(tx), self.distance_left_m)
        t = (np.asarray(tx, dtype=float) - left) / (right - left)
        return 1.0 / ((1.0 - t) / self.distance_left_m + t / self.distance_right_m)


def _texel_tan(scene: DepthScene) -> float:
    return scene.tan_pitch / scene.texels_per_px


def _padding_texels(padding_arcmin: float, texel_tan: float) -> int:
    return int(round(math.tan(arcmin_to_rad(padding_arcmin)) / texel_tan)) if padding_arcmin > 0 else 0


def _geometry(scene: DepthScene, index: int, panel: Panel) -> PanelGeometry:
    texel_tan = _texel_tan(scene)
    texel_arcmin = float(rad_to_arcmin(math.atan(texel_tan)))
    chart = panel.chart
    pad = _padding_texels(chart.padding_arcmin, texel_tan)
    cx, cy = (math.tan(arcmin_to_rad(v)) for v in panel.center_arcmin)
    if isinstance(panel, ChartPanel):
        distance = panel.distance_m
        spec = chart.spec(distance)
        mm_per_texel = 1000.0 * distance * texel_tan
        layout = layout_chart(spec, dpi=MM_PER_INCH / mm_per_texel)
        shape = (layout.shape_px[0] + 2 * pad, layout.shape_px[1] + 2 * pad)
        half_w, half_h = 0.5 * shape[1] * texel_tan, 0.5 * shape[0] * texel_tan
        top, left, bottom, _ = layout.letters[0].box_mm
        return PanelGeometry(
            index, f"panel {distance:g} m", "panel", (cx - half_w, cx + half_w, cy - half_h, cy + half_h),
            distance, distance, shape, pad, spec, texel_arcmin, mm_per_texel,
            (shape[0] * mm_per_texel, shape[1] * mm_per_texel), bottom - top,
        )
    spec = chart.spec(min(panel.distance_left_m, panel.distance_right_m))
    layout = layout_chart(spec, arcmin_per_px=texel_arcmin)
    shape = (layout.shape_px[0] + 2 * pad, layout.shape_px[1] + 2 * pad)
    half_w, half_h = 0.5 * shape[1] * texel_tan, 0.5 * shape[0] * texel_tan
    name = f"tilted {panel.distance_left_m:g}-{panel.distance_right_m:g} m"
    return PanelGeometry(index, name, "tilted", (cx - half_w, cx + half_w, cy - half_h, cy + half_h),
                         panel.distance_left_m, panel.distance_right_m, shape, pad, spec, texel_arcmin)


def panel_geometries(scene: DepthScene) -> tuple[PanelGeometry, ...]:
    """Every panel's :class:`PanelGeometry`, in the scene's order."""
    return tuple(_geometry(scene, i, p) for i, p in enumerate(scene.panels))


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


# -- scene dicts ------------------------------------------------------------------------
def _film(scene: DepthScene, kind: str) -> dict:
    rows, cols = scene.size_px
    return {"type": "hdrfilm", "width": cols, "height": rows, "rfilter": {"type": "box"},
            "pixel_format": "luminance" if kind == "mono" else "rgb", "component_format": "float32",
            "sample_border": False}


def _identity() -> list[list[float]]:
    return [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]


def _pinhole(scene: DepthScene, kind: str, far_clip_mm: float) -> dict:
    return {"type": "perspective", "fov": scene.fov_x_deg(), "fov_axis": "x", "near_clip": NEAR_CLIP_MM,
            "far_clip": far_clip_mm, "to_world": _identity(),
            "sampler": {"type": scene.sampler, "sample_count": 16, "seed": 0}, "film": _film(scene, kind)}


def _eye_sensor(scene: DepthScene, viewer: EyeViewer, kind: str, far_clip_mm: float) -> dict:
    k = focus_matrix_diopters(viewer)
    camera = _pinhole(scene, kind, far_clip_mm)
    camera.update({"type": EYE_SENSOR, "aperture_radius": 0.5 * viewer.pupil_diameter_mm,
                   "power_xx_diopters": float(k[0, 0]), "power_xy_diopters": float(k[0, 1]),
                   "power_yy_diopters": float(k[1, 1])})
    del camera["fov_axis"]  # the eye sensor's fov is always horizontal
    return camera


def _fronto_shape(g: PanelGeometry, emitter: dict) -> dict:
    left, right, bottom, top = g.box_tan
    z = 1000.0 * g.distance_left_m
    cx, cy = 0.5 * (left + right) * z, 0.5 * (bottom + top) * z
    height, width = g.size_mm
    # As the DSLR bench's chart (vissim.bench.dslr.dslr_scene, pinned by its render test): the
    # rectangle turned 180 deg about y faces the observer, texture u runs along world -x (image
    # right) and bitmap row 0 sits at the bottom, so the raster goes in upside down.
    return {"type": "rectangle",
            "to_world": [[-0.5 * width, 0.0, 0.0, -cx], [0.0, 0.5 * height, 0.0, cy], [0.0, 0.0, -1.0, z],
                         [0.0, 0.0, 0.0, 1.0]],
            "emitter": emitter}


def tilted_mesh(g: PanelGeometry, columns: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(vertices mm, normals, uv, faces) of a tilted chart: ``columns`` strips, uv = image tangents.

    Vertex (j, top/bottom) lies on the plane at image tangent ``(tx_j, top/bottom)``; u runs
    0 -> 1 to the observer's right, v 0 at the top (bitmap row 0), faces wound toward the observer.
    """
    left, right, bottom, top = g.box_tan
    tx = np.linspace(left, right, columns + 1)
    z = 1000.0 * g.axial_distance_m(tx)
    vertices = np.empty((2 * (columns + 1), 3))
    vertices[0::2] = np.stack([-tx * z, top * z, z], axis=1)
    vertices[1::2] = np.stack([-tx * z, bottom * z, z], axis=1)
    u = np.linspace(0.0, 1.0, columns + 1)
    uv = np.stack([np.repeat(u, 2), np.tile([0.0, 1.0], columns + 1)], axis=1)
    # Plane a z - b x = 1 (mm): a, b from two points; its normal toward the observer is (b, 0, -a).
    (x0, z0), (x1, z1) = (vertices[0, 0], vertices[0, 2]), (vertices[-1, 0], vertices[-1, 2])
    a, b = np.linalg.solve([[z0, -x0], [z1, -x1]], [1.0, 1.0])
    normal = np.array([b, 0.0, -a]) / math.hypot(a, b)
    normals = np.broadcast_to(normal, vertices.shape).copy()
    j = np.arange(columns)
    faces = np.concatenate([np.stack([2 * j, 2 * j + 1, 2 * j + 2], axis=1),
                            np.stack([2 * j + 2, 2 * j + 1, 2 * j + 3], axis=1)])
    v = vertices[faces]
    if np.dot(np.cross(v[0, 1] - v[0, 0], v[0, 2] - v[0, 0]), normal) < 0:
        faces = faces[:, ::-1]
    return vertices, normals, uv, faces.astype(np.int32)


def _tilted_ply(g: PanelGeometry, columns: int, cache_dir) -> Path:
    vertices, normals, uv, faces = tilted_mesh(g, columns)
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"comment {_MESH_SCHEMA}: tilted chart, millimetres, uv = image tangents\n"
        f"element vertex {len(vertices)}\n"
        + "".join(f"property float {n}\n" for n in ("x", "y", "z", "nx", "ny", "nz", "u", "v"))
        + f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    ).encode("ascii")
    face = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    face["n"], face["i"] = 3, faces
    data = header + np.concatenate([vertices, normals, uv], axis=1).astype("<f4").tobytes() + face.tobytes()
    directory = Path(cache_dir) if cache_dir is not None else mesh_cache_dir()
    path = directory / f"tilted-{hashlib.sha256(data).hexdigest()[:24]}.ply"
    if not path.is_file():
        with atomic_output(path, overwrite=True) as tmp:  # a concurrent writer writes the same bytes
            tmp.write_bytes(data)
        log.info("wrote tilted chart mesh %s (%d faces)", path, len(faces))
    return path


def _emitter(scene: DepthScene, g: PanelGeometry, content: str) -> dict:
    if content == "proximity":
        if g.kind == "panel":
            return {"type": "area", "radiance": 1.0 / g.distance_left_m}
        u = (np.arange(PROXIMITY_TEXELS) + 0.5) / PROXIMITY_TEXELS
        ramp = (1.0 - u) / g.distance_left_m + u / g.distance_right_m  # 1/z is linear in the tangent
        data = ramp.astype(np.float32)[None, :, None]
        return {"type": "area", "radiance": {"type": "bitmap", "data": data, "raw": True,
                                             "filter_type": "bilinear", "wrap_mode": "clamp"}}
    texture = panel_texture(g)[:, :, None] * np.float32(scene.radiance_scale)
    if g.kind == "panel":
        texture = texture[::-1]
    return {"type": "area", "radiance": {"type": "bitmap", "data": np.ascontiguousarray(texture), "raw": True,
                                         "filter_type": "nearest", "wrap_mode": "clamp"}}


def depth_scene_dict(
    scene: DepthScene,
    viewer: Viewer,
    *,
    view: str = "blurred",
    content: str = "radiance",
    kind: str = "mono",
    mesh_cache_dir=None,
) -> dict[str, Any]:
    """The Mitsuba scene dict of ``scene`` seen by ``viewer`` (module doc for views and contents).

    Shape keys are ``panel_<i>`` in the scene's order and ``lens_<i>`` for a camera's trial lenses.
    """
    if view not in VIEWS:
        raise VissimInputError(f"view must be one of {', '.join(VIEWS)}, got {view!r}")
    if content not in CONTENTS:
        raise VissimInputError(f"content must be one of {', '.join(CONTENTS)}, got {content!r}")
    if kind not in ("mono", "rgb"):
        raise VissimInputError(f"render kind must be 'mono' or 'rgb', got {kind!r}")
    if not isinstance(viewer, (EyeViewer, CameraViewer)):
        raise VissimInputError(f"viewer must be an EyeViewer or a CameraViewer, got {type(viewer).__name__}")
    far_clip = _FAR_CLIP_FACTOR * 1000.0 * scene.far_distance_m()
    out: dict[str, Any] = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": MAX_DEPTH, "rr_depth": MAX_DEPTH, "hide_emitters": False},
    }
    if isinstance(viewer, EyeViewer):
        blurred = view == "blurred"
        out["camera"] = _eye_sensor(scene, viewer, kind, far_clip) if blurred else _pinhole(scene, kind, far_clip)
    else:
        bench = viewer.bench(scene)
        # The bench's own camera and lens meshes; its chart (a token raster) is dropped.
        bench_dict = dslr_scene(bench, np.full((2, 2), 0.5, np.float32), 1.0e6, kind=kind,
                                mesh_cache_dir=mesh_cache_dir)
        camera = bench_dict["camera"] if view == "blurred" else _pinhole(scene, kind, far_clip)
        camera["far_clip"] = far_clip
        out["camera"] = camera
        out.update({key: value for key, value in bench_dict.items() if key.startswith("lens_")})
    for g in panel_geometries(scene):
        emitter = _emitter(scene, g, content)
        if g.kind == "panel":
            out[f"panel_{g.index}"] = _fronto_shape(g, emitter)
        else:
            columns = max(8, math.ceil(2.0 * (g.box_tan[1] - g.box_tan[0]) / scene.tan_pitch))
            path = _tilted_ply(g, columns, mesh_cache_dir)
            out[f"panel_{g.index}"] = {"type": "ply", "filename": str(path), "face_normals": False, "emitter": emitter}
    return out


# -- the two scenes -------------------------------------------------------------
def default_panels_scene(distances_m=DEFAULT_DISTANCES_M, *, logmar: float = 0.5, letters: str | None = None,
                         padding_arcmin: float = 8.0, step_arcmin=(40.0, 20.0), size_px=(128, 192)) -> DepthScene:
    """Charts at ``distances_m``, far to near from upper right to lower left, each overlapping the next.

    Each panel shows one Sloan letter (``letters``: one per panel, default H V Z D S ...) at
    ``logmar``; neighbouring centres are ``step_arcmin`` (right, up) apart.
    """
    placed = sorted(distances_m, reverse=True)
    letters = letters or "HVZDSNCKOR"[: len(placed)]
    if len(letters) != len(placed):
        raise VissimInputError(f"give one letter per panel: {len(placed)} distances, letters {letters!r}")
    panels = []
    for i, (distance, letter) in enumerate(zip(placed, letters)):
        step = 0.5 * (len(placed) - 1) - i
        center = (step * step_arcmin[0], step * step_arcmin[1])
        panels.append(ChartPanel(distance, center, PanelChart(letter, logmar, padding_arcmin=padding_arcmin)))
    return DepthScene(tuple(panels), size_px=tuple(size_px))


def default_tilted_scene(distance_left_m: float = 0.5, distance_right_m: float = 3.0, *,
                         size_px=(96, 192)) -> DepthScene:
    """A tilted chart spanning ``distance_left_m`` to ``distance_right_m`` across the image."""
    chart = PanelChart("HVZDS NCKOR", 0.5, padding_arcmin=8.0)
    return DepthScene((TiltedChart(distance_left_m, distance_right_m, (0.0, 0.0), chart),), size_px=tuple(size_px))
