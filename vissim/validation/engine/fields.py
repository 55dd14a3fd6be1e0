"""Checks of campaign-file values: each bad value gets one line naming the file, the field and its unit.

Shared by the campaign loader (`vissim.validation.engine.loader`), every bench kind's part of
the file and the capture manifest.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from vissim.checks import (AXIS_RANGE_DEG, MAX_CAMPAIGN_SEED, MAX_DESCRIPTION_CHARS, MAX_SPP, TRIAL_LENS_RANGE_DIOPTERS,
                           name_problem, path_arg)
from vissim.errors import VissimInputError
from vissim.optics.rx.trial_lens import MAX_LENSES_IN_HOLDER
from vissim.vocabulary import refuse_renamed_keys

__all__ = ["field_error", "read_toml_file", "read_campaign_toml", "number", "whole_number",
           "checked_numbers", "seed_pair", "text", "table", "tables", "value_list", "choices", "settings_kwargs",
           "lens", "lenses", "LensSpec", "LENS_KEYS", "MAX_SPP", "CAMPAIGN_TABLES"]

#: Top-level tables that make a TOML file a campaign: its head and any bench kind's configurations.
CAMPAIGN_TABLES = ("campaign", "item", "sweep", "config")


def field_error(source: str, where: str, message: str) -> VissimInputError:
    return VissimInputError(f"{source}: {where}: {message}")


class UnknownFieldError(VissimInputError):
    """A campaign file's key that its kind does not know: perhaps another kind's (`vissim.validation.engine.loader`)."""


def unknown_field_error(source: str, where: str, message: str) -> UnknownFieldError:
    return UnknownFieldError(f"{source}: {where}: {message}")


def refuse_unknown_keys(table: dict, known, source: str, where: str, noun: str = "key") -> None:
    """Refuse a table's keys that are not ``known``: a renamed one naming its new spelling
    (`vissim.vocabulary.refuse_renamed_keys`), else one `UnknownFieldError` listing them and the keys known."""
    unknown = set(table) - set(known)
    refuse_renamed_keys(unknown, known, f"{source}: {where}")
    if unknown:
        raise unknown_field_error(source, where, f"unknown {noun if len(unknown) == 1 else noun + 's'} "
                                                 f"{sorted(unknown)}; known: {', '.join(known)}")


def read_toml_file(path: str | Path, what: str = "campaign file") -> dict:
    """The TOML document at ``path``; one clean error naming it if it is absent, a folder, binary or not TOML."""
    path = path_arg(path, f"the {what}'s path")
    if not path.exists():
        raise VissimInputError(f"{what} {path} does not exist")
    if path.is_dir():
        raise VissimInputError(f"{path} is a folder, not a {what} (give a .toml file)")
    if not path.is_file():
        raise VissimInputError(f"{path} is not a regular file, so not a {what}")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise VissimInputError(f"cannot read {what} {path}: {exc.strerror or exc}") from None
    try:
        return tomllib.loads(data.decode("utf-8"))
    except UnicodeDecodeError:
        raise VissimInputError(f"{path} is not a {what}: it is not UTF-8 text (a binary file?)") from None
    except tomllib.TOMLDecodeError as exc:
        raise VissimInputError(f"{path} is not a {what}: not valid TOML ({exc})") from None


def read_campaign_toml(path: str | Path) -> dict:
    """The TOML document of a campaign file; one clean error for anything that is not one."""
    doc = read_toml_file(path)
    if not set(doc) & set(CAMPAIGN_TABLES):
        found = f"its tables: {', '.join(sorted(doc))}" if doc else "it is empty"
        raise VissimInputError(f"{path} is not a campaign file: it has no [campaign], [[item]], [[sweep]] or "
                               f"[[config]] table ({found})")
    return doc


def number(value: Any, source: str, where: str, unit: str, *, lo: float | None = None, hi: float | None = None,
           positive: bool = False) -> float:
    """A finite number (not a bool), > 0 if ``positive``, within ``[lo, hi]`` if given."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise field_error(source, where, f"expected a number in {unit}, got {value!r}")
    if positive and value <= 0:
        raise field_error(source, where, f"must be > 0 {unit}, got {value!r}")
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        span = (f"{lo:g} {unit} only" if lo == hi else f"within {lo:g} to {hi:g} {unit}") if (
            lo is not None and hi is not None) else (f"at least {lo:g} {unit}" if lo is not None else f"at most {hi:g} {unit}")
        raise field_error(source, where, f"must be {span}, got {value!r}")
    return float(value)


def whole_number(value: Any, source: str, where: str, unit: str, *, lo: int, hi: int) -> int:
    """An integer (not a bool) within ``[lo, hi]``; a number outside the range is told so first (1e9, not 'whole')."""
    is_number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if is_number and not lo <= value <= hi:  # NaN and infinity too
        raise field_error(source, where, f"must be {lo} to {hi} {unit}, got {value!r}")
    if not is_number or not isinstance(value, int):
        raise field_error(source, where, f"expected a whole number of {unit} in {lo} to {hi}, got {value!r}")
    return value


def checked_numbers(raw: dict, ranges: dict, source: str, where: str, *, whole: bool = False) -> dict:
    """The entries of ``raw`` that ``ranges`` names (``{key: (unit, lowest, highest)}``), each checked."""
    check = whole_number if whole else number
    return {key: check(raw[key], source, f"{where}.{key}", unit, lo=lo, hi=hi)
            for key, (unit, lo, hi) in ranges.items() if key in raw}


def seed_pair(value: Any, source: str, where: str) -> tuple[int, int]:
    """Two different seeds in 0..MAX_CAMPAIGN_SEED (the ground truth twice: its noise floor)."""
    if not (isinstance(value, list) and len(value) == 2):
        raise field_error(source, where, f"need two different integer seeds (for the noise floor), got {value!r}")
    seeds = tuple(whole_number(s, source, f"{where}[{i}]", "(a seed)", lo=0, hi=MAX_CAMPAIGN_SEED)
                  for i, s in enumerate(value))
    if seeds[0] == seeds[1]:
        raise field_error(source, where, f"need two different integer seeds (for the noise floor), got {value!r}")
    return seeds  # type: ignore[return-value]


def text(value: Any, source: str, where: str) -> str:
    if not isinstance(value, str):
        raise field_error(source, where, f"expected a string, got {value!r}")
    return value


def description_text(value: Any, source: str, where: str) -> str:
    """A campaign description: a string of at most `vissim.checks.MAX_DESCRIPTION_CHARS`."""
    if len(text(value, source, where)) > MAX_DESCRIPTION_CHARS:
        raise field_error(source, where, f"a description is at most {MAX_DESCRIPTION_CHARS} characters, got {len(value)}")
    return value


def name_text(value: Any, source: str, where: str) -> str:
    """A campaign or configuration name: a string within `vissim.checks.MAX_NAME_CHARS`, printable."""
    problem = name_problem(text(value, source, where))
    if problem:
        raise field_error(source, where, problem)
    return value


def table(value: Any, source: str, where: str) -> dict:
    if not isinstance(value, dict):
        raise field_error(source, where, f"must be a table, got {value!r}")
    return value


def tables(doc: dict, key: str, source: str) -> list[dict]:
    """``[[key]]`` entries: a list of tables (``[key]``, a single table, is refused with a hint)."""
    value = doc.get(key, [])
    if not isinstance(value, list):
        raise field_error(source, key, f"write [[{key}]] (an array of tables), not [{key}] or {key} = ...")
    return [table(v, source, f"{key}[{i}]") for i, v in enumerate(value)]


def value_list(value: Any, source: str, where: str, example: str) -> list:
    """A non-empty list, e.g. a sweep's ``letters``."""
    if not isinstance(value, list) or not value:
        raise field_error(source, where, f"must be a non-empty list, e.g. {example}; got {value!r}")
    return value


def choices(value: Any, allowed: tuple[str, ...], source: str, where: str) -> tuple[str, ...]:
    """A non-empty list of distinct names from ``allowed``."""
    ok = isinstance(value, list) and value and all(isinstance(v, str) and v in allowed for v in value)
    if not ok:
        raise field_error(source, where, f"choose from {', '.join(allowed)} (a list); got {value!r}")
    if len(set(value)) != len(value):
        raise field_error(source, where, f"lists a name twice: {value!r}")
    return tuple(value)


def settings_kwargs(head: dict, settings_class, source: str, where: str, *, numbers: dict, whole_numbers: dict,
                    lists: dict, texts: tuple[str, ...], switches: tuple[str, ...] = (),
                    read_elsewhere: tuple[str, ...] = ()) -> dict:
    """Checked fields of ``settings_class`` found in a campaign's settings table ``head`` (named ``where``).

    ``numbers`` and ``whole_numbers`` as `checked_numbers`, ``seeds`` by `seed_pair`,
    ``lists`` (``{key: allowed names}``) by `choices`, ``switches`` must be true or false;
    ``texts`` must be strings and, like ``read_elsewhere``, are no fields; any other key is refused.
    """
    known = {f.name for f in fields(settings_class)}
    refuse_unknown_keys({k: v for k, v in head.items() if k not in texts}, sorted(known | set(read_elsewhere)), source,
                        f"[{where}]", "setting")
    kwargs = checked_numbers(head, numbers, source, where)
    kwargs |= checked_numbers(head, whole_numbers, source, where, whole=True)
    if "seeds" in head:
        kwargs["seeds"] = seed_pair(head["seeds"], source, f"{where}.seeds")
    for key, allowed in lists.items():
        if key in head:
            kwargs[key] = choices(head[key], allowed, source, f"{where}.{key}")
    for key in texts:
        if key in head:
            {"name": name_text, "description": description_text}.get(key, text)(head[key], source, f"{where}.{key}")
    for key in switches:
        if key in head:
            if not isinstance(head[key], bool):
                raise field_error(source, f"{where}.{key}", f"must be true or false, got {head[key]!r}")
            kwargs[key] = head[key]
    return kwargs


@dataclass(frozen=True)
class LensSpec:
    """One trial lens in the holder (thin lens powers; TABO axis)."""

    sphere_diopters: float = 0.0
    cylinder_diopters: float = 0.0
    axis_deg: float = 180.0

    def label(self) -> str:
        """The lens's power as this project writes every power: minus cylinder, the sphere's sign shown
        (``+1.00 DS``, ``+2.00 -2.00 x 180`` for a +2.00 cylinder at 90, ``plano -1.00 x 90``)."""
        from vissim.optics.rx.prescription import Prescription

        return Prescription(self.sphere_diopters, self.cylinder_diopters, self.axis_deg).minus_cylinder().format()


#: A trial lens's keys in a campaign file, as in every scene file (`vissim.bench.scene_toml`).
LENS_KEYS = ("sphere_diopters", "cylinder_diopters", "axis_deg")


def lens(entry: Any, source: str, where: str) -> LensSpec:
    """One trial lens: a number (sphere, D) or a table {sphere_diopters, cylinder_diopters, axis_deg}."""
    limit = dict(zip(("lo", "hi"), TRIAL_LENS_RANGE_DIOPTERS))
    if isinstance(entry, (int, float)) and not isinstance(entry, bool):
        return LensSpec(number(entry, source, where, "dioptres", **limit))
    if not isinstance(entry, dict):
        raise field_error(source, where, f"a lens is a number (sphere, D) or a table {{{', '.join(LENS_KEYS)}}}, "
                                         f"got {entry!r}")
    refuse_unknown_keys(entry, LENS_KEYS, source, where, "lens field")
    cyl = number(entry.get("cylinder_diopters", 0.0), source, f"{where}.cylinder_diopters", "dioptres", **limit)
    if cyl != 0 and "axis_deg" not in entry:
        raise field_error(source, where, "a cylinder needs axis_deg, its axis in degrees (TABO)")
    low, high = AXIS_RANGE_DEG
    axis = number(entry.get("axis_deg", 180.0), source, f"{where}.axis_deg", "degrees", lo=low, hi=high)
    sphere = number(entry.get("sphere_diopters", 0.0), source, f"{where}.sphere_diopters", "dioptres", **limit)
    return LensSpec(sphere, cyl, axis if cyl else 180.0)


def lenses(value: Any, source: str, where: str) -> tuple[LensSpec, ...]:
    """Up to `MAX_LENSES_IN_HOLDER` lenses in the holder (plano lenses dropped)."""
    entries = value if isinstance(value, list) else [value]
    if len(entries) > MAX_LENSES_IN_HOLDER:
        raise field_error(source, where, f"the holder takes at most {MAX_LENSES_IN_HOLDER} lenses, got {len(entries)}")
    specs = tuple(lens(e, source, f"{where}[{i}]") for i, e in enumerate(entries))
    return tuple(s for s in specs if (s.sphere_diopters, s.cylinder_diopters) != (0.0, 0.0))
