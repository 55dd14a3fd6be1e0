"""A depth campaign's part of the campaign file: its settings and configurations.

A depth campaign's ``[campaign]`` table has ``kind = "depth"`` and its settings; each
``[[config]]`` table is a scene file (``scene``, relative to the campaign file) and an observer:
an eye (``prescription``, ``pupil_diameter_mm``, ``accommodation_diopters``), the DSLR (``camera =
{f_number, focus_distance_m, focal_length_mm, lenses}``), or none (the scene file's).
``validation/depth.toml`` is the commented example; `vissim.validation.depth.kind` is the bench kind.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from vissim.bench.depth.scene import DepthScene
from vissim.bench.depth.scene_files import load_depth_scene_toml
from vissim.bench.depth.viewers import CameraViewer, EyeViewer
from vissim.checks import (ACCOMMODATION_RANGE_DIOPTERS, DEFAULT_LAYER_SPACING_FRACTION, DATA_RANGE_RANGE, DEFAULT_WAVELENGTH_NM, EYE_PUPIL_RANGE_MM,
                           F_NUMBER_RANGE, FOCAL_LENGTH_RANGE_MM, LAYER_SPACING_FRACTION_RANGE, MARGIN_RANGE_PX,
                           MAX_CAMPAIGN_SEED, OBJECT_DISTANCE_RANGE_M, OVERSAMPLE_RANGE, VERTEX_DISTANCE_RANGE_MM,
                           WAVELENGTH_RANGE_NM)
from vissim.errors import VissimInputError
from vissim.optics.rx.prescription import Prescription
from vissim.optics.rx.trial_lens import TrialLens
from vissim.provenance import json_safe
from vissim.validation.engine.configurations import refuse_duplicate_names
from vissim.validation.engine.fields import (MAX_SPP, checked_numbers, field_error, lenses, name_text, number,
                                             refuse_unknown_keys, settings_kwargs, tables, text)

__all__ = ["DepthConfiguration", "DepthCampaignSettings", "read_depth_part", "DEPTH_SIMULATIONS", "DEPTH_INPUTS"]

DEPTH_SIMULATIONS = ("geometric", "wave")
#: What a simulation starts from: the scene's layers rendered alone (radiance and coverage,
#: `vissim.optics.depth.layered.composite_layers`) or one all-in-focus image and its depth
#: map (`vissim.optics.depth.depth_map.blur_depth`).
DEPTH_INPUTS = ("layered", "rgbd")


@dataclass(frozen=True)
class DepthConfiguration:
    """One comparison: a scene (loaded from ``scene_file``) seen by one observer."""

    name: str
    scene_file: str
    scene: DepthScene
    viewer: EyeViewer | CameraViewer

    def as_json(self) -> dict:
        return {"name": self.name, "scene_file": self.scene_file, "viewer": json_safe(self.viewer),
                "viewer_label": self.viewer.label()}

    def key_inputs(self) -> dict:
        """What the item's results depend on: the scene's content and the observer (not the file's name)."""
        return {"scene": self.scene, "viewer": self.viewer}

    def frame_margin_px(self, settings: DepthCampaignSettings) -> int:
        """Pixels (of the campaign's grid) the simulations' inputs extend beyond the frame on every side."""
        from vissim.bench.depth.viewers import frame_margin_px

        return frame_margin_px(self.viewer, self.scene) if settings.frame_margin else 0


@dataclass(frozen=True)
class DepthCampaignSettings:
    spp: int = 64
    aux_spp: int = 32
    seeds: tuple[int, int] = (1, 2)
    aux_seed: int = 3
    oversample: int = 1
    simulations: tuple[str, ...] = DEPTH_SIMULATIONS
    wavelength_nm: float = DEFAULT_WAVELENGTH_NM
    data_range: float = 1.0
    margin_px: float = 1.0
    layer_spacing_fraction: float = DEFAULT_LAYER_SPACING_FRACTION
    inputs: tuple[str, ...] = DEPTH_INPUTS
    frame_margin: bool = True  # render the simulations' inputs beyond the frame by the largest blur radius




# -- loading ---------------------------------------------------------------------------
#: [campaign] numbers: (unit, lowest, highest), the ranges of `vissim.checks`.
NUMBER_SETTINGS = {
    "wavelength_nm": ("nm", *WAVELENGTH_RANGE_NM),
    "data_range": ("(linear reflectance)", *DATA_RANGE_RANGE),
    "margin_px": ("px", *MARGIN_RANGE_PX),
    "layer_spacing_fraction": ("(of a blur-free depth step)", *LAYER_SPACING_FRACTION_RANGE),
}
#: [campaign] whole numbers: (unit, lowest, highest), the ranges of `vissim.checks`.
WHOLE_SETTINGS = {
    "spp": ("samples per pixel", 1, MAX_SPP),
    "aux_spp": ("samples per pixel", 1, MAX_SPP),
    "aux_seed": ("(a seed)", 0, MAX_CAMPAIGN_SEED),
    "oversample": ("(sub-pixels per pixel per axis)", *OVERSAMPLE_RANGE),
}


def _settings(head: dict, source: str) -> DepthCampaignSettings:
    return DepthCampaignSettings(**settings_kwargs(
        head, DepthCampaignSettings, source, "campaign", numbers=NUMBER_SETTINGS, whole_numbers=WHOLE_SETTINGS,
        lists={"simulations": DEPTH_SIMULATIONS, "inputs": DEPTH_INPUTS}, texts=(), switches=("frame_margin",)))


#: Camera fields: (unit, lowest, highest).
CAMERA_FIELDS = {
    "f_number": ("(f-number)", *F_NUMBER_RANGE),
    "focus_distance_m": ("m", *OBJECT_DISTANCE_RANGE_M),
    "focal_length_mm": ("mm", *FOCAL_LENGTH_RANGE_MM),
    "vertex_distance_mm": ("mm", *VERTEX_DISTANCE_RANGE_MM),
}


#: An eye observer's keys in a ``[[config]]`` table, and all its keys.
EYE_KEYS = ("prescription", "pupil_diameter_mm", "accommodation_diopters")
CONFIG_KEYS = ("name", "scene", *EYE_KEYS, "camera")


def _eye(raw: dict, viewer, source: str, where: str) -> EyeViewer:
    base_eye = viewer if isinstance(viewer, EyeViewer) else EyeViewer()
    rx = base_eye.prescription
    if "prescription" in raw:
        try:
            rx = Prescription.parse(text(raw["prescription"], source, f"{where}.prescription"))
        except VissimInputError as exc:
            raise field_error(source, f"{where}.prescription", str(exc)) from None
    pupil = number(raw.get("pupil_diameter_mm", base_eye.pupil_diameter_mm), source, f"{where}.pupil_diameter_mm", "mm",
                   lo=EYE_PUPIL_RANGE_MM[0], hi=EYE_PUPIL_RANGE_MM[1])
    accommodation = number(raw.get("accommodation_diopters", base_eye.accommodation_diopters), source, f"{where}.accommodation_diopters",
                           "dioptres", lo=ACCOMMODATION_RANGE_DIOPTERS[0], hi=ACCOMMODATION_RANGE_DIOPTERS[1])
    try:
        return EyeViewer(rx, pupil, accommodation)
    except VissimInputError as exc:
        raise field_error(source, where, str(exc)) from None


def _camera(camera: Any, viewer, source: str, where: str) -> CameraViewer:
    allowed = set(CAMERA_FIELDS) | {"lenses"}
    if not isinstance(camera, dict) or set(camera) - allowed:
        raise field_error(source, where, f"a table of {sorted(allowed)}, got {camera!r}")
    kwargs: dict[str, Any] = checked_numbers(camera, CAMERA_FIELDS, source, where)
    specs = lenses(camera.get("lenses", []), source, f"{where}.lenses")
    kwargs["lenses"] = tuple(TrialLens(s.sphere_diopters, s.cylinder_diopters, s.axis_deg) for s in specs)
    try:
        return dataclasses.replace(viewer if isinstance(viewer, CameraViewer) else CameraViewer(), **kwargs)
    except VissimInputError as exc:
        raise field_error(source, where, str(exc)) from None


def _configuration(raw: dict, base: Path, source: str, where: str) -> DepthConfiguration:
    refuse_unknown_keys(raw, CONFIG_KEYS, source, where, "field")
    if "scene" not in raw:
        raise field_error(source, where, "needs scene = a depth scene file (relative to the campaign file)")
    scene_file = (base / text(raw["scene"], source, f"{where}.scene")).resolve()
    if not scene_file.is_file():
        raise field_error(source, f"{where}.scene", f"{scene_file} is not a file")
    try:
        loaded = load_depth_scene_toml(scene_file)
    except VissimInputError as exc:
        raise field_error(source, f"{where}.scene", str(exc)) from None
    eye_keys = set(EYE_KEYS) & set(raw)
    if eye_keys and "camera" in raw:
        raise field_error(source, where, f"give an eye ({', '.join(EYE_KEYS)}) or a camera, not both")
    viewer = loaded.viewer
    if eye_keys:
        viewer = _eye(raw, viewer, source, where)
    elif "camera" in raw:
        viewer = _camera(raw["camera"], viewer, source, f"{where}.camera")
    name = name_text(raw["name"], source, f"{where}.name") if "name" in raw else ""
    return DepthConfiguration(name or f"{scene_file.stem}: {viewer.label()}", str(scene_file), loaded.scene, viewer)


def read_depth_part(doc: dict, head: dict, path: Path) -> tuple[DepthCampaignSettings, tuple[DepthConfiguration, ...], None]:
    """(settings, configurations, no manifest) of a depth campaign: its ``[campaign]`` settings and ``[[config]]``."""
    source = str(path)
    settings = _settings(head, source)
    configs = [_configuration(c, path.parent, source, f"config[{i}]") for i, c in enumerate(tables(doc, "config", source))]
    refuse_duplicate_names(source, [(f"config[{i}]", c) for i, c in enumerate(configs)],
                           lambda c: f"scene {Path(c.scene_file).name}, {c.viewer.label()}")
    return settings, tuple(configs), None