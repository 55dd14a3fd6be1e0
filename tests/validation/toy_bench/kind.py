"""The toy bench: a bright disc blurred by a Gaussian of a configured width, rendered with seeded noise.

Its simulation is the same Gaussian blur without noise, so it sits at the render's noise floor:
PSNR 3 dB over the floor's (MSE sigma^2 against 2 sigma^2), whatever the width.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
from scipy import ndimage

from vissim.atomic import write_json_atomic
from vissim.imaging.metrics import compare_images, noise_floor
from vissim.validation.engine.fields import number, settings_kwargs, tables
from vissim.validation.engine.figures import Figure
from vissim.validation.engine.item_files import save_item_image
from vissim.validation.engine.metrics import PSNR, floor_column
from vissim.validation.engine.protocol import ItemPlan, ReportParts
from vissim.validation.engine.summary import margin

SIZE_PX = 32
NOISE = 0.01


@dataclass(frozen=True)
class ToySettings:
    spp: int = 1  # unused; every kind's settings take --spp
    seeds: tuple[int, int] = (1, 2)


@dataclass(frozen=True)
class ToyConfiguration:
    name: str
    sigma_px: float

    def as_json(self) -> dict:
        return asdict(self)

    def key_inputs(self) -> dict:
        return {"sigma_px": self.sigma_px}


@dataclass(frozen=True)
class ToySpec:
    kind: ClassVar[str] = "toy"
    sigma_px: float
    seed: int

    def as_json(self) -> dict:
        return asdict(self)


def disc(sigma_px: float) -> np.ndarray:
    y, x = np.mgrid[:SIZE_PX, :SIZE_PX] - SIZE_PX / 2
    return ndimage.gaussian_filter((np.hypot(x, y) < 8).astype(np.float64), sigma_px)


class ToyKind:
    name = "toy"
    tables = ("disc",)

    def read(self, doc, head, path):
        source = str(path)
        settings = ToySettings(**settings_kwargs(head, ToySettings, source, "campaign", numbers={}, whole_numbers={},
                                                 lists={}, texts=()))
        configs = tuple(ToyConfiguration(str(t.get("name", f"disc {i}")),
                                         number(t.get("sigma_px", 1.0), source, f"disc[{i}].sigma_px", "px", lo=0.1,
                                                hi=8.0))
                        for i, t in enumerate(tables(doc, "disc", source)))
        return settings, configs, None

    def build(self, configuration, settings):
        return disc(configuration.sigma_px)  # the noise-free image: the simulation

    def check_memory(self, campaign):
        pass

    def plan_items(self, campaign, todo):
        return {key: ItemPlan(renders={f"truth_{i}": ToySpec(campaign.configurations[index].sigma_px, seed)
                                       for i, seed in enumerate(campaign.settings.seeds)})
                for key, index in todo}, []

    def render(self, spec):
        noise = np.random.default_rng(spec.seed).normal(0.0, NOISE, (SIZE_PX, SIZE_PX))
        return (disc(spec.sigma_px) + noise).astype(np.float32)

    def compute_item(self, key, campaign, index, images, plan, render_provenance, item_dir: Path):
        truth_a, truth_b = images["truth_0"], images["truth_1"]
        simulated = campaign.built[index]
        result = {"key": key, "configuration": campaign.configurations[index].as_json(),
                  "metrics": compare_images(truth_a, simulated, data_range=1.0).as_json(),
                  "noise_floor": noise_floor(truth_a, truth_b, 1.0).as_json(),
                  "images": {"simulation": save_item_image(item_dir, "simulation", simulated, {})}}
        write_json_atomic(item_dir / "result.json", result, overwrite=True)
        return result

    def input_files(self, record):
        return []

    def report(self, results, run_dir, record, progress=None):
        rows = [{"configuration": r["configuration"]["name"], PSNR.name: r["metrics"][PSNR.name],
                 floor_column(PSNR): r["noise_floor"][PSNR.name]} for r in results]
        table = "### toy\n\n| configuration | PSNR dB |\n|---|---|\n" + "".join(
            f"| {r['configuration']} | {r[PSNR.name]:.{PSNR.digits}f} |\n" for r in rows)
        return ReportParts("toy validation", rows, table, {})

    def summary_lines(self, rows):
        return [f"{r['configuration']}: {margin(r):+.2f} dB over the floor" for r in rows]


BENCH = ToyKind()
