"""The depth bench as a bench kind of the validation engine (``kind = "depth"``).

A configuration is a depth scene (`vissim.bench.depth.scene`) seen by an observer: an eye, the
DSLR, or the scene file's own (`vissim.validation.depth.schema`).  Its truth is the blurred view
rendered at two seeds; the simulations start from pinhole renders (`vissim.validation.depth.renders`).
"""

from __future__ import annotations

from pathlib import Path

from vissim.validation.depth.renders import build_depth, render_depth_spec, render_specs
from vissim.validation.depth.schema import read_depth_part
from vissim.validation.engine.protocol import Campaign, ItemPlan

__all__ = ["BENCH", "DepthKind"]


class DepthKind:
    """The `vissim.validation.engine.protocol.BenchKind` of the depth bench."""

    name = "depth"
    tables = ("config",)
    items_on_threads = False  # each item blurs its layers on every core, and its memory check is for one item

    def read(self, doc: dict, head: dict, path: Path):
        return read_depth_part(doc, head, path)

    def build(self, configuration, settings):
        return build_depth(configuration, settings)

    def check_memory(self, campaign: Campaign) -> None:
        from vissim.validation.depth.preflight import check_depth_campaign_memory

        check_depth_campaign_memory(campaign)

    def plan_items(self, campaign: Campaign, todo: list[tuple[str, int]]) -> tuple[dict[str, ItemPlan], list[str]]:
        plans = {key: ItemPlan(renders=render_specs(campaign.built[index], campaign.settings))
                 for key, index in todo}
        return plans, []

    def render(self, spec):
        return render_depth_spec(spec)

    def compute_item(self, key: str, campaign: Campaign, index: int, images: dict, plan: ItemPlan,
                     render_provenance: dict, item_dir: Path) -> dict:
        from vissim.validation.depth.item import compute_depth_item

        return compute_depth_item(key, campaign.built[index], campaign.settings, images, item_dir,
                                  render_provenance=render_provenance)

    def input_files(self, record: dict) -> list[Path]:
        """The scene file of every configuration."""
        return [Path(c["scene_file"]) for c in record.get("configurations", []) if c.get("scene_file")]

    def report(self, results: list[dict], run_dir: Path, record: dict, progress=None):
        from vissim.validation.depth.report import depth_report

        return depth_report(results, run_dir, record, progress)

    def summary_lines(self, rows: list[dict]) -> list[str]:
        from vissim.validation.depth.report import summary_lines

        return summary_lines(rows)


BENCH = DepthKind()
