"""The DSLR bench as a bench kind of the validation engine (``kind = "dslr"``, the default).

A configuration is a letter behind trial lenses on the thesis's DSLR bench
(`vissim.validation.dslr.schema`); its truth is the bench rendered at two seeds, or a real
capture from the campaign's manifest (`vissim.validation.dslr.captures`).
"""

from __future__ import annotations

from pathlib import Path

from vissim.validation.dslr.loader import read_dslr_part
from vissim.validation.dslr.renders import build_dslr, no_lens_spec, render_dslr_spec, truth_specs
from vissim.validation.engine.protocol import Campaign, ItemPlan

__all__ = ["BENCH", "DslrKind"]

ROLES = ("truth_a", "truth_b", "no_lens")


class DslrKind:
    """The `vissim.validation.engine.protocol.BenchKind` of the DSLR bench."""

    name = "dslr"
    tables = ("item", "sweep")
    items_on_threads = True
    #: What the campaign's helper process imports ahead (its items' libraries among them, 1-2 s): it computes
    #: items and draws the report's figures.
    helper_modules = ("vissim.validation.dslr.item", "vissim.validation.dslr.report", "scipy.ndimage",
                      "scipy.interpolate", "scipy.optimize", "skimage.metrics", "skimage.registration")

    def read(self, doc: dict, head: dict, path: Path):
        return read_dslr_part(doc, head, path)

    def build(self, configuration, settings):
        return build_dslr(configuration, settings)

    def check_memory(self, campaign: Campaign) -> None:
        from vissim.validation.dslr.preflight import check_campaign_memory

        check_campaign_memory(campaign)

    def plan_items(self, campaign: Campaign, todo: list[tuple[str, int]]) -> tuple[dict[str, ItemPlan], list[str]]:
        """Rendered items: the truth at two seeds and the no-lens render; captured ones: their tiles, read now."""
        from vissim.validation.dslr.capture_plans import capture_item_plans

        rendered = [(k, i) for k, i in todo if not campaign.configurations[i].capture]
        plans, skipped = capture_item_plans(campaign, [(k, i) for k, i in todo if campaign.configurations[i].capture])
        for key, index in rendered:
            built = campaign.built[index]
            specs = (*truth_specs(built, campaign.settings), no_lens_spec(built, campaign.settings))
            plans[key] = ItemPlan(renders=dict(zip(ROLES, specs)), source={"ground_truth": "bench render"})
        return plans, skipped

    def render(self, spec):
        return render_dslr_spec(spec)

    def compute_item(self, key: str, campaign: Campaign, index: int, images: dict, plan: ItemPlan,
                     render_provenance: dict, item_dir: Path) -> dict:
        from vissim.validation.engine.renders import spec_key
        from vissim.validation.dslr.item import compute_item

        source = dict(plan.source)
        if plan.renders:
            source["render_keys"] = [spec_key(spec) for spec in plan.renders.values()]
        return compute_item(key, campaign.built[index], campaign.settings, images["truth_a"], images.get("truth_b"),
                            images["no_lens"], item_dir, source=source, render_provenance=render_provenance)

    def input_files(self, record: dict) -> list[Path]:
        """The manifest and, when a configuration names a capture, every capture file it lists."""
        manifest = record.get("manifest")
        if manifest is None:
            return []
        files = [Path(manifest)]
        if Path(manifest).is_file() and any(c.get("capture") for c in record.get("configurations", [])):
            from vissim.validation.dslr.captures import load_manifest

            files += [capture.file for capture in load_manifest(manifest).values()]
        return files

    def report(self, results: list[dict], run_dir: Path, record: dict, progress=None):
        from vissim.validation.dslr.report import dslr_report

        return dslr_report(results, run_dir, record, progress)

    def summary_lines(self, rows: list[dict]) -> list[str]:
        from vissim.validation.dslr.report import summary_lines

        return summary_lines(rows)


BENCH = DslrKind()
