"""Scene files (TOML) of every bench: read one, and check its tables, keys, types and units.

Each bench's loader (`vissim.bench.dslr.scene_files`, `vissim.bench.atv.scene_files`,
`vissim.bench.depth.scene_files`) builds on these: an unknown table or key, or a value of the
wrong type, raises `VissimInputError` naming the file, the key and the unit.
"""

from __future__ import annotations

import math
import os
import tomllib
from pathlib import Path
from typing import Any

from vissim.checks import trial_lens_diopters
from vissim.errors import VissimInputError
from vissim.optics.rx.trial_lens import TrialLens
from vissim.vocabulary import refuse_renamed_keys

__all__ = ["read_scene_toml", "typed_value", "sub_table", "check_keys", "checked_values", "parse_trial_lenses",
           "image_size_px"]

# key -> (type, unit) of one trial lens (``[[holder.lenses]]``, ``[[camera.lenses]]``)
_LENS = {
    "sphere_diopters": (float, "D"),
    "cylinder_diopters": (float, "D"),
    "axis_deg": (float, "degrees TABO"),
    "refractive_index": (float, "(dimensionless)"),
    "center_thickness_mm": (float, "mm"),
    "back_surface_diopters": (float, "D"),
}

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
    """Refuse a key of ``table`` that is not in ``allowed`` (a renamed key by its new name)."""
    refuse_renamed_keys(table, allowed, where)
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
    if not isinstance(entries, list) or not all(isinstance(entry, dict) for entry in entries):
        raise VissimInputError(f"{where} must be an array of tables (sphere_diopters, ...), got {entries!r}")
    lenses = []
    for i, entry in enumerate(entries):
        lens_where = f"{where} #{i + 1}"
        kwargs = checked_values(entry, _LENS, lens_where)
        if "sphere_diopters" not in kwargs and "cylinder_diopters" not in kwargs:
            raise VissimInputError(f"{lens_where} needs sphere_diopters and/or cylinder_diopters (D)")
        kwargs.setdefault("sphere_diopters", 0.0)
        for key in ("sphere_diopters", "cylinder_diopters"):
            if key in kwargs:
                trial_lens_diopters(kwargs[key], f"{lens_where} {key}")
        lenses.append(TrialLens(**kwargs))
    return tuple(lenses)


def image_size_px(size: list, source: str) -> tuple[int, int]:
    """``[image] size_px`` as (rows, cols) in whole pixels."""
    if len(size) != 2 or not all(isinstance(v, int) and not isinstance(v, bool) for v in size):
        raise VissimInputError(f"{source} [image] size_px must be [rows, cols] in whole px, got {size!r}")
    return tuple(size)  # type: ignore[return-value]


def read_scene_toml(path: str | os.PathLike[str]) -> tuple[dict, str]:
    """(the TOML document, its path as text) of a scene file; one clean error if unreadable or not TOML."""
    if isinstance(path, str) and not path.strip():
        raise VissimInputError(f"the scene file's path {path!r} is empty; give a TOML file")
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise VissimInputError(f"cannot read scene file {path}: {exc.strerror or exc}") from None
    try:
        return tomllib.loads(text), str(path)
    except tomllib.TOMLDecodeError as exc:
        raise VissimInputError(f"{path} is not valid TOML: {exc}") from None
