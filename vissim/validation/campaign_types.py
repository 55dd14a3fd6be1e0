"""What a single-plane campaign is: its settings, its configurations, and an item's key.

The TOML loader (`vissim.validation.campaign`) builds these; the harness's modules
(simulations, renders, items, the runner) take them, without importing the loader.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass

from vissim.checks import DEFAULT_WAVELENGTH_NM
from vissim.optics.psf import SIMULATOR_REVISION
from vissim.optics.trial_lens import CROWN_GLASS_INDEX
from vissim.thesis import THESIS_CHART_DISTANCE_MM, THESIS_F_NUMBER, THESIS_FOCAL_LENGTH_MM, THESIS_VERTEX_DISTANCE_MM
from vissim.units import mm_to_m
from vissim.validation.fields import LensSpec

__all__ = ["Configuration", "CampaignSettings", "Campaign", "SIMULATIONS", "INPUTS", "SCHEMA_VERSION"]

#: Simulations a campaign may ask for (see vissim.validation.simulate.SIMULATION_PARTS).
SIMULATIONS = ("wave", "geometric", "thesis", "thesis_power", "thesis_pupil", "no_magnification")
#: Inputs the simulations are applied to: the bench's no-lens render, or the synthetic chart.
INPUTS = ("render", "synthetic")
#: Bumped when the meaning of an item's inputs or results changes, so old results are not reused
#: (2: the geometric self-check's row, and synthetic inputs aligned on the fine grid; 3: the
#: prescription fit of each capture, ``fit_rx``).
SCHEMA_VERSION = 3


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
    group: str = ""  # the report's group: its sweep's name, or its own name (empty: its own name)

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
    chart_distance_m: float = mm_to_m(THESIS_CHART_DISTANCE_MM)
    vertex_distance_mm: float = THESIS_VERTEX_DISTANCE_MM
    wavelength_nm: float = DEFAULT_WAVELENGTH_NM
    refractive_index: float = CROWN_GLASS_INDEX
    simulations: tuple[str, ...] = ("wave", "geometric", "thesis")
    inputs: tuple[str, ...] = INPUTS
    data_range: float = 1.0  # linear reflectance units: what SSIM/PSNR call the peak
    wave_truth: bool = True  # the wave bench (traced lenses' wave PSF) as a second truth, and the geometric
    # self-check (the traced lenses' ray PSF against the render; validation.wave_bench)
    fit_rx: bool = False  # fit the refraction each capture with lenses shows (vissim.fit), beside vergence theory


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
        payload = {"schema": SCHEMA_VERSION, "simulator": SIMULATOR_REVISION, "settings": asdict(self.settings),
                   "configuration": configuration.as_json()}
        payload["configuration"].pop("name")
        payload["configuration"].pop("group")  # names and groups label results; they do not change them
        text = json.dumps(payload, sort_keys=True, default=list)
        return hashlib.sha256(text.encode()).hexdigest()[:16]
