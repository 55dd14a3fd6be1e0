"""Depth scene files (TOML): panels, a tilted chart, the image, sampling and the observer.

Tables: ``[image]`` (``arcmin_per_px``, ``size_px`` = [rows, cols]), ``[sampling]`` (``spp``,
``seed``, ``aux_spp`` for the pinhole renders, ``sampler``, ``texels_per_px``), one observer
-- ``[eye]`` (``prescription``, ``pupil_diameter_mm``, ``accommodation_diopters``) or ``[camera]``
(the DSLR: ``focal_length_mm``, ``f_number``, ``focus_distance_m``, ``vertex_distance_mm``,
``lens_gap_mm``, ``refractive_index``, ``clear_aperture_mm``, ``fresnel_loss`` and
``[[camera.lenses]]`` as in ``scenes/dslr_bench.toml``) -- and the panels: ``[[panel]]``
(``distance_m``, ``center_arcmin`` = [right, up]) and ``[[tilted]]`` (``distance_left_m``,
``distance_right_m``, ``center_arcmin``), each with the chart keys ``letters``, ``logmar``,
``padding_arcmin``, ``polarity``, ``paper_reflectance``, ``ink_reflectance``.  No observer
table means an emmetropic eye with a 4 mm pupil.  ``scenes/depth_panels.toml`` and
``scenes/depth_tilted.toml`` are the commented examples.  Unknown keys and wrong types raise
`VissimInputError` naming the file, the key and the unit.
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass
from typing import Any

from vissim.bench.depth.scene import ChartPanel, DepthScene, PanelChart, TiltedChart
from vissim.bench.depth.viewers import CameraViewer, EyeViewer
from vissim.bench.scene_toml import (check_keys, checked_values, image_size_px, parse_trial_lenses, read_scene_toml,
                                     sub_table, typed_value)
from vissim.checks import samples_per_pixel
from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import Prescription

__all__ = ["DepthSceneFile", "load_depth_scene_toml", "depth_scene_from_doc"]

_IMAGE = {"arcmin_per_px": (float, "arcmin/px"), "size_px": (list, "[rows, cols] px")}
_SAMPLING = {
    "spp": (int, "samples per pixel"),
    "seed": (int, "(integer)"),
    "aux_spp": (int, "samples per pixel of the pinhole renders"),
    "sampler": (str, "(name)"),
    "texels_per_px": (float, "texels per pixel"),
}
_EYE = {"prescription": (str, "(e.g. '-2.00 -0.50 x 180')"), "pupil_diameter_mm": (float, "mm"),
        "accommodation_diopters": (float, "dioptres")}
_CAMERA = {
    "focal_length_mm": (float, "mm"), "f_number": (float, "(f-number)"), "focus_distance_m": (float, "m"),
    "vertex_distance_mm": (float, "mm"), "lens_gap_mm": (float, "mm"), "refractive_index": (float, "(dimensionless)"),
    "clear_aperture_mm": (float, "mm"), "fresnel_loss": (bool, "(true/false)"), "lenses": (list, "(array of tables)"),
}
_CHART = {
    "letters": (str, "(Sloan letters, rows separated by spaces)"), "logmar": (float, "LogMAR"),
    "padding_arcmin": (float, "arcmin"), "polarity": (str, "('black-on-white' or 'white-on-black')"),
    "paper_reflectance": (float, "(fraction 0-1)"), "ink_reflectance": (float, "(fraction 0-1)"),
}
_PANEL = {"distance_m": (float, "m"), "center_arcmin": (list, "[right, up] arcmin"), **_CHART}
_TILTED = {"distance_left_m": (float, "m"), "distance_right_m": (float, "m"),
           "center_arcmin": (list, "[right, up] arcmin"), **_CHART}
_TABLES = ("image", "sampling", "eye", "camera", "panel", "tilted")


@dataclass(frozen=True)
class DepthSceneFile:
    """A loaded depth scene file: the scene, the observer and the sampling it asks for."""

    scene: DepthScene
    viewer: EyeViewer | CameraViewer
    spp: int = 64
    seed: int = 0
    aux_spp: int = 64
    source: str = ""


def _center(values: dict, where: str) -> tuple[float, float]:
    center = values.pop("center_arcmin", [0.0, 0.0])
    if len(center) != 2:
        raise VissimInputError(f"{where} center_arcmin must be [right, up] in arcmin, got {center!r}")
    return tuple(typed_value(v, float, f"{where} center_arcmin", "arcmin") for v in center)


def _panels(doc: dict, source: str) -> tuple:
    panels = []
    for table_name, schema in (("panel", _PANEL), ("tilted", _TILTED)):
        entries = doc.get(table_name, [])
        if not isinstance(entries, list):
            raise VissimInputError(f"{source}: [[{table_name}]] must be an array of tables, got {entries!r}")
        for i, entry in enumerate(entries):
            where = f"{source} [[{table_name}]] #{i + 1}"
            values = checked_values(entry, schema, where)
            center = _center(values, where)
            chart = PanelChart(**{k: values.pop(k) for k in list(values) if k in _CHART})
            if table_name == "panel":
                if "distance_m" not in values:
                    raise VissimInputError(f"{where} needs distance_m (metres)")
                panels.append(ChartPanel(values["distance_m"], center, chart))
            else:
                panels.append(TiltedChart(values.get("distance_left_m", 0.5), values.get("distance_right_m", 3.0),
                                          center, chart))
    if not panels:
        raise VissimInputError(f"{source}: no panels; add [[panel]] and/or [[tilted]] tables")
    return tuple(panels)


def _viewer(doc: dict, source: str) -> EyeViewer | CameraViewer:
    if "eye" in doc and "camera" in doc:
        raise VissimInputError(f"{source}: give one observer, [eye] or [camera], not both")
    if "camera" in doc:
        where = f"{source} [camera]"
        values = checked_values(doc["camera"], _CAMERA, where)
        lenses = parse_trial_lenses(values.pop("lenses", []), f"{source} [[camera.lenses]]")
        return CameraViewer(lenses=lenses, **values)
    values = checked_values(doc.get("eye", {}), _EYE, f"{source} [eye]")
    rx = Prescription.parse(values.pop("prescription", "plano"))
    return EyeViewer(rx, **values)


def depth_scene_from_doc(doc: dict, source: str) -> DepthSceneFile:
    """The `DepthSceneFile` of a parsed TOML document (module doc)."""
    check_keys(doc, _TABLES, source)
    image = checked_values(sub_table(doc, "image", source), _IMAGE, f"{source} [image]")
    sampling = checked_values(sub_table(doc, "sampling", source), _SAMPLING, f"{source} [sampling]")
    fields: dict[str, Any] = {}
    if "size_px" in image:
        fields["size_px"] = image_size_px(image["size_px"], source)
    if "arcmin_per_px" in image:
        fields["arcmin_per_px"] = image["arcmin_per_px"]
    for key in ("sampler", "texels_per_px"):
        if key in sampling:
            fields[key] = sampling[key]
    scene = DepthScene(_panels(doc, source), **fields)
    counts = {key: sampling.get(key, default) for key, default in (("spp", 64), ("seed", 0), ("aux_spp", 64))}
    for key in ("spp", "aux_spp"):
        counts[key] = samples_per_pixel(counts[key], f"{source} [sampling] {key}")
    return DepthSceneFile(scene, _viewer(doc, source), counts["spp"], counts["seed"], counts["aux_spp"], source)


def load_depth_scene_toml(path: str | os.PathLike[str], **overrides: Any) -> DepthSceneFile:
    """Load a depth scene file; ``overrides`` (not None) replace `DepthSceneFile` fields."""
    doc, source = read_scene_toml(path)
    loaded = depth_scene_from_doc(doc, source)
    return dataclasses.replace(loaded, **{k: v for k, v in overrides.items() if v is not None})
