"""Render depth scenes: the blurred image, and on request the all-in-focus image and a depth map.

Three renders of one scene (`vissim.bench.depth.scene_dict.depth_scene_dict`), one pixel grid:

* **blurred** -- the observer's optics (eye sensor or DSLR thin lens + trial lenses), seed ``seed``;
* **all in focus** -- a pinhole at the pupil centre, same film, same lenses, seed ``seed + 1``;
* **depth** -- the pinhole looking at the *proximity pass* (each panel glows with ``1/z``
  dioptres, z axial, and carries its label), seed ``seed + 2``.  A pixel's value is the mean
  proximity of its *nearest* surface over the part of the pixel it covers (0 where every sample
  sees sky; `vissim.bench.depth.scene_dict.DEPTH_PASS_STATISTIC`), and the depth map is
  ``1 / proximity`` metres, ``inf`` for sky: the axial distance
  `vissim.optics.depth.depth_map.blur_depth` expects for these flat-focal-plane optics.  A pixel
  split between a near panel and the far one behind it takes the near panel's depth, not the
  sample mean (an in-between depth no surface has, which left the near panel's edges too
  sharp in tutorial 4).  Through trial lenses the depth
  pass sees what the pinhole sees (magnified), unlike Mitsuba's ``aov`` integrator, whose
  ``position``/``depth`` stop at the first surface (the lens).  `render_aov_depth`
  gives that AOV's axial depth as an independent check on scenes without lenses (its
  ``depth`` type is measured from the near-clip plane along the ray, so ``position.z`` is
  used instead);
* **layers** (on request) -- each panel alone (the scene's other panels removed), through the
  same pinhole: its radiance and its coverage (the panel glowing with 1), seeds ``seed + 3 +
  2 i`` and ``seed + 4 + 2 i``.  What the pupil sees *behind* a nearer panel's edge is there,
  for `vissim.optics.depth.layered.composite_layers`.

The frame: the pinhole renders (all in focus, depth, layers) cover ``margin_px`` more pixels on
every side than the blurred render (`vissim.bench.depth.scene.DepthScene.with_margin`; the
blurred render's pixel ``[i, j]`` is their ``[i + m, j + m]``), so a simulation from them sees what
the observer sees beyond the frame; `vissim.bench.depth.viewers.frame_margin_px` is the
margin that holds the scene's largest blur.

Only this package imports Mitsuba (through `vissim.render.backend.mitsuba`).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from vissim.bench.depth.scene_dict import DEPTH_PASS_CONTENT, DEPTH_PASS_STATISTIC
from vissim.errors import VissimInputError
from vissim.provenance import json_safe, make_provenance
from vissim.render.backend import mitsuba
from vissim.render.eye_sensor import register_eye_sensor
from vissim.render.fixed_order import render_image
from vissim.render.plugins import register_plugins
from vissim.render.run import mitsuba_versions, render_scene, to_mitsuba_dict
from vissim.units import mm_to_m

__all__ = ["DepthRenderResult", "render_depth", "render_view", "render_aov_depth", "proximity_to_depth_m",
           "SKY_PROXIMITY_D"]

log = logging.getLogger(__name__)

#: Mean proximities below this (dioptres, i.e. beyond 1000 km) are sky: depth inf.
SKY_PROXIMITY_D = 1e-6


@dataclass(frozen=True, eq=False)
class DepthRenderResult:
    """float32 images on one grid (None when not asked for); ``depth_m`` axial metres of each pixel's
    nearest surface (``proximity_diopters``: its proximity), inf = sky."""

    blurred: np.ndarray | None
    all_in_focus: np.ndarray | None
    depth_m: np.ndarray | None
    proximity_diopters: np.ndarray | None
    variant: str
    spp: int
    seed: int
    seconds: float
    provenance: dict | None = None
    margin_px: int = 0  # the pinhole renders' extra pixels on every side
    layer_radiance: tuple[np.ndarray, ...] | None = None  # per panel, in the scene's order
    layer_coverage: tuple[np.ndarray, ...] | None = None


def proximity_to_depth_m(proximity_diopters) -> np.ndarray:
    """Axial depth (m, float32) from a proximity pass (D): ``1/p``, inf where ``p < SKY_PROXIMITY_D``."""
    proximity = np.asarray(proximity_diopters, dtype=np.float64)
    if not np.all(np.isfinite(proximity)) or proximity.min(initial=0.0) < -1e-6:
        raise VissimInputError("a proximity pass must be finite and >= 0 dioptres")
    with np.errstate(divide="ignore"):
        depth = np.where(proximity < SKY_PROXIMITY_D, np.inf, 1.0 / np.maximum(proximity, SKY_PROXIMITY_D))
    return depth.astype(np.float32)


def render_view(scene, viewer, *, view: str, content: str = "radiance", spp: int, seed: int = 0,
                kind: str = "mono", variant: str | None = None, pass_spp: int | None = None,
                progress: Callable[[int, int], None] | None = None, mesh_cache_dir=None,
                panels: tuple[int, ...] | None = None, statistic: str = "mean"):
    """One render (`vissim.render.run.RenderResult`) of ``depth_scene_dict(scene, viewer, ...)``;
    ``statistic``: how a pixel comes from its samples (`vissim.render.run.PIXEL_STATISTICS`)."""
    from vissim.bench.depth.scene_dict import depth_scene_dict

    kind = {"proximity": "mono", "coverage": "mono", DEPTH_PASS_CONTENT: "rgb"}.get(content, kind)
    register_eye_sensor(mitsuba(kind, variant))
    scene_dict = depth_scene_dict(scene, viewer, view=view, content=content, kind=kind, mesh_cache_dir=mesh_cache_dir,
                                  panels=panels)
    return render_scene(scene_dict, kind=kind, spp=spp, seed=seed, variant=variant, pass_spp=pass_spp,
                        progress=progress, statistic=statistic)


def render_depth(
    scene,
    viewer,
    *,
    spp: int,
    seed: int = 0,
    blurred: bool = True,
    all_in_focus: bool = False,
    depth: bool = False,
    layers: bool = False,
    margin_px: int = 0,
    aux_spp: int | None = None,
    kind: str = "mono",
    variant: str | None = None,
    pass_spp: int | None = None,
    progress: Callable[[str, int, int], None] | None = None,
    mesh_cache_dir=None,
) -> DepthRenderResult:
    """Render ``scene`` seen by ``viewer``: blurred, and on request all-in-focus, depth and layers (module doc).

    ``aux_spp`` is the sample count of the pinhole renders (default ``spp``); their noise is
    only the pixel-area sampling of edges.  They cover ``margin_px`` more pixels on every side
    than the blurred render.  ``progress(name, done_spp, total_spp)`` reports each render.  The
    provenance records the scene, the viewer, seeds, spp, the margin and versions.
    """
    from vissim.bench.depth.scene import panel_geometries
    from vissim.bench.depth.viewers import viewing_setup

    start = time.perf_counter()
    aux = int(spp if aux_spp is None else aux_spp)
    wide = scene.with_margin(margin_px)
    jobs = [("blurred", scene, "blurred", "radiance", seed, spp, None, "mean")] if blurred else []
    if all_in_focus:
        jobs.append(("all_in_focus", wide, "all_in_focus", "radiance", seed + 1, aux, None, "mean"))
    if depth:
        jobs.append(("proximity", wide, "all_in_focus", DEPTH_PASS_CONTENT, seed + 2, aux, None, DEPTH_PASS_STATISTIC))
    if layers:
        for i in range(len(scene.panels)):
            jobs.append((f"layer_{i}", wide, "all_in_focus", "radiance", seed + 3 + 2 * i, aux, (i,), "mean"))
            jobs.append((f"coverage_{i}", wide, "all_in_focus", "coverage", seed + 4 + 2 * i, aux, (i,), "mean"))
    if not jobs:
        raise VissimInputError("nothing to render: ask for the blurred image, the all-in-focus image, the depth "
                               "or the layers")
    images: dict[str, np.ndarray] = {}
    results = {}
    for name, grid, view, content, job_seed, job_spp, panels, statistic in jobs:
        report = None if progress is None else (lambda done, total, name=name: progress(name, done, total))
        result = render_view(grid, viewer, view=view, content=content, spp=job_spp, seed=job_seed, kind=kind,
                             variant=variant, pass_spp=pass_spp, progress=report, mesh_cache_dir=mesh_cache_dir,
                             panels=panels, statistic=statistic)
        images[name], results[name] = result.pixels, result
    proximity = images.get("proximity")
    depth_m = None if proximity is None else proximity_to_depth_m(proximity)
    first = results[jobs[0][0]]
    setup = viewing_setup(viewer, scene)
    provenance = make_provenance(
        scene=scene,
        viewer=viewer,
        viewer_label=viewer.label(),
        focus_matrix_diopters=setup.focus_matrix_diopters,
        panels=[{"name": g.name, "box_arcmin": g.box_arcmin, "distance_left_m": g.distance_left_m,
                 "distance_right_m": g.distance_right_m, "size_mm": g.size_mm, "letter_height_mm": g.letter_height_mm,
                 "blur_diameter_arcmin": [float(setup.blur_diameter_at_arcmin(d))
                                          for d in (g.distance_left_m, g.distance_right_m)]}
                for g in panel_geometries(scene)],
        arcmin_per_px=scene.arcmin_per_px,
        margin_px=int(margin_px),
        margin_definition="the all-in-focus, depth and layer renders cover margin_px more pixels on every side "
                          "than the blurred render; crop them by margin_px to its frame",
        renders={name: {"spp": r.spp, **r.render_record()} for name, r in results.items()},
        depth_definition="axial distance (m) along the view axis, from the pupil plane, of the nearest surface in "
                         "the pixel: 1 / its mean proximity over the samples on it (renders.proximity."
                         "pixel_statistic = nearest_surface), not over the whole pixel; inf = sky",
        kind=kind,
        variant=first.variant,
        **mitsuba_versions(),
    )
    n = len(scene.panels)
    radiance = tuple(images[f"layer_{i}"] for i in range(n)) if layers else None
    coverage = tuple(images[f"coverage_{i}"] for i in range(n)) if layers else None
    return DepthRenderResult(images.get("blurred"), images.get("all_in_focus"), depth_m, proximity,
                             first.variant, first.spp, int(seed), time.perf_counter() - start, json_safe(provenance),
                             int(margin_px), radiance, coverage)


def render_aov_depth(scene, viewer, *, spp: int = 16, seed: int = 0, variant: str | None = None,
                     mesh_cache_dir=None) -> np.ndarray:
    """Axial depth (m) from Mitsuba's ``aov`` integrator (``position`` z) through the pinhole; inf = sky.

    Mean surface z over each pixel's samples, sky counted as z = 0 (so mixed sky pixels are
    meaningless).  Refused with trial lenses: the AOV stops at the first surface, the lens.
    """
    from vissim.bench.depth.scene_dict import depth_scene_dict

    scene_dict = depth_scene_dict(scene, viewer, view="all_in_focus", content="proximity",
                                  mesh_cache_dir=mesh_cache_dir)
    if any(key.startswith("lens_") for key in scene_dict):
        raise VissimInputError("the aov depth stops at the first surface (a lens); with trial lenses use "
                               "render_depth(depth=True)")
    mi = mitsuba("mono", variant)
    register_plugins(mi)
    register_eye_sensor(mi)
    scene_dict["integrator"] = {"type": "aov", "aovs": "pos:position"}
    loaded = mi.load_dict(to_mitsuba_dict(scene_dict, mi))
    image = render_image(mi, loaded, int(spp), int(seed)).image.astype(np.float64)
    z_mm = image[:, :, 2]
    return np.where(z_mm > 0.0, mm_to_m(z_mm), np.inf).astype(np.float32)
