"""Bench scene files (TOML): read, validate, and turn into a `DslrBench` and a chart.

A scene file has the tables ``[camera]``, ``[holder]`` (with ``[[holder.lenses]]``, chart side
first), ``[chart]``, ``[image]`` and ``[sampling]``; ``scenes/dslr_bench.toml`` is the
commented example.  Every table and key is optional (defaults: the thesis's bench, an empty
holder, the Sloan letter R at LogMAR 1.0); unknown tables or keys, and values of the wrong
type, raise `VissimInputError` naming the file, the key and the unit.

The ``[chart]`` table alone also makes a *chart file* (`load_chart_toml`): either one
letter (``letter``, ``logmar``) or an ETDRS chart (``letters``, ``logmar_range``,
``logmar_step``, ``seed``), with ``polarity``, ``paper_reflectance``, ``ink_reflectance``, and
``chart_distance_m`` (metres, as everywhere a file names it; the bench's own lengths are mm), which
is also the chart's viewing distance.
"""

from __future__ import annotations

import os
from typing import Any

from vissim.bench.dslr.bench import DslrBench
from vissim.bench.scene_toml import (check_keys, checked_values, image_size_px, parse_trial_lenses, read_scene_toml,
                                     sub_table, typed_value)
from vissim.charts import DEFAULT_LETTER_SEED, ChartSpec, etdrs_chart_spec, single_letter_spec
from vissim.checks import F_NUMBER_RANGE, FOCAL_LENGTH_RANGE_MM, OBJECT_DISTANCE_RANGE_M, number_within
from vissim.errors import VissimInputError
from vissim.units import m_to_mm, mm_to_m

__all__ = ["load_bench_toml", "load_chart_toml", "chart_spec_from_table", "bench_from_tables"]

# key -> (DslrBench field, type, unit)
_CAMERA = {
    "focal_length_mm": ("focal_length_mm", float, "mm"),
    "f_number": ("f_number", float, "(f-number)"),
    "focus_distance_mm": ("focus_distance_mm", float, "mm"),
}
#: The ranges of a file's camera (`vissim.checks`): any camera lens and bench.
_CAMERA_BOUNDS = {"focal_length_mm": FOCAL_LENGTH_RANGE_MM, "f_number": F_NUMBER_RANGE,
                  "focus_distance_mm": tuple(m_to_mm(d) for d in OBJECT_DISTANCE_RANGE_M)}
_HOLDER = {
    "vertex_distance_mm": ("vertex_distance_mm", float, "mm"),
    "lens_gap_mm": ("lens_gap_mm", float, "mm"),
    "refractive_index": ("refractive_index", float, "(dimensionless)"),
    "clear_aperture_mm": ("clear_aperture_mm", float, "mm"),
    "lenses": (None, list, "(array of tables)"),
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
    "chart_distance_m": (float, "m"),
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
    for name, bounds in _CAMERA_BOUNDS.items():  # a camera a file describes; the API also takes a pinhole's f/1000
        if name in fields:
            number_within(fields[name], f"{source} [camera] {name}", _CAMERA[name][2], bounds)
    if "size_px" in fields:
        fields["size_px"] = image_size_px(fields["size_px"], source)
    holder_lenses = sub_table(doc, "holder", source).get("lenses", [])
    fields["lenses"] = parse_trial_lenses(holder_lenses, f"{source} [[holder.lenses]]")
    chart = sub_table(doc, "chart", source)
    if "chart_distance_m" in chart:
        fields["chart_distance_mm"] = m_to_mm(number_within(
            typed_value(chart["chart_distance_m"], float, f"{source} [chart] chart_distance_m", "m"),
            f"{source} [chart] chart_distance_m", "m", OBJECT_DISTANCE_RANGE_M))
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
