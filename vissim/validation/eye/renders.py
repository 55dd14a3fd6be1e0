"""The eye bench's renders: `vissim.render.eye_render.render_eye` of a configuration, and the lens it renders."""

from __future__ import annotations

import math
from dataclasses import dataclass, asdict
from typing import ClassVar

from vissim.render.eye_render import EyeRender, eye_bench, eye_chart

__all__ = ["EyeSpec", "EyeBuilt", "build_bench", "eye_render_settings", "chart_half_arcmin", "spec"]


@dataclass(frozen=True)
class EyeSpec:
    """One render: the configuration's `EyeRender` fields (a plain, picklable record)."""

    kind: ClassVar[str] = "eye"
    fields: tuple  # sorted (name, value) pairs of EyeRender

    def as_json(self) -> dict:
        record = dict(self.fields)
        if not record.get("surfaces"):  # the model's own surfaces: the key such a render always had
            record.pop("surfaces", None)
        return record

    def settings(self) -> EyeRender:
        return EyeRender(**dict(self.fields))


def eye_render_settings(configuration, spp: int, seed: int) -> EyeRender:
    """The `EyeRender` of one configuration at ``spp`` and ``seed``."""
    c = configuration
    return EyeRender(model=c.model, accommodation_diopters=c.accommodation_diopters, pupil_mm=c.pupil_mm,
                     field_deg=tuple(c.field_deg), wavelength_nm=c.wavelength_nm, spectrum=c.spectrum,
                     size_px=tuple(c.size_px), arcmin_per_px=c.arcmin_per_px, spp=spp, seed=seed,
                     chart_distance_m=c.chart_distance_m, letter=c.letter, logmar=c.logmar,
                     lens=None if c.lens is None else tuple(c.lens), vertex_mm=c.vertex_mm, rx=c.rx,
                     surfaces=tuple(c.surfaces))


def spec(configuration, spp: int, seed: int) -> EyeSpec:
    settings = eye_render_settings(configuration, spp, seed)
    return EyeSpec(tuple(sorted((k, v) for k, v in asdict(settings).items())))


@dataclass(frozen=True)
class EyeBuilt:
    """What the simulations need of the rendered scene: the trial lens as meshed (thick; None: no lens) and
    the chart texture's half size (rows, columns) in arcmin: beyond it the scene is black."""

    lens: object
    chart_half_arcmin: tuple[float, float]


def build_bench(configuration, settings) -> EyeBuilt:
    render = eye_render_settings(configuration, settings.spp, settings.seeds[0])
    bench = eye_bench(render)
    return EyeBuilt(bench.physical_lenses[0] if bench.lenses else None, chart_half_arcmin(render, bench))


def chart_half_arcmin(settings: EyeRender, bench) -> tuple[float, float]:
    """The chart texture's half size, arcmin (rows, columns), as `render_eye` lays it (`dslr_scene`'s rule)."""
    from vissim.bench.dslr.bench import chart_texture_shape

    chart = eye_chart(settings, bench)
    shape = chart_texture_shape(bench, bench.viewing_setup(), chart.mm_per_px)
    distance_mm = 1000.0 * settings.chart_distance_m
    return tuple(60.0 * math.degrees(math.atan(0.5 * n * chart.mm_per_px / distance_mm)) for n in shape)
