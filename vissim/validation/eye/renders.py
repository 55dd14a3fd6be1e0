"""The eye bench a configuration is built into, once, and the renders its item needs.

`build_bench` builds the configuration's `vissim.bench.eye.bench.EyeBench` (its `Eye` the item's own,
`EyeConfiguration.eye`), its chart printed and its lens meshed then; each render's `EyeSpec` carries that
bench with a sample count and a seed, so a seed's worker builds neither again
(`vissim.render.eye_render.render_eye_bench`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from vissim.bench.eye.bench import EyeBench
from vissim.optics.rx.trial_lens import TrialLens

__all__ = ["EyeSpec", "EyeBuilt", "build_bench", "configuration_bench", "spec"]


@dataclass(frozen=True)
class EyeSpec:
    """One render: the configuration's bench, at ``spp`` samples per pixel from ``seed``."""

    kind: ClassVar[str] = "eye"
    bench: EyeBench
    spp: int
    seed: int

    def as_json(self) -> dict:
        return {**self.bench.as_json(), "spp": self.spp, "seed": self.seed}


@dataclass(frozen=True)
class EyeBuilt:
    """A configuration built once: its bench (the simulations read the rendered scene from it)."""

    bench: EyeBench


def configuration_bench(configuration) -> EyeBench:
    """The `EyeBench` of one configuration (`vissim.validation.eye.schema.EyeConfiguration`)."""
    c = configuration
    return EyeBench(eye=c.eye(), chart_distance_m=c.chart_distance_m, letter=c.letter, logmar=c.logmar,
                    lenses=() if c.lens is None else (TrialLens(*c.lens),), vertex_mm=c.vertex_mm,
                    field_deg=tuple(c.field_deg), size_px=tuple(c.size_px), arcmin_per_px=c.arcmin_per_px,
                    wavelength_nm=c.wavelength_nm, spectrum=c.spectrum)


def build_bench(configuration, settings) -> EyeBuilt:
    """The configuration's bench, its chart printed and its lens meshed now (carried to each render)."""
    bench = configuration_bench(configuration)
    bench.chart_half_arcmin  # noqa: B018 -- prints the chart and sizes its texture once, here
    bench.measured_phase  # noqa: B018 -- a measured eye's phase plane, fitted once, here
    return EyeBuilt(bench)


def spec(built: EyeBuilt, spp: int, seed: int) -> EyeSpec:
    """The render of ``built``'s bench at ``spp`` and ``seed``."""
    return EyeSpec(built.bench, int(spp), int(seed))
