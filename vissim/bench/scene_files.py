"""Bench scene files (TOML): read, validate, and turn into a `DslrBench` and a chart.

A scene file has the tables ``[camera]``, ``[holder]`` (with ``[[holder.lenses]]``, chart side
first), ``[chart]``, ``[image]`` and ``[sampling]``; ``scenes/dslr_bench.toml`` is the
commented example.  Every table and key is optional (defaults: the thesis's bench, an empty
holder, the Sloan letter R at LogMAR 1.0); unknown tables or keys, and values of the wrong
type, raise `VissimInputError` naming the file, the key and the unit.

The ``[chart]`` table alone also makes a *chart file* (`load_chart_toml`): either one
letter (``letter``, ``logmar``) or an ETDRS chart (``letters``, ``logmar_range``,
``logmar_step``, ``seed``), with ``polarity``, ``paper_reflectance``, ``ink_reflectance``.  The
chart's viewing distance is the bench's chart distance.
"""

from __future__ import annotations

import math
import os
import tomllib
from pathlib import Path
from typing import Any

from vissim.bench.dslr import DslrBench
from vissim.charts import DEFAULT_LETTER_SEED, ChartSpec, etdrs_chart_spec, single_letter_spec
from vissim.errors import VissimInputError
from vissim.optics.trial_lens import EYE_VERTEX_DISTANCE_MM, TrialLens
from vissim.units import mm_to_m

__all__ = ["load_bench_toml", "load_chart_toml", "chart_spec_from_table", "bench_from_tables", "read_scene_toml",
           "typed_value", "sub_table", "check_keys", "checked_values", "parse_trial_lenses", "image_size_px"]

# key -> (DslrBench field, type, unit)
_CAMERA = {
    "focal_length_mm": ("focal_length_mm", float, "mm"),
    "f_number": ("f_number", float, "(f-number)"),
    "focus_distance_mm": ("focus_distance_mm", float, "mm"),
}
_HOLDER = {
    "vertex_distance_mm": ("vertex_distance_mm", float, "mm"),
    "lens_gap_mm": ("lens_gap_mm", float, "mm"),
    "refractive_index": ("refractive_index", float, "(dimensionless)"),
    "clear_aperture_mm": ("clear_aperture_mm", float, "mm"),
    "lenses": (None, list, "(array of tables)"),
}
_LENS = {
    "sphere_diopters": (float, "D"),
    "cylinder_diopters": (float, "D"),
    "axis_deg": (float, "degrees TABO"),
    "refractive_index": (float, "(dimensionless)"),
    "center_thickness_mm": (float, "mm"),
    "back_surface_diopters": (float, "D"),
}
_IMAGE = {"arcmin_per_px": ("arcmin_per_px", float, "arcmin/px"), "size_px": ("size_px", list, "[rows, cols] px")}
_SAMPLING = {
    "spp": ("spp", int, "samples per pixel"),
    "seed": ("seed", int, "(integer)"),
    "sampler": ("sampler", str, "(name)"),
    "fresnel_loss": ("fresnel_loss", bool, "(true/false)"),
    "texels_per_px": ("texels_per_px", float, "texels per camera pixel"),
}
_CHART = {
    "distance_mm": (float, "mm"),
    "letter": (str, "(Sloan letter)"),
    "logmar": (float, "LogMAR"),
    "letters": (str, "(Sloan letters, rows separated by spaces)"),
    "logmar_range": (list, "[start, stop] LogMAR"),
    "logmar_step": (float, "LogMAR"),
    "seed": (int, "(integer)"),
    "polarity": (str, "('black-on-white' or 'white-on-black')"),
    "paper_reflectance": (float, "(fraction 0-1)"),
    "ink_reflectance": (float, "(fraction 0-1)"),
}
_TABLES = ("camera", "holder", "chart", "image", "sampling")


def typed_value(value: Any, kind: type, where: str, unit: str) -> Any:
    """``value`` as ``kind`` (a finite float, an int, or any type), or an error naming ``where`` and ``unit``."""
    if kind is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise VissimInputError(f"{where} must be a number in {unit}, got {value!r}")
        return float(value)
    if kind is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise VissimInputError(f"{where} must be an integer {unit}, got {value!r}")
        return value
    if not isinstance(value, kind):
        raise VissimInputError(f"{where} must be a {kind.__name__} {unit}, got {value!r}")
    return value


def sub_table(doc: dict, name: str, source: str) -> dict:
    """The table ``[name]`` of ``doc`` (empty when absent)."""
    table = doc.get(name, {})
    if not isinstance(table, dict):
        raise VissimInputError(f"{source}: [{name}] must be a table, got {table!r}")
    return table


def check_keys(table: dict, allowed, where: str) -> None:
    """Refuse a key of ``table`` that is not in ``allowed``."""
    for key in table:
        if key not in allowed:
            raise VissimInputError(f"{where}: unknown key {key!r}; expected one of {', '.join(allowed)}")


def checked_values(table: Any, schema: dict, where: str) -> dict:
    """The keys of ``table`` checked against ``schema`` ``{key: (type, unit)}``."""
    if not isinstance(table, dict):
        raise VissimInputError(f"{where} must be a table, got {table!r}")
    check_keys(table, schema, where)
    return {key: typed_value(value, schema[key][0], f"{where} {key}", schema[key][1]) for key, value in table.items()}


def parse_trial_lenses(entries: list, where: str) -> tuple[TrialLens, ...]:
    """The trial lenses of an array of ``_LENS`` tables called ``where`` (e.g. ``[[holder.lenses]]``)."""
    lenses = []
    for i, entry in enumerate(entries):
        lens_where = f"{where} #{i + 1}"
        kwargs = checked_values(entry, _LENS, lens_where)
        if "sphere_diopters" not in kwargs and "cylinder_diopters" not in kwargs:
            raise VissimInputError(f"{lens_where} needs sphere_diopters and/or cylinder_diopters (D)")
        kwargs.setdefault("sphere_diopters", 0.0)
        lenses.append(TrialLens(**kwargs))
    return tuple(lenses)


def image_size_px(size: list, source: str) -> tuple[int, int]:
    """``[image] size_px`` as (rows, cols) in whole pixels."""
    if len(size) != 2 or not all(isinstance(v, int) and not isinstance(v, bool) for v in size):
        raise VissimInputError(f"{source} [image] size_px must be [rows, cols] in whole px, got {size!r}")
    return tuple(size)  # type: ignore[return-value]


def read_scene_toml(path: str | os.PathLike[str]) -> tuple[dict, str]:
    """(the TOML document, its path as text) of a scene file; one clean error if unreadable or not TOML."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise VissimInputError(f"cannot read scene file {path}: {exc.strerror or exc}") from None
    try:
        return tomllib.loads(text), str(path)
    except tomllib.TOMLDecodeError as exc:
        raise VissimInputError(f"{path} is not valid TOML: {exc}") from None


def chart_spec_from_table(table: dict, source: str, chart_distance_mm: float) -> ChartSpec:
    """The chart of a ``[chart]`` table (module doc) at ``chart_distance_mm``."""
    where = f"{source} [chart]"
    values = checked_values(table, _CHART, where)
    style = {key: values[key] for key in ("polarity", "paper_reflectance", "ink_reflectance") if key in values}
    style["viewing_distance_m"] = mm_to_m(chart_distance_mm)
    if "letters" in values or "logmar_range" in values:
        if "letter" in values or "logmar" in values:
            raise VissimInputError(f"{where}: give either letter/logmar (one letter) or letters/logmar_range (ETDRS)")
        span = values.get("logmar_range", [1.0, -0.3])
        if len(span) != 2:
            raise VissimInputError(f"{where} logmar_range must be [start, stop] in LogMAR, got {span!r}")
        start, stop = (typed_value(v, float, f"{where} logmar_range", "LogMAR") for v in span)
        return etdrs_chart_spec((start, stop), values.get("logmar_step", 0.1), letters=values.get("letters"),
                                seed=values.get("seed", DEFAULT_LETTER_SEED), **style)
    for key in ("logmar_step", "seed"):
        if key in values:
            raise VissimInputError(f"{where}: {key} applies to ETDRS charts (letters/logmar_range) only")
    return single_letter_spec(values.get("letter", "R"), values.get("logmar", 1.0), **style)


def bench_from_tables(doc: dict, source: str, **overrides: Any) -> DslrBench:
    """A `DslrBench` from parsed scene tables; ``overrides`` replace fields last."""
    check_keys(doc, _TABLES, source)
    fields: dict[str, Any] = {}
    for name, schema in (("camera", _CAMERA), ("holder", _HOLDER), ("image", _IMAGE), ("sampling", _SAMPLING)):
        table = sub_table(doc, name, source)
        check_keys(table, schema, f"{source} [{name}]")
        for key, value in table.items():
            field, kind, unit = schema[key]
            if field is not None:
                fields[field] = typed_value(value, kind, f"{source} [{name}] {key}", unit)
    if "size_px" in fields:
        fields["size_px"] = image_size_px(fields["size_px"], source)
    holder_lenses = sub_table(doc, "holder", source).get("lenses", [])
    fields["lenses"] = parse_trial_lenses(holder_lenses, f"{source} [[holder.lenses]]")
    chart = sub_table(doc, "chart", source)
    if "distance_mm" in chart:
        fields["chart_distance_mm"] = typed_value(chart["distance_mm"], float, f"{source} [chart] distance_mm", "mm")
    fields.update({key: value for key, value in overrides.items() if value is not None})
    return DslrBench(**fields)


def load_bench_toml(path: str | os.PathLike[str], **overrides: Any) -> tuple[DslrBench, ChartSpec]:
    """(bench, chart spec) of the scene file at ``path``; ``overrides`` (not None) replace bench fields."""
    doc, source = read_scene_toml(path)
    bench = bench_from_tables(doc, source, **overrides)
    return bench, chart_spec_from_table(sub_table(doc, "chart", source), source, bench.chart_distance_mm)


def load_chart_toml(path: str | os.PathLike[str], chart_distance_mm: float) -> ChartSpec:
    """The chart of the ``[chart]`` table of ``path`` (other tables are ignored)."""
    doc, source = read_scene_toml(path)
    return chart_spec_from_table(sub_table(doc, "chart", source), source, chart_distance_mm)


_ATV_TUBE_KEYS = {
    "tube_length_mm": (float, "mm"), "lens_power_diopters": (float, "dioptres"),
    "lens_refractive_index": (float, "(index)"), "lens_center_thickness_mm": (float, "mm"),
    "lens_clear_aperture_mm": (float, "mm"), "lens_convex_side": (str, "('eye' or 'phone')"),
    "eye_relief_mm": (float, "mm"), "pixels_per_inch": (float, "ppi"), "pixel_radiance": (float, "(linear)"),
}


def load_atv_toml(path: str | os.PathLike[str]):
    """The `AtvConfig` of an ATV scene file (``scenes/atv_tube.toml``)."""
    from vissim.bench.atv import AtvConfig, AtvEye, AtvTube, atv_trial_lens
    from vissim.optics.prescription import Prescription

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
    lens = checked("trial_lens", "sphere_diopters", "cylinder_diopters", "axis_deg", "distance_mm", "fresnel_loss")
    trial = None
    if "sphere_diopters" in lens or "cylinder_diopters" in lens:
        powers = (("sphere_diopters", 0.0, "dioptres"), ("cylinder_diopters", 0.0, "dioptres"),
                  ("axis_deg", 180.0, "degrees"))
        trial = atv_trial_lens(*(value("trial_lens", key, default, float, unit) for key, default, unit in powers))
    return AtvConfig(tube=tube, eye=eye, trial_lens=trial,
                     trial_lens_distance_mm=value("trial_lens", "distance_mm", EYE_VERTEX_DISTANCE_MM, float, "mm"),
                     fresnel_loss=value("trial_lens", "fresnel_loss", False, bool, "(true/false)"))
