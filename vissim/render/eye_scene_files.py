"""Scene files (TOML) of ``vissim render eye``: the eye, the light, the chart, the spectacles, the render.

Tables (every one and every key optional; a key left out keeps `EyeRender`'s default):

* ``[eye]``: ``model``, ``accommodation_diopters``, ``pupil_diameter_mm`` or ``iris_mm``, ``prescription`` (the
  prescription the eye needs at the spectacle plane), ``field_deg`` (``[x, y]``, OSA's frame);
* ``[light]``: ``wavelength_nm`` or ``spectrum`` (``"mono"``, ``"photopic"``);
* ``[chart]``: ``chart_distance_m``, ``letter``, ``logmar``;
* ``[spectacles]``: ``vertex_distance_mm`` and one trial lens, ``sphere_diopters``, ``cylinder_diopters``,
  ``axis_deg`` (the key names of every scene file's trial lens, `vissim.bench.scene_toml`);
* ``[render]``: ``size_px`` (``[rows, cols]``), ``arcmin_per_px``, ``spp``, ``seed``.

An unknown table or key, a value of the wrong type or out of range raises `VissimInputError`:
one line naming the file, the key and the unit.  Ranges are those `EyeRender` checks (the
functions of `vissim.checks` it calls, here given the key's name); what `EyeRender` alone decides
(the model's name and accommodation range, pupil and iris together) comes back prefixed by the file.
"""

from __future__ import annotations

import os
from typing import Any

from vissim.bench.scene_toml import check_keys, read_scene_toml, sub_table, typed_value
from vissim.checks import (EYE_LIGHT_RANGE_NM, VIEWING_DISTANCE_RANGE_M, arcmin_per_px, eye_pupil_diameter_mm, number_within,
                           size_px, trial_lens_diopters, vertex_distance_mm)
from vissim.errors import VissimInputError
from vissim.render.eye_render import EyeRender

__all__ = ["EYE_SCENE_KEYS", "eye_scene_values", "eye_render_from_values", "load_eye_scene"]

#: table -> key -> (the `EyeRender` field, type, unit); the spectacles' trial lens is read apart.
EYE_SCENE_KEYS: dict[str, dict[str, tuple[str, type, str]]] = {
    "eye": {"model": ("model", str, "(a schematic eye's name)"),
            "accommodation_diopters": ("accommodation_diopters", float, "D"),
            "pupil_diameter_mm": ("pupil_mm", float, "mm"), "iris_mm": ("iris_mm", float, "mm"),
            "prescription": ("rx", str, "(a prescription, e.g. '-2.00 -0.50 x 180')"),
            "field_deg": ("field_deg", list, "([x, y] degrees)")},
    "light": {"wavelength_nm": ("wavelength_nm", float, "nm"), "spectrum": ("spectrum", str, "('mono' or 'photopic')")},
    "chart": {"chart_distance_m": ("chart_distance_m", float, "m"), "letter": ("letter", str, "(one Sloan letter)"),
              "logmar": ("logmar", float, "LogMAR")},
    "spectacles": {"vertex_distance_mm": ("vertex_mm", float, "mm")},
    "render": {"size_px": ("size_px", list, "([rows, cols] whole px)"), "arcmin_per_px": ("arcmin_per_px", float,
                                                                                          "arcmin per pixel"),
               "spp": ("spp", int, "samples per pixel"), "seed": ("seed", int, "(sampler seed)")},
}
_LENS_KEYS = {"sphere_diopters": "D", "cylinder_diopters": "D", "axis_deg": "degrees TABO"}


def _field_deg(value: list, where: str) -> tuple[float, float]:
    if len(value) != 2:
        raise VissimInputError(f"{where} must be [x, y] in degrees, got {value!r}")
    return tuple(typed_value(v, float, where, "degrees") for v in value)  # type: ignore[return-value]


def _ranged(values: dict, source: str) -> None:
    """The ranges `EyeRender` checks, with the check's message naming the file and the key."""
    checks = {"pupil_mm": ("eye", eye_pupil_diameter_mm), "iris_mm": ("eye", eye_pupil_diameter_mm),
              "wavelength_nm": ("light", lambda v, n: number_within(v, n, "nm", EYE_LIGHT_RANGE_NM)),
              "arcmin_per_px": ("render", arcmin_per_px),
              "chart_distance_m": ("chart", lambda v, n: number_within(v, n, "m", VIEWING_DISTANCE_RANGE_M)),
              "vertex_mm": ("spectacles", vertex_distance_mm)}
    keys = {field: key for table in EYE_SCENE_KEYS.values() for key, (field, _, _) in table.items()}
    for field, (table, check) in checks.items():
        if field in values:
            check(values[field], f"{source} [{table}].{keys[field]}")
    if values.get("spp", 1) < 1:
        raise VissimInputError(f"{source} [render].spp must be >= 1 samples per pixel, got {values['spp']}")


def _named(where: str, check, *args) -> None:
    """``check(*args)``; its refusal as one line prefixed by ``where`` (the file and the keys)."""
    try:
        check(*args)
    except VissimInputError as exc:
        raise VissimInputError(f"{where}: {exc}") from None


def _checked_elsewhere(values: dict, source: str) -> None:
    """What the eye model, the prescription, the chart and the trial lens check themselves (the render would
    refuse it later), refused now with the keys named."""
    from vissim.charts import single_letter_spec
    from vissim.optics.eyes.models import eye_model
    from vissim.optics.rx.prescription import Prescription
    from vissim.optics.rx.trial_lens import TrialLens

    defaults = EyeRender.__dataclass_fields__
    if "model" in values or "accommodation_diopters" in values:
        _named(f"{source} [eye].model, accommodation_diopters", eye_model,
               *(values.get(k, defaults[k].default) for k in ("model", "accommodation_diopters")))
    if "rx" in values:
        _named(f"{source} [eye].prescription", Prescription.parse, values["rx"])
    if "letter" in values or "logmar" in values:
        letter, logmar, distance = (values.get(k, defaults[k].default) for k in ("letter", "logmar", "chart_distance_m"))
        _named(f"{source} [chart].letter, logmar", lambda *a: single_letter_spec(*a, viewing_distance_m=distance),
               letter, logmar)
    if "lens" in values:
        _named(f"{source} [spectacles] sphere_diopters, cylinder_diopters, axis_deg", TrialLens, *values["lens"])


def _spectacle_lens(table: dict, source: str) -> tuple[float, float, float] | None:
    """(sphere D, cylinder D, axis deg) of ``[spectacles]``'s trial lens, or None when it has none."""
    where = f"{source} [spectacles]"
    given = {key: typed_value(table[key], float, f"{where}.{key}", unit)
             for key, unit in _LENS_KEYS.items() if key in table}
    if "sphere_diopters" not in given and "cylinder_diopters" not in given:
        if "axis_deg" in given:
            raise VissimInputError(f"{where}.axis_deg needs cylinder_diopters (D)")
        return None
    sphere = trial_lens_diopters(given.get("sphere_diopters", 0.0), f"{where}.sphere_diopters")
    cylinder = trial_lens_diopters(given.get("cylinder_diopters", 0.0), f"{where}.cylinder_diopters")
    if cylinder != 0.0 and "axis_deg" not in given:
        raise VissimInputError(f"{where}.cylinder_diopters {cylinder:g} D needs axis_deg (degrees TABO, 0-180)")
    return sphere, cylinder, given.get("axis_deg", 180.0)


def eye_scene_values(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The `EyeRender` fields a scene file gives (only those it gives), checked (module doc)."""
    doc, source = read_scene_toml(path)
    check_keys(doc, tuple(EYE_SCENE_KEYS), source)
    values: dict[str, Any] = {}
    for name, keys in EYE_SCENE_KEYS.items():
        table = sub_table(doc, name, source)
        check_keys(table, (*keys, *_LENS_KEYS) if name == "spectacles" else tuple(keys), f"{source} [{name}]")
        for key, (field, kind, unit) in keys.items():
            if key in table:
                values[field] = typed_value(table[key], kind, f"{source} [{name}].{key}", unit)
        if name == "spectacles" and (lens := _spectacle_lens(table, source)) is not None:
            values["lens"] = lens
    if "field_deg" in values:
        values["field_deg"] = _field_deg(values["field_deg"], f"{source} [eye].field_deg")
    if "size_px" in values:
        values["size_px"] = size_px(values["size_px"], f"{source} [render].size_px")
    _ranged(values, source)
    _checked_elsewhere(values, source)
    if "iris_mm" in values and "pupil_mm" not in values:
        values["pupil_mm"] = None  # the iris instead of EyeRender's default entrance pupil
    _whole(values, source)
    return values


def _whole(values: dict, source: str) -> None:
    """`EyeRender` of ``values``; a refusal names the key that alone is refused (field_deg beyond the
    sensor's reach), or the file when it takes two keys (pupil_diameter_mm with iris_mm)."""
    try:
        EyeRender(**values)
    except VissimInputError as exc:
        keys = {field: f"[{table}].{key}" for table, fields in EYE_SCENE_KEYS.items()
                for key, (field, _, _) in fields.items()}
        for field in (field for field in keys if field in values):
            alone = {field: values[field], "pupil_mm": None} if field == "iris_mm" else {field: values[field]}
            if not _accepted(alone):
                raise VissimInputError(f"{source} {keys[field]}: {exc}") from None
        raise VissimInputError(f"{source}: {exc}") from None


def _accepted(values: dict) -> bool:
    try:
        EyeRender(**values)
    except VissimInputError:
        return False
    return True


def eye_render_from_values(values: dict[str, Any], source: str) -> EyeRender:
    """`EyeRender` of ``values``; its refusal as one line prefixed by ``source`` (the file, or the command line)."""
    try:
        return EyeRender(**values)
    except VissimInputError as exc:
        raise VissimInputError(f"{source}: {exc}") from None


def load_eye_scene(path: str | os.PathLike[str]) -> EyeRender:
    """The `EyeRender` of an eye scene file (``scenes/eye.toml``; module doc)."""
    return eye_render_from_values(eye_scene_values(path), str(path))
