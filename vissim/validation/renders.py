"""Bench renders a campaign needs, keyed by their inputs so they are made once and reused."""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass

from vissim.bench.dslr.bench import DslrBench
from vissim.optics.trial_lens import TrialLens
from vissim.units import m_to_mm
from vissim.validation.campaign_types import CampaignSettings, Configuration

__all__ = ["RenderSpec", "bench_for", "campaign_bench", "bench_lenses", "truth_specs", "no_lens_spec", "render_spec"]


def _dslr_bench(grid, f_number: float, lenses: tuple[TrialLens, ...], **extra) -> DslrBench:
    """A bench focused on its chart; ``grid`` (campaign settings or a render spec) gives distances and sampling."""
    chart_distance_mm = m_to_mm(grid.chart_distance_m)
    return DslrBench(focal_length_mm=grid.focal_length_mm, f_number=f_number, focus_distance_mm=chart_distance_mm,
                     chart_distance_mm=chart_distance_mm, vertex_distance_mm=grid.vertex_distance_mm, lenses=lenses,
                     arcmin_per_px=grid.arcmin_per_px, size_px=tuple(grid.tile_px), **extra)


def campaign_bench(configuration: Configuration, settings: CampaignSettings) -> DslrBench:
    """The configuration's bench; its `viewing_setup` is what the simulations assume."""
    thin = tuple(TrialLens(l.sphere_diopters, l.cylinder_diopters, l.axis_deg) for l in configuration.lenses)
    return _dslr_bench(settings, configuration.f_number, thin, refractive_index=settings.refractive_index)


def bench_lenses(configuration: Configuration, settings: CampaignSettings) -> tuple[TrialLens, ...]:
    """The trial lenses as the bench renders them: crown glass, realistic thickness."""
    return campaign_bench(configuration, settings).physical_lenses


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
    return RenderSpec(letter=configuration.letter, logmar=configuration.logmar, polarity=configuration.polarity,
                      lenses=lenses, f_number=configuration.f_number, focal_length_mm=settings.focal_length_mm,
                      chart_distance_m=settings.chart_distance_m, vertex_distance_mm=settings.vertex_distance_mm,
                      arcmin_per_px=settings.arcmin_per_px, tile_px=tuple(settings.tile_px), spp=settings.spp,
                      seed=seed)


def truth_specs(configuration: Configuration, settings: CampaignSettings) -> tuple[RenderSpec, RenderSpec]:
    """The ground truth rendered twice (two seeds) for its noise floor."""
    lenses = bench_lenses(configuration, settings)
    return tuple(_spec(configuration, settings, lenses, seed) for seed in settings.seeds)  # type: ignore[return-value]


def no_lens_spec(configuration: Configuration, settings: CampaignSettings) -> RenderSpec:
    """The bench without trial lenses: the thesis's simulation input (a third seed)."""
    return _spec(configuration, settings, (), settings.seeds[0] + settings.seeds[1] + 1)


def bench_for(spec: RenderSpec) -> DslrBench:
    """The `DslrBench` that renders ``spec`` (its lenses are already physical)."""
    return _dslr_bench(spec, spec.f_number, spec.lenses, spp=spec.spp, seed=spec.seed)


def render_spec(spec: RenderSpec):
    """Render one spec with Mitsuba on this machine (a worker process or a Dask worker).

    Returns the `vissim.render.run.RenderResult`: float32 ``pixels``, ``variant``, ``spp``
    (taken) and ``provenance``, whose ``inputs.mitsuba_render`` records the spp asked and taken,
    variant, seeds, passes and determinism; the campaign runner writes it in the EXR header.
    """
    from vissim.charts import single_letter_spec
    from vissim.render.run import (
        render_bench,  # the Mitsuba door, imported where it runs
    )

    chart = single_letter_spec(spec.letter, spec.logmar, viewing_distance_m=spec.chart_distance_m, polarity=spec.polarity)
    return render_bench(bench_for(spec), chart)
