"""What a DSLR campaign is: its settings and its configurations.

Its part of the campaign file is read by `vissim.validation.dslr.loader`; the bench kind
(`vissim.validation.dslr.kind`) builds each configuration once.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from vissim.checks import DEFAULT_WAVELENGTH_NM
from vissim.optics.rx.trial_lens import CROWN_GLASS_INDEX
from vissim.thesis import THESIS_CHART_DISTANCE_MM, THESIS_F_NUMBER, THESIS_FOCAL_LENGTH_MM, THESIS_VERTEX_DISTANCE_MM
from vissim.units import mm_to_m
from vissim.validation.engine.fields import LensSpec
from vissim.validation.engine.summary import NO_LENS

__all__ = ["Configuration", "CampaignSettings", "SIMULATIONS", "INPUTS", "trial_lens_phrase"]

#: Simulations a campaign may ask for (see vissim.validation.dslr.simulate.SIMULATION_PARTS).
SIMULATIONS = ("wave", "geometric", "thesis", "thesis_power", "thesis_pupil", "no_magnification")
#: Inputs the simulations are applied to: the bench's no-lens render, or the synthetic chart.
INPUTS = ("render", "synthetic")
#: Between the lenses of a set in a lens label: ``+1.00 DS + plano -0.50 x 30``.
LENS_JOINER = " + "


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
        return LENS_JOINER.join(l.label() for l in self.lenses) if self.lenses else NO_LENS

    def as_json(self) -> dict:
        return asdict(self)

    def key_inputs(self) -> dict:
        """What the item's results depend on: every field but the name and group, which label them."""
        return {"configuration": {k: v for k, v in self.as_json().items() if k not in ("name", "group")}}


def lens_label_of(result: dict) -> str:
    """An item's trial lenses as `Configuration.lens_label` writes them now (an item computed before keeps the label
    of its day in its ``lens_label``; its configuration's lenses are what count)."""
    lenses = (result.get("configuration") or {}).get("lenses")
    if lenses is None:
        return result.get("lens_label", NO_LENS)
    specs = [LensSpec(**lens) if isinstance(lens, dict) else LensSpec(*lens) for lens in lenses]
    return LENS_JOINER.join(spec.label() for spec in specs) if specs else NO_LENS


def trial_lens_phrase(lens_label: str) -> str:
    """A lens label (`Configuration.lens_label`) in words, as configuration names and figure headings say it:
    ``trial lens +2.00 DS``, ``trial lenses +1.00 DS + plano -0.50 x 30`` or ``no lens``."""
    if lens_label == NO_LENS:
        return NO_LENS
    return f"trial lens{'es' if LENS_JOINER in lens_label else ''} {lens_label}"


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
