"""The eye bench as a bench kind of the validation engine (``kind = "eye"``).

A configuration is a letter seen by a schematic eye through an optional trial lens
(`vissim.validation.eye.schema`), built once into its eye bench (`vissim.validation.eye.renders`).  Its
truth is that bench rendered (`vissim.render.eye_render.render_eye_bench`) at two seeds (their
difference: the render's noise floor); the simulations (`vissim.validation.eye.simulate`)
blur the chart and are scored against it.
"""

from __future__ import annotations

from pathlib import Path

from vissim.validation.engine.protocol import Campaign, ItemPlan

__all__ = ["BENCH", "EyeKind"]


class EyeKind:
    """The `vissim.validation.engine.protocol.BenchKind` of the eye bench."""

    name = "eye"
    tables = ("item", "sweep")
    items_on_threads = True

    def read(self, doc: dict, head: dict, path: Path):
        from vissim.validation.eye.schema import read_campaign

        settings, configurations = read_campaign(doc, head, str(path))
        return settings, configurations, None

    def build(self, configuration, settings):
        from vissim.validation.eye.renders import build_bench

        return build_bench(configuration, settings)

    def check_memory(self, campaign: Campaign) -> None:
        pass  # images of at most 512 x 512 pixels

    def plan_items(self, campaign: Campaign, todo: list[tuple[str, int]]) -> tuple[dict[str, ItemPlan], list[str]]:
        from vissim.validation.eye.renders import spec

        settings = campaign.settings
        return {key: ItemPlan(renders={f"truth_{i}": spec(campaign.built[index], settings.spp, seed)
                                       for i, seed in enumerate(settings.seeds)})
                for key, index in todo}, []

    def render(self, spec):
        from vissim.render.eye_render import render_eye_bench

        return render_eye_bench(spec.bench, spec.spp, spec.seed)

    def compute_item(self, key: str, campaign: Campaign, index: int, images: dict, plan: ItemPlan,
                     render_provenance: dict, item_dir: Path) -> dict:
        from vissim.validation.eye.item import compute_eye_item

        return compute_eye_item(key, campaign.configurations[index], campaign.settings, campaign.built[index],
                                images, item_dir, render_provenance)

    def input_files(self, record: dict) -> list[Path]:
        return []

    def report(self, results: list[dict], run_dir: Path, record: dict, progress=None):
        from vissim.validation.eye.report import eye_report

        return eye_report(results, run_dir, record)

    def summary_lines(self, rows: list[dict]) -> list[str]:
        from vissim.validation.eye.report import summary_lines

        return summary_lines(rows)


BENCH = EyeKind()
