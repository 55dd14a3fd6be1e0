"""Validation campaigns as TOML files: settings plus a list of configurations.

A campaign file has a ``[campaign]`` table of settings shared by every configuration, and
configurations given one by one (``[[item]]``) or as sweeps (``[[sweep]]``, the product of its
lists).  See ``validation/quick.toml`` for a commented example.  Every field is validated
with a message naming the file, the field and its unit.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import tomllib
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

from vissim.trial_lens import (
    CROWN_GLASS_INDEX,
    THESIS_CHART_DISTANCE_MM,
    THESIS_F_NUMBER,
    THESIS_FOCAL_LENGTH_MM,
    THESIS_VERTEX_DISTANCE_MM,
)
from vissim.errors import VissimInputError
from vissim.optotypes import SLOAN_LETTERS

__all__ = ["LensSpec", "Configuration", "CampaignSettings", "Campaign", "load_campaign", "SIMULATIONS", "INPUTS"]

#: Simulations a campaign may ask for (see vissim.validation.simulate.SIMULATION_PARTS).
SIMULATIONS = ("wave", "geometric", "thesis", "thesis_power", "thesis_pupil", "no_magnification")
#: Inputs the simulations are applied to: the bench's no-lens render, or the synthetic chart.
INPUTS = ("render", "synthetic")
POLARITIES = ("black-on-white", "white-on-black")
#: Bumped when the meaning of an item's inputs changes, so old results are not reused.
SCHEMA_VERSION = 1


@dataclass(frozen=True)
class LensSpec:
    """One trial lens in the holder (thin lens powers; TABO axis)."""

    sphere_diopters: float = 0.0
    cylinder_diopters: float = 0.0
    axis_deg: float = 180.0

    def label(self) -> str:
        if self.cylinder_diopters == 0:
            return f"{self.sphere_diopters:+.2f} DS"
        if self.sphere_diopters == 0:
            return f"{self.cylinder_diopters:+.2f} DC x {self.axis_deg:g}"
        return f"{self.sphere_diopters:+.2f} {self.cylinder_diopters:+.2f} x {self.axis_deg:g}"


@dataclass(frozen=True)
class Configuration:
    """One comparison: a letter on the bench behind some trial lenses."""

    name: str
    letter: str
    logmar: float
    polarity: str = "black-on-white"
    lenses: tuple[LensSpec, ...] = ()
    f_number: float = THESIS_F_NUMBER
    capture: str | None = None  # id of a real RAW capture in the manifest, if any

    def lens_label(self) -> str:
        return " + ".join(l.label() for l in self.lenses) if self.lenses else "no lens"

    def as_json(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class CampaignSettings:
    spp: int = 256
    seeds: tuple[int, int] = (1, 2)
    arcmin_per_px: float = 1.0
    tile_px: tuple[int, int] = (133, 113)  # rows, cols (errata item 8)
    focal_length_mm: float = THESIS_FOCAL_LENGTH_MM
    chart_distance_m: float = THESIS_CHART_DISTANCE_MM / 1000.0
    vertex_distance_mm: float = THESIS_VERTEX_DISTANCE_MM
    wavelength_nm: float = 550.0
    refractive_index: float = CROWN_GLASS_INDEX
    simulations: tuple[str, ...] = ("wave", "geometric", "thesis")
    inputs: tuple[str, ...] = INPUTS
    data_range: float = 1.0  # linear reflectance units: what SSIM/PSNR call the peak


@dataclass(frozen=True)
class Campaign:
    name: str
    description: str
    settings: CampaignSettings
    configurations: tuple[Configuration, ...]
    source: str = ""
    manifest: str | None = None

    def item_key(self, configuration: Configuration) -> str:
        """Stable key of one item's inputs: equal inputs, equal key (results are reused)."""
        payload = {"schema": SCHEMA_VERSION, "settings": asdict(self.settings), "configuration": configuration.as_json()}
        payload["configuration"].pop("name")
        text = json.dumps(payload, sort_keys=True, default=list)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def _err(source: str, where: str, message: str) -> VissimInputError:
    return VissimInputError(f"{source}: {where}: {message}")


def _float(value: Any, source: str, where: str, unit: str, *, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise _err(source, where, f"expected a number in {unit}, got {value!r}")
    if positive and value <= 0:
        raise _err(source, where, f"must be > 0 {unit}, got {value!r}")
    return float(value)


def _lens(entry: Any, source: str, where: str) -> LensSpec:
    if isinstance(entry, (int, float)) and not isinstance(entry, bool):
        return LensSpec(_float(entry, source, where, "dioptres"))
    if not isinstance(entry, dict):
        raise _err(source, where, f"a lens is a number (sphere, D) or a table {{sphere, cylinder, axis}}, got {entry!r}")
    unknown = set(entry) - {"sphere", "cylinder", "axis"}
    if unknown:
        raise _err(source, where, f"unknown lens field(s) {sorted(unknown)}; use sphere, cylinder, axis")
    cyl = _float(entry.get("cylinder", 0.0), source, f"{where}.cylinder", "dioptres")
    if cyl != 0 and "axis" not in entry:
        raise _err(source, where, "a cylinder needs an axis in degrees (TABO)")
    axis = _float(entry.get("axis", 180.0), source, f"{where}.axis", "degrees")
    if not 0 <= axis <= 180:
        raise _err(source, f"{where}.axis", f"must be within 0-180 degrees, got {axis:g}")
    return LensSpec(_float(entry.get("sphere", 0.0), source, f"{where}.sphere", "dioptres"), cyl, axis if cyl else 180.0)


def _lenses(value: Any, source: str, where: str) -> tuple[LensSpec, ...]:
    entries = value if isinstance(value, list) else [value]
    if len(entries) > 3:
        raise _err(source, where, f"the holder takes at most 3 lenses, got {len(entries)}")
    lenses = tuple(_lens(e, source, f"{where}[{i}]") for i, e in enumerate(entries))
    return tuple(l for l in lenses if (l.sphere_diopters, l.cylinder_diopters) != (0.0, 0.0))


def _configuration(raw: dict, defaults: CampaignSettings, source: str, where: str, f_number: float) -> Configuration:
    unknown = set(raw) - {"name", "letter", "logmar", "polarity", "lenses", "f_number", "capture"}
    if unknown:
        raise _err(source, where, f"unknown field(s) {sorted(unknown)}")
    letter = str(raw.get("letter", "")).upper()
    if len(letter) != 1 or letter not in SLOAN_LETTERS:
        raise _err(source, f"{where}.letter", f"must be one of the Sloan letters {', '.join(SLOAN_LETTERS)}, got {raw.get('letter')!r}")
    polarity = raw.get("polarity", "black-on-white")
    if polarity not in POLARITIES:
        raise _err(source, f"{where}.polarity", f"must be {' or '.join(POLARITIES)}, got {polarity!r}")
    logmar = _float(raw.get("logmar", 1.0), source, f"{where}.logmar", "LogMAR")
    lenses = _lenses(raw.get("lenses", []), source, f"{where}.lenses")
    f_number = _float(raw.get("f_number", f_number), source, f"{where}.f_number", "(f-number)", positive=True)
    config = Configuration("", letter, logmar, polarity, lenses, f_number, raw.get("capture"))
    name = str(raw.get("name") or f"{letter} {logmar:+.1f} {polarity.split('-')[0]} {config.lens_label()}")
    return Configuration(name, letter, logmar, polarity, lenses, f_number, config.capture)


def _sweep(raw: dict, defaults: CampaignSettings, source: str, where: str, f_number: float) -> list[Configuration]:
    unknown = set(raw) - {"name", "letters", "logmars", "polarities", "lenses", "f_number", "spheres", "cylinders"}
    if unknown:
        raise _err(source, where, f"unknown field(s) {sorted(unknown)}")
    letters = raw.get("letters", ["N"])
    logmars = raw.get("logmars", [1.0])
    polarities = raw.get("polarities", ["black-on-white"])
    lens_sets: list[Any] = []
    lens_sets += [[{"sphere": s}] for s in raw.get("spheres", [])]
    lens_sets += [[c] for c in raw.get("cylinders", [])]
    lens_sets += list(raw.get("lenses", []))
    if not lens_sets:
        lens_sets = [[]]
    prefix = raw.get("name", "")
    out = []
    for letter, logmar, polarity, lenses in itertools.product(letters, logmars, polarities, lens_sets):
        item = {"letter": letter, "logmar": logmar, "polarity": polarity, "lenses": lenses, "f_number": raw.get("f_number", f_number)}
        config = _configuration(item, defaults, source, where, f_number)
        label = f"{prefix}: {config.name}" if prefix else config.name
        out.append(Configuration(label, *[getattr(config, f.name) for f in fields(Configuration)][1:]))
    return out


def _settings(raw: dict, source: str) -> CampaignSettings:
    known = {f.name for f in fields(CampaignSettings)}
    unknown = set(raw) - known - {"name", "description", "f_number", "manifest"}
    if unknown:
        raise _err(source, "[campaign]", f"unknown setting(s) {sorted(unknown)}; known: {sorted(known)}")
    kwargs: dict[str, Any] = {}
    for key in ("arcmin_per_px", "focal_length_mm", "chart_distance_m", "vertex_distance_mm", "wavelength_nm", "refractive_index", "data_range"):
        if key in raw:
            kwargs[key] = _float(raw[key], source, f"campaign.{key}", key.rsplit("_", 1)[-1], positive=True)
    if "spp" in raw:
        if not isinstance(raw["spp"], int) or raw["spp"] < 1:
            raise _err(source, "campaign.spp", f"samples per pixel must be a positive integer, got {raw['spp']!r}")
        kwargs["spp"] = raw["spp"]
    if "seeds" in raw:
        seeds = raw["seeds"]
        if not (isinstance(seeds, list) and len(seeds) == 2 and all(isinstance(s, int) for s in seeds) and seeds[0] != seeds[1]):
            raise _err(source, "campaign.seeds", f"need two different integer seeds (for the noise floor), got {seeds!r}")
        kwargs["seeds"] = tuple(seeds)
    if "tile_px" in raw:
        tile = raw["tile_px"]
        if not (isinstance(tile, list) and len(tile) == 2 and all(isinstance(t, int) and t >= 16 for t in tile)):
            raise _err(source, "campaign.tile_px", f"need [rows, cols] in pixels (>= 16), got {tile!r}")
        kwargs["tile_px"] = tuple(tile)
    for key, allowed in (("simulations", SIMULATIONS), ("inputs", INPUTS)):
        if key in raw:
            values = tuple(raw[key])
            bad = [v for v in values if v not in allowed]
            if bad or not values:
                raise _err(source, f"campaign.{key}", f"choose from {', '.join(allowed)}; got {list(values)!r}")
            kwargs[key] = values
    return CampaignSettings(**kwargs)


def load_campaign(path: str | Path) -> Campaign:
    """Read and validate a campaign TOML file."""
    path = Path(path)
    source = str(path)
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise VissimInputError(f"campaign file {source} does not exist") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise VissimInputError(f"{source} is not valid TOML: {exc}") from None
    head = raw.get("campaign", {})
    settings = _settings(head, source)
    f_number = _float(head.get("f_number", 5.0), source, "campaign.f_number", "(f-number)", positive=True)
    configurations: list[Configuration] = []
    for i, item in enumerate(raw.get("item", [])):
        configurations.append(_configuration(item, settings, source, f"item[{i}]", f_number))
    for i, sweep in enumerate(raw.get("sweep", [])):
        configurations += _sweep(sweep, settings, source, f"sweep[{i}]", f_number)
    unknown = set(raw) - {"campaign", "item", "sweep"}
    if unknown:
        raise _err(source, "top level", f"unknown table(s) {sorted(unknown)}; use [campaign], [[item]], [[sweep]]")
    if not configurations:
        raise _err(source, "top level", "no configurations: add [[item]] or [[sweep]] tables")
    seen: dict[str, Configuration] = {}
    unique = []
    for c in configurations:  # the same inputs twice run once
        key = json.dumps({k: v for k, v in c.as_json().items() if k != "name"}, sort_keys=True, default=list)
        if key not in seen:
            seen[key] = c
            unique.append(c)
    manifest = head.get("manifest")
    if manifest is not None:
        manifest = str((path.parent / manifest).resolve())
    return Campaign(
        name=str(head.get("name", path.stem)),
        description=str(head.get("description", "")),
        settings=settings,
        configurations=tuple(unique),
        source=source,
        manifest=manifest,
    )
