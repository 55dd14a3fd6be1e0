"""The ATV tube as a Mitsuba scene dict: lenses, black tube, the lit pixel, and the eye as a camera.

Scene dicts hold plain values (4 x 4 row-major ``to_world`` lists), converted by
`vissim.render.run.to_mitsuba_dict`; nothing here imports Mitsuba.  The lenses are PLY
meshes (`vissim.bench.lenses.mesh.cached_lens_ply`) with the refraction-only BSDF; the
optional camera is a ``thinlens`` at the pupil, the cross-check of the light tracer.
"""

from __future__ import annotations

import math
from typing import Any

from vissim.bench.atv.tube import AtvConfig
from vissim.bench.lenses.mesh import cached_lens_ply
from vissim.checks import arcmin_per_px as check_arcmin_per_px
from vissim.checks import samples_per_pixel
from vissim.errors import VissimInputError
from vissim.units import arcmin_to_rad, diopters_to_mm

__all__ = ["LENS_BSDF", "MAX_DEPTH", "NEAR_CLIP_MM", "atv_scene"]

#: Plugin name of the refraction-only BSDF; equals `vissim.render.plugins.REFRACT_BSDF`.
LENS_BSDF = "vissim_refract"
NEAR_CLIP_MM = 1.0
#: Path depth of the camera cross-check: two lenses, four refractions, the pixel, some slack.
MAX_DEPTH = 16
_FAR_FOCUS_MM = 1.0e9


def _translate(x: float, y: float, z: float) -> list[list[float]]:
    return [[1.0, 0.0, 0.0, x], [0.0, 1.0, 0.0, y], [0.0, 0.0, 1.0, z], [0.0, 0.0, 0.0, 1.0]]


def _camera(config: AtvConfig, arcmin_per_px: float, size_px: int, spp: int, seed: int, kind: str) -> dict:
    excess = config.eye.viewing_setup().defocus_matrix_diopters
    if abs(excess[0][1]) > 1e-12 or abs(excess[0][0] - excess[1][1]) > 1e-12:
        raise VissimInputError(f"the camera cross-check models a spherical eye only; this eye's error is "
                               f"{config.eye.refractive_error} D (use the light tracer)")
    focus_diopters = float(excess[0][0])
    if focus_diopters < 0.0:
        raise VissimInputError(f"the camera cross-check cannot focus beyond infinity: the eye's excess power plus "
                               f"accommodation is {focus_diopters:g} D < 0 D (use the light tracer)")
    focus_mm = _FAR_FOCUS_MM if focus_diopters == 0.0 else diopters_to_mm(focus_diopters)
    half_tan = math.tan(0.5 * size_px * float(arcmin_to_rad(arcmin_per_px)))
    return {
        "type": "thinlens",
        "fov": 2.0 * math.degrees(math.atan(half_tan)),
        "fov_axis": "x",
        "aperture_radius": 0.5 * config.eye.pupil_diameter_mm,
        "focus_distance": focus_mm,
        "near_clip": NEAR_CLIP_MM,
        "far_clip": 10.0 * config.layout().phone_z_mm,
        # Looking along +z with +y up: Mitsuba's camera frame is +x left, so image right is world -x.
        "to_world": _translate(0.0, 0.0, 0.0),
        "sampler": {"type": "independent", "sample_count": int(spp), "seed": int(seed)},
        "film": {"type": "hdrfilm", "width": int(size_px), "height": int(size_px), "rfilter": {"type": "box"},
                 "pixel_format": "luminance" if kind == "mono" else "rgb", "component_format": "float32",
                 "sample_border": False},
    }


def atv_scene(config: AtvConfig, *, camera: bool = True, arcmin_per_px: float = 1.0, size_px: int = 65,
              spp: int = 64, seed: int = 0, kind: str = "mono", mesh_cache_dir=None) -> dict[str, Any]:
    """The Mitsuba scene dict of ``config``: lenses, black tube, the lit pixel, and the eye as a camera.

    Shape keys (Mitsuba ids) are ``collimator``, ``trial_lens`` (when present), ``tube`` and
    ``pixel``.  With ``camera=False`` the dict has no sensor or integrator (the light tracer's
    geometry).  The camera is a ``thinlens`` of aperture radius pupil / 2 at the pupil, focused
    where the eye is (``1 / (E + A)``, or at 10^9 mm), its ``size_px`` square film covering
    ``size_px * arcmin_per_px`` (odd ``size_px`` puts the axis on the centre pixel).
    """
    if kind not in ("mono", "rgb"):
        raise VissimInputError(f"render kind must be 'mono' or 'rgb', got {kind!r}")
    layout, tube = config.layout(), config.tube
    lenses = [("collimator", tube.collimator_lens(), tube.lens_clear_aperture_mm, layout.collimator_back_vertex_z_mm)]
    if config.trial_lens is not None:
        lenses.append(("trial_lens", config.trial_lens, config.trial_clear_aperture_mm, layout.trial_back_vertex_z_mm))
    half = 0.5 * tube.pixel_pitch_mm
    ox, oy = tube.pixel_offset_mm
    black = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]} if kind == "rgb" else 0.0}
    scene: dict[str, Any] = {
        "type": "scene",
        "tube": {"type": "cylinder", "p0": [0.0, 0.0, 0.0], "p1": [0.0, 0.0, layout.phone_z_mm],
                 "radius": layout.tube_radius_mm, "flip_normals": True, "bsdf": black},
        # The rectangle spans [-1, 1]^2 with normal +z; flipped, it emits toward the eye (-z).
        "pixel": {"type": "rectangle", "flip_normals": True,
                  "to_world": [[half, 0.0, 0.0, ox], [0.0, half, 0.0, oy], [0.0, 0.0, 1.0, layout.phone_z_mm],
                               [0.0, 0.0, 0.0, 1.0]],
                  "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [tube.pixel_radiance] * 3}
                              if kind == "rgb" else tube.pixel_radiance}},
    }
    for key, lens, aperture, z in lenses:
        path = cached_lens_ply(lens, aperture, cache_dir=mesh_cache_dir)
        scene[key] = {"type": "ply", "filename": str(path), "face_normals": False, "to_world": _translate(0.0, 0.0, z),
                      "bsdf": {"type": LENS_BSDF, "int_ior": float(lens.refractive_index),
                               "fresnel_loss": bool(config.fresnel_loss)}}
    if camera:
        if int(size_px) != size_px or size_px < 1:
            raise VissimInputError(f"image size must be a whole number of pixels >= 1, got {size_px!r}")
        step = check_arcmin_per_px(arcmin_per_px)
        spp = samples_per_pixel(spp)
        scene["integrator"] = {"type": "path", "max_depth": MAX_DEPTH, "rr_depth": MAX_DEPTH, "hide_emitters": False}
        scene["eye"] = _camera(config, step, int(size_px), int(spp), int(seed), kind)
    return scene
