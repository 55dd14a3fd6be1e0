"""ATV scene files (TOML): the tube, the eye and the trial lens (``scenes/atv_tube.toml``).

Tables ``[tube]`` (`AtvTube`'s fields), ``[eye]`` (``pupil_diameter_mm``, ``prescription``,
``accommodation_diopters``) and ``[trial_lens]`` (``sphere_diopters``, ``cylinder_diopters``,
``axis_deg``, ``vertex_distance_mm``, ``fresnel_loss``); every key is optional.  Unknown tables or keys,
and values of the wrong type, raise `VissimInputError` naming the file, the key and the unit.
"""

from __future__ import annotations

import os
from typing import Any

from vissim.bench.atv.tube import AtvConfig, AtvEye, AtvTube, atv_trial_lens
from vissim.bench.scene_toml import check_keys, read_scene_toml, sub_table, typed_value
from vissim.checks import trial_lens_diopters
from vissim.optics.rx.prescription import Prescription
from vissim.optics.rx.trial_lens import EYE_VERTEX_DISTANCE_MM

__all__ = ["load_atv_toml"]

_ATV_TUBE_KEYS = {
    "tube_length_mm": (float, "mm"), "lens_power_diopters": (float, "dioptres"),
    "lens_refractive_index": (float, "(index)"), "lens_center_thickness_mm": (float, "mm"),
    "lens_clear_aperture_mm": (float, "mm"), "lens_convex_side": (str, "('eye' or 'phone')"),
    "eye_relief_mm": (float, "mm"), "pixels_per_inch": (float, "ppi"), "pixel_radiance": (float, "(linear)"),
}


def load_atv_toml(path: str | os.PathLike[str]):
    """The `AtvConfig` of an ATV scene file (``scenes/atv_tube.toml``)."""
    doc, source = read_scene_toml(path)
    check_keys(doc, ("tube", "eye", "trial_lens"), source)
    tables: dict[str, dict] = {}

    def checked(name: str, *keys: str) -> dict:
        tables[name] = sub_table(doc, name, source)
        check_keys(tables[name], keys, f"{source} [{name}]")
        return tables[name]

    def value(name: str, key: str, default: Any, kind: type, unit: str) -> Any:
        return typed_value(tables[name].get(key, default), kind, f"{source} [{name}].{key}", unit)

    tube = AtvTube(**{k: value("tube", k, None, *_ATV_TUBE_KEYS[k]) for k in checked("tube", *_ATV_TUBE_KEYS)})
    rx = checked("eye", "pupil_diameter_mm", "prescription", "accommodation_diopters").get("prescription")
    eye = AtvEye(
        pupil_diameter_mm=value("eye", "pupil_diameter_mm", 4.0, float, "mm"),
        refractive_error=None if rx in (None, "") else Prescription.parse(value("eye", "prescription", None, str, "")),
        accommodation_diopters=value("eye", "accommodation_diopters", 0.0, float, "dioptres"),
    )
    lens = checked("trial_lens", "sphere_diopters", "cylinder_diopters", "axis_deg", "vertex_distance_mm", "fresnel_loss")
    trial = None
    if "sphere_diopters" in lens or "cylinder_diopters" in lens:
        powers = (("sphere_diopters", 0.0, "dioptres"), ("cylinder_diopters", 0.0, "dioptres"),
                  ("axis_deg", 180.0, "degrees"))
        sphere, cylinder, axis = (value("trial_lens", key, default, float, unit) for key, default, unit in powers)
        where = f"{source} [trial_lens]"
        trial = atv_trial_lens(trial_lens_diopters(sphere, f"{where}.sphere_diopters"),
                               trial_lens_diopters(cylinder, f"{where}.cylinder_diopters"), axis)
    return AtvConfig(tube=tube, eye=eye, trial_lens=trial,
                     trial_lens_distance_mm=value("trial_lens", "vertex_distance_mm", EYE_VERTEX_DISTANCE_MM, float, "mm"),
                     fresnel_loss=value("trial_lens", "fresnel_loss", False, bool, "(true/false)"))
