"""The DSLR bench a configuration is built into, once, and the renders its item needs."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

from vissim.bench.dslr.bench import DslrBench
from vissim.optics.rx.viewing_setup import ViewingSetup
from vissim.optics.rx.trial_lens import TrialLens
from vissim.provenance import json_safe
from vissim.units import m_to_mm
from vissim.validation.dslr.schema import CampaignSettings, Configuration

__all__ = ["DslrBuilt", "RenderSpec", "build_dslr", "truth_specs", "no_lens_spec", "render_dslr_spec"]


@dataclass(frozen=True)
class DslrBuilt:
    """A configuration built once: its bench (the lenses as specified) and the viewing setup the simulations assume."""

    configuration: Configuration
    bench: DslrBench
    setup: ViewingSetup

    @property
    def lenses(self) -> tuple[TrialLens, ...]:
        """The trial lenses as the bench renders them: crown glass, realistic thickness."""
        return self.bench.physical_lenses


def build_dslr(configuration: Configuration, settings: CampaignSettings) -> DslrBuilt:
    """The configuration's bench, focused on its chart, and its `ViewingSetup` at the campaign's wavelength."""
    chart_distance_mm = m_to_mm(settings.chart_distance_m)
    thin = tuple(TrialLens(l.sphere_diopters, l.cylinder_diopters, l.axis_deg) for l in configuration.lenses)
    bench = DslrBench(focal_length_mm=settings.focal_length_mm, f_number=configuration.f_number,
                      focus_distance_mm=chart_distance_mm, chart_distance_mm=chart_distance_mm,
                      vertex_distance_mm=settings.vertex_distance_mm, lenses=thin,
                      refractive_index=settings.refractive_index, arcmin_per_px=settings.arcmin_per_px,
                      size_px=tuple(settings.tile_px))
    return DslrBuilt(configuration, bench, bench.viewing_setup(settings.wavelength_nm))


@dataclass(frozen=True)
class RenderSpec:
    """One bench render: the bench (its lenses physical, with its spp and seed) and the letter its chart shows."""

    kind: ClassVar[str] = "dslr"
    bench: DslrBench
    letter: str
    logmar: float
    polarity: str

    def as_json(self) -> dict:
        return json_safe(self)


def _spec(built: DslrBuilt, settings: CampaignSettings, lenses: tuple[TrialLens, ...], seed: int) -> RenderSpec:
    config = built.configuration
    return RenderSpec(replace(built.bench, lenses=lenses, spp=settings.spp, seed=seed), config.letter, config.logmar,
                      config.polarity)


def truth_specs(built: DslrBuilt, settings: CampaignSettings) -> tuple[RenderSpec, RenderSpec]:
    """The ground truth rendered twice (two seeds) for its noise floor."""
    return tuple(_spec(built, settings, built.lenses, seed) for seed in settings.seeds)  # type: ignore[return-value]


def no_lens_spec(built: DslrBuilt, settings: CampaignSettings) -> RenderSpec:
    """The bench without trial lenses: the thesis's simulation input (a third seed)."""
    return _spec(built, settings, (), settings.seeds[0] + settings.seeds[1] + 1)


def render_dslr_spec(spec: RenderSpec):
    """Render one spec with Mitsuba on this machine (a worker process or a Dask worker).

    Returns the `vissim.render.run.RenderResult`: float32 ``pixels``, ``variant``, ``spp``
    (taken) and ``provenance``, whose ``inputs.mitsuba_render`` records the spp asked and taken,
    variant, seeds, passes and determinism; the engine writes it in the EXR header.
    """
    from vissim.charts import single_letter_spec
    from vissim.render.run import render_bench  # the Mitsuba door, imported where it runs
    from vissim.units import mm_to_m

    chart = single_letter_spec(spec.letter, spec.logmar, viewing_distance_m=mm_to_m(spec.bench.chart_distance_mm),
                               polarity=spec.polarity)
    return render_bench(spec.bench, chart)
