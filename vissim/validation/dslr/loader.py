"""A DSLR campaign's part of the campaign file: its settings and configurations.

The ``[campaign]`` table holds settings shared by every configuration, and configurations are
given one by one (``[[item]]``) or as sweeps (``[[sweep]]``, the product of its lists).  See ``validation/quick.toml`` for a commented example.  Every field is validated
with a message naming the file, the field and its unit.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

from vissim.charts import POLARITIES
from vissim.checks import (ARCMIN_PER_PX_RANGE, DATA_RANGE_RANGE, F_NUMBER_RANGE, FOCAL_LENGTH_RANGE_MM, LOGMAR_RANGE,
                           OBJECT_DISTANCE_RANGE_M, REFRACTIVE_INDEX_RANGE, TILE_RANGE_PX, VERTEX_DISTANCE_RANGE_MM,
                           WAVELENGTH_RANGE_NM)
from vissim.optotypes import SLOAN_LETTERS
from vissim.validation.dslr.schema import INPUTS, SIMULATIONS, CampaignSettings, Configuration, trial_lens_phrase
from vissim.validation.engine.configurations import refuse_duplicate_names, sweep_combinations
from vissim.validation.engine.fields import (
    MAX_SPP,
    field_error,
    lenses,
    name_text,
    number,
    settings_kwargs,
    tables,
    text,
    refuse_unknown_keys,
    value_list,
    whole_number,
)

__all__ = ["read_dslr_part"]

#: [campaign] numbers: (unit, lowest, highest), the ranges of `vissim.checks`.
NUMBER_SETTINGS = {
    "arcmin_per_px": ("arcmin/px", *ARCMIN_PER_PX_RANGE),
    "focal_length_mm": ("mm", *FOCAL_LENGTH_RANGE_MM),
    "chart_distance_m": ("m", *OBJECT_DISTANCE_RANGE_M),
    "vertex_distance_mm": ("mm", *VERTEX_DISTANCE_RANGE_MM),
    "wavelength_nm": ("nm", *WAVELENGTH_RANGE_NM),
    "refractive_index": ("(refractive index)", *REFRACTIVE_INDEX_RANGE),
    "data_range": ("(linear reflectance)", *DATA_RANGE_RANGE),
}
#: Sloan letters are 5 strokes tall: 5 arcmin at LogMAR 0.
LETTER_ARCMIN_AT_LOGMAR_0 = 5.0


def _f_number(value: Any, source: str, where: str) -> float:
    return number(value, source, where, "(f-number)", lo=F_NUMBER_RANGE[0], hi=F_NUMBER_RANGE[1])


def _configuration(raw: dict, settings: CampaignSettings, source: str, where: str, f_number: float) -> Configuration:
    refuse_unknown_keys(raw, ITEM_KEYS, source, where, "field")
    letter = raw.get("letter")
    if not isinstance(letter, str) or len(letter) != 1 or letter.upper() not in SLOAN_LETTERS:
        raise field_error(source, f"{where}.letter", f"must be one of the Sloan letters {', '.join(SLOAN_LETTERS)}, "
                                                     f"got {letter!r}")
    letter = letter.upper()
    polarity = raw.get("polarity", "black-on-white")
    if not isinstance(polarity, str) or polarity not in POLARITIES:
        raise field_error(source, f"{where}.polarity", f"must be {' or '.join(POLARITIES)}, got {polarity!r}")
    logmar = number(raw.get("logmar", 1.0), source, f"{where}.logmar", "LogMAR", lo=LOGMAR_RANGE[0], hi=LOGMAR_RANGE[1])
    letter_arcmin = LETTER_ARCMIN_AT_LOGMAR_0 * 10.0**logmar
    tile_arcmin = min(settings.tile_px) * settings.arcmin_per_px
    if letter_arcmin > tile_arcmin:
        raise field_error(source, f"{where}.logmar", f"a LogMAR {logmar:g} letter is {letter_arcmin:.3g} arcmin tall, "
                                                     f"more than the {tile_arcmin:.3g} arcmin tile; enlarge tile_px")
    specs = lenses(raw.get("lenses", []), source, f"{where}.lenses")
    f_number = _f_number(raw.get("f_number", f_number), source, f"{where}.f_number")
    capture, name = (None if raw.get(k) is None else check(raw[k], source, f"{where}.{k}")
                     for k, check in (("capture", text), ("name", name_text)))
    config = Configuration(name or "", letter, logmar, polarity, specs, f_number, capture)
    label = f"{letter} LogMAR {logmar:.1f} {polarity.split('-')[0]}, {trial_lens_phrase(config.lens_label())}"
    return replace(config, name=name or label, group=name or label)


def _describe(c: Configuration) -> str:
    """What a configuration compares, for messages: letter, LogMAR, polarity, lenses, f-number, capture."""
    capture = f", capture {c.capture}" if c.capture else ""
    return f"letter {c.letter}, LogMAR {c.logmar:g}, {c.polarity}, {c.lens_label()}, f/{c.f_number:g}{capture}"


#: Keys of an ``[[item]]`` and of a ``[[sweep]]`` (where a list sweeps ``letter``, ``logmar``, ``polarity``, one
#: ``lens`` per configuration and ``lenses``, a set per configuration).
ITEM_KEYS = ("name", "letter", "logmar", "polarity", "lenses", "f_number", "capture")
SWEEP_KEYS = ("name", "letter", "logmar", "polarity", "lens", "lenses", "f_number")


def _swept(value: Any, source: str, where: str, example: str) -> list:
    """A sweep's values: its list, or the one value it gives."""
    return value_list(value if isinstance(value, list) else [value], source, where, example)


def _sweep(raw: dict, settings: CampaignSettings, source: str, where: str, f_number: float) -> list[Configuration]:
    refuse_unknown_keys(raw, SWEEP_KEYS, source, where, "field")
    letters = _swept(raw.get("letter", ["N"]), source, f"{where}.letter", '["K", "N"]')
    logmars = _swept(raw.get("logmar", [1.0]), source, f"{where}.logmar", "[1.0, 0.5]")
    polarities = _swept(raw.get("polarity", ["black-on-white"]), source, f"{where}.polarity", '["black-on-white"]')
    lens_sets: list[Any] = []
    if "lens" in raw:  # one lens per configuration: a number (a sphere, D) or a lens table
        single = _swept(raw["lens"], source, f"{where}.lens", "[0.0, 2.0, { cylinder_diopters = 2.0, axis_deg = 90 }]")
        lens_sets += [[entry] for entry in single]
    if "lenses" in raw:
        lens_sets += list(value_list(raw["lenses"], source, f"{where}.lenses", "[[2.0], [1.0, -0.5]] (lens sets)"))
    prefix = name_text(raw["name"], source, f"{where}.name") if "name" in raw else ""
    out = []
    axes = {"letter": letters, "logmar": logmars, "polarity": polarities, "lenses": lens_sets or [[]]}
    for combination in sweep_combinations(axes, source, where):
        item = {**combination, "f_number": raw.get("f_number", f_number)}
        config = _configuration(item, settings, source, where, f_number)
        label = f"{prefix}: {config.name}" if prefix else config.name
        out.append(replace(config, name=label, group=prefix or label))
    return out


def _settings(raw: dict, source: str) -> CampaignSettings:
    kwargs = settings_kwargs(raw, CampaignSettings, source, "campaign", numbers=NUMBER_SETTINGS,
                             whole_numbers={"spp": ("samples per pixel", 1, MAX_SPP)},
                             lists={"simulations": SIMULATIONS, "inputs": INPUTS},
                             texts=("manifest",), switches=("wave_truth", "fit_rx"),
                             read_elsewhere=("f_number",))
    if "tile_px" in raw:
        tile, (low, high) = raw["tile_px"], TILE_RANGE_PX
        if not (isinstance(tile, list) and len(tile) == 2):
            raise field_error(source, "campaign.tile_px", f"need [rows, cols] in pixels (>= {low}), got {tile!r}")
        kwargs["tile_px"] = tuple(whole_number(t, source, f"campaign.tile_px[{i}]", "pixels", lo=low, hi=high)
                                  for i, t in enumerate(tile))
    return CampaignSettings(**kwargs)


def read_dslr_part(doc: dict, head: dict, path: Path) -> tuple[CampaignSettings, tuple[Configuration, ...], str | None]:
    """(settings, configurations, manifest) of a DSLR campaign: its ``[campaign]`` settings, ``[[item]]`` and ``[[sweep]]``.

    The same inputs given twice run once; two configurations with one name are refused.
    """
    source = str(path)
    settings = _settings(head, source)
    f_number = _f_number(head.get("f_number", 5.0), source, "campaign.f_number")
    configurations = [(f"item[{i}]", _configuration(item, settings, source, f"item[{i}]", f_number))
                      for i, item in enumerate(tables(doc, "item", source))]
    for i, sweep in enumerate(tables(doc, "sweep", source)):
        configurations += [(f"sweep[{i}] #{k + 1}", c)
                           for k, c in enumerate(_sweep(sweep, settings, source, f"sweep[{i}]", f_number))]
    unique: dict[str, tuple[str, Configuration]] = {}
    for where, c in configurations:  # the same inputs twice run once
        unique.setdefault(json.dumps(c.key_inputs(), sort_keys=True, default=list), (where, c))
    refuse_duplicate_names(source, unique.values(), _describe)
    manifest = head.get("manifest")
    if manifest is not None:
        manifest = str((path.parent / manifest).resolve())
    return settings, tuple(c for _, c in unique.values()), manifest