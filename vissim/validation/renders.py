"""Bench renders a campaign needs, keyed by their inputs so they are made once and reused."""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass

import numpy as np

from vissim.bench.lens_mesh import realistic_center_thickness_mm
from vissim.trial_lens import TrialLens
from vissim.validation.campaign import CampaignSettings, Configuration

__all__ = ["RenderSpec", "bench_lenses", "truth_specs", "no_lens_spec", "render_spec", "BENCH_CLEAR_APERTURE_MM"]

#: Clear aperture of the trial lenses (mm): larger than the 3.6 mm beam plus the field.
BENCH_CLEAR_APERTURE_MM = 20.0


def bench_lenses(configuration: Configuration, settings: CampaignSettings) -> tuple[TrialLens, ...]:
    """The trial lenses the bench holds (thick, realistic thickness) and the simulations assume."""
    lenses = []
    for spec in configuration.lenses:
        if settings.thick_lenses:
            thin = TrialLens(spec.sphere_diopters, spec.cylinder_diopters, spec.axis_deg)
            thickness = realistic_center_thickness_mm(thin, BENCH_CLEAR_APERTURE_MM, settings.refractive_index)
            lenses.append(
                TrialLens(spec.sphere_diopters, spec.cylinder_diopters, spec.axis_deg,
                          refractive_index=settings.refractive_index, center_thickness_mm=thickness)
            )
        else:
            lenses.append(TrialLens(spec.sphere_diopters, spec.cylinder_diopters, spec.axis_deg))
    return tuple(lenses)


@dataclass(frozen=True)
class RenderSpec:
    """Everything one bench render depends on."""

    letter: str
    logmar: float
    polarity: str
    lenses: tuple[TrialLens, ...]
    f_number: float
    focal_length_mm: float
    chart_distance_m: float
    vertex_distance_mm: float
    arcmin_per_px: float
    tile_px: tuple[int, int]
    spp: int
    seed: int

    @property
    def key(self) -> str:
        text = json.dumps(asdict(self), sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def as_json(self) -> dict:
        return json.loads(json.dumps(asdict(self), default=str))


def _spec(configuration: Configuration, settings: CampaignSettings, lenses, seed: int) -> RenderSpec:
    return RenderSpec(
        letter=configuration.letter,
        logmar=configuration.logmar,
        polarity=configuration.polarity,
        lenses=lenses,
        f_number=configuration.f_number,
        focal_length_mm=settings.focal_length_mm,
        chart_distance_m=settings.chart_distance_m,
        vertex_distance_mm=settings.vertex_distance_mm,
        arcmin_per_px=settings.arcmin_per_px,
        tile_px=tuple(settings.tile_px),
        spp=settings.spp,
        seed=seed,
    )


def truth_specs(configuration: Configuration, settings: CampaignSettings) -> tuple[RenderSpec, RenderSpec]:
    """The ground truth rendered twice (two seeds) for its noise floor."""
    lenses = bench_lenses(configuration, settings)
    return tuple(_spec(configuration, settings, lenses, seed) for seed in settings.seeds)  # type: ignore[return-value]


def no_lens_spec(configuration: Configuration, settings: CampaignSettings) -> RenderSpec:
    """The bench without trial lenses: the thesis's simulation input (a third seed)."""
    return _spec(configuration, settings, (), settings.seeds[0] + settings.seeds[1] + 1)


def render_spec(spec: RenderSpec) -> np.ndarray:
    """Render one spec on this machine (a worker process or a Dask worker): float32 (H, W)."""
    from vissim.render.run import render_tile  # the Mitsuba door, imported where it runs

    return render_tile(spec)
