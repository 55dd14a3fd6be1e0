"""Depth scenes as Mitsuba scene dicts: the observer's camera, the panels' shapes and emitters.

The scene (`vissim.bench.depth.scene`) says where panels are; this module turns it into a
dict.  Views and contents (`depth_scene_dict`): ``view="blurred"`` uses the observer's
optics, ``"all_in_focus"`` a pinhole (``perspective``) at the pupil centre with the same film and the
same lenses, so both images share one pixel grid.  ``content="proximity"`` replaces every
panel's radiance by its proximity ``1000 / z_mm`` dioptres (``z`` axial), a *depth pass*: a
pinhole render of it gives each pixel's mean proximity (0 for empty sky).  ``"surface_proximity"``
(kind ``"rgb"``) adds each surface's label ``i + 1`` in G, so that a pixel can keep its *nearest*
surface (`DEPTH_PASS_STATISTIC`); that is the RGB-D depth pass, which
`vissim.render.depth_render.render_depth` turns into the axial depth in metres that
`vissim.optics.depth.depth_map.blur_depth` expects.  Axial, because these thin lenses have flat focal
planes: the blur is exactly ``pupil x |K - 1/z|`` at every field angle.

Nothing here imports Mitsuba; dicts hold plain values (``to_world`` as nested lists, bitmap
``data`` as float32 arrays), converted by `vissim.render.run.to_mitsuba_dict`.
"""

from __future__ import annotations

import hashlib
import logging
import math
from pathlib import Path
from typing import Any

import numpy as np

from vissim.atomic import atomic_output, cache_output
from vissim.bench.depth.scene import DepthScene, PanelGeometry, panel_geometries
from vissim.bench.depth.textures import panel_texture
from vissim.bench.depth.viewers import CameraViewer, EyeViewer, Viewer, viewing_setup
from vissim.bench.dslr.bench import NEAR_CLIP_MM, dslr_scene
from vissim.bench.scene_parts import MAX_DEPTH, hdr_film
from vissim.bench.lenses.mesh import mesh_cache_dir
from vissim.errors import VissimInputError
from vissim.units import m_to_mm

__all__ = ["EYE_SENSOR", "VIEWS", "CONTENTS", "DEPTH_PASS_CONTENT", "DEPTH_PASS_STATISTIC", "depth_scene_dict",
           "tilted_mesh"]

log = logging.getLogger(__name__)

#: Plugin name of the eye sensor; equals `vissim.render.eye_sensor.EYE_SENSOR`.
EYE_SENSOR = "vissim_eye"
VIEWS = ("blurred", "all_in_focus")
CONTENTS = ("radiance", "proximity", "coverage", "surface_proximity")
#: The RGB-D depth pass: every panel glows with (proximity, its label, 0), and each pixel keeps the
#: mean proximity of its *nearest* surface over the part of the pixel that surface covers
#: (`vissim.render.run.nearest_surface`), not the mean over the pixel: a pixel half on a
#: 0.4 m panel and half on the 6 m one behind it would get an in-between depth that neither has.
#: A blur-by-depth model blurs the pixel's light with its depth's PSF, and the light there is the
#: near surface's; the far surface lies behind it.  (A layer's own proximity pass keeps the mean.)
DEPTH_PASS_CONTENT, DEPTH_PASS_STATISTIC = "surface_proximity", "nearest_surface"
#: Texels of a tilted chart's proximity ramp (bilinear; error <= slope x 0.5 / texels at the rim).
PROXIMITY_TEXELS = 1024
_MESH_SCHEMA = "vissim.tilted-chart-mesh/1"
_FAR_CLIP_FACTOR = 10.0


def _pinhole(scene: DepthScene, kind: str, far_clip_mm: float) -> dict:
    return {"type": "perspective", "fov": scene.fov_x_deg(), "fov_axis": "x", "near_clip": NEAR_CLIP_MM,
            "far_clip": far_clip_mm, "to_world": np.eye(4).tolist(),
            "sampler": {"type": scene.sampler, "sample_count": 16, "seed": 0}, "film": hdr_film(scene.size_px, kind)}


def _eye_sensor(scene: DepthScene, viewer: EyeViewer, kind: str, far_clip_mm: float) -> dict:
    setup = viewing_setup(viewer)
    k = setup.focus_matrix_diopters
    camera = _pinhole(scene, kind, far_clip_mm)
    camera.update({"type": EYE_SENSOR, "aperture_radius": 0.5 * setup.pupil_diameter_mm,
                   "power_xx_diopters": float(k[0, 0]), "power_xy_diopters": float(k[0, 1]),
                   "power_yy_diopters": float(k[1, 1])})
    del camera["fov_axis"]  # the eye sensor's fov is always horizontal
    return camera


def _fronto_shape(g: PanelGeometry, emitter: dict) -> dict:
    left, right, bottom, top = g.box_tan
    z = m_to_mm(g.distance_left_m)
    cx, cy = 0.5 * (left + right) * z, 0.5 * (bottom + top) * z
    height, width = g.size_mm
    # As the DSLR bench's chart (vissim.bench.dslr.bench.dslr_scene, pinned by its render test): the
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
    z = m_to_mm(g.axial_distance_m(tx))
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
        with cache_output(), atomic_output(path, overwrite=True) as tmp:  # a concurrent writer: the same bytes
            tmp.write_bytes(data)
        log.info("wrote tilted chart mesh %s (%d faces)", path, len(faces))
    return path


def _emitter(scene: DepthScene, g: PanelGeometry, content: str) -> dict:
    if content == "coverage":
        return {"type": "area", "radiance": 1.0}
    if content in ("proximity", "surface_proximity"):
        label = content == "surface_proximity"
        if g.kind == "panel" and label:
            return {"type": "area", "radiance": {"type": "rgb", "value": [1.0 / g.distance_left_m, g.index + 1.0, 0.0]}}
        if g.kind == "panel":
            return {"type": "area", "radiance": 1.0 / g.distance_left_m}
        u = (np.arange(PROXIMITY_TEXELS) + 0.5) / PROXIMITY_TEXELS
        ramp = (1.0 - u) / g.distance_left_m + u / g.distance_right_m  # 1/z is linear in the tangent
        data = ramp.astype(np.float32)[None, :, None]
        if label:
            data = np.stack([ramp, np.full_like(ramp, g.index + 1.0), np.zeros_like(ramp)], axis=-1)
            data = data.astype(np.float32)[None]
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
    panels: tuple[int, ...] | None = None,
) -> dict[str, Any]:
    """The Mitsuba scene dict of ``scene`` seen by ``viewer`` (module doc for views and contents).

    Shape keys are ``panel_<i>`` in the scene's order and ``lens_<i>`` for a camera's trial lenses.
    ``panels`` (indices into ``scene.panels``) keeps only those panels: a *layer* of the scene,
    seen unoccluded by the others.  ``content="coverage"`` makes every kept panel glow with 1, so
    a pinhole render of it is the layer's coverage (alpha) per pixel.
    """
    if view not in VIEWS:
        raise VissimInputError(f"view must be one of {', '.join(VIEWS)}, got {view!r}")
    if content not in CONTENTS:
        raise VissimInputError(f"content must be one of {', '.join(CONTENTS)}, got {content!r}")
    if kind not in ("mono", "rgb"):
        raise VissimInputError(f"render kind must be 'mono' or 'rgb', got {kind!r}")
    if content == "surface_proximity" and kind != "rgb":
        raise VissimInputError("content 'surface_proximity' carries a label in G: render kind 'rgb'")
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
    keep = range(len(scene.panels)) if panels is None else tuple(panels)
    if not set(keep) <= set(range(len(scene.panels))):
        raise VissimInputError(f"panels {tuple(keep)!r} are not indices of the scene's {len(scene.panels)} panels")
    for g in panel_geometries(scene):
        if g.index not in keep:
            continue
        emitter = _emitter(scene, g, content)
        if g.kind == "panel":
            out[f"panel_{g.index}"] = _fronto_shape(g, emitter)
        else:
            columns = max(8, math.ceil(2.0 * (g.box_tan[1] - g.box_tan[0]) / scene.tan_pitch))
            path = _tilted_ply(g, columns, mesh_cache_dir)
            out[f"panel_{g.index}"] = {"type": "ply", "filename": str(path), "face_normals": False, "emitter": emitter}
    return out
