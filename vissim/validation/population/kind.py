"""Populations of measured eyes as a campaign kind of the validation engine (``kind = "population"``).

A campaign names a dataset's eyes and the conditions they are crossed with (`vissim.validation.population.schema`);
each condition is one item: every eye evaluated under it (`evaluate_population`), spread over the run's
``--workers`` processes or its ``--scheduler`` (a Dask cluster), each task carrying only its eyes' names.  No
renders.  The report is the population's (`vissim.validation.population.report`): a row per eye and condition,
the gap table, the MTF fan chart, a letter through 16 eyes and, with three or more fields on the horizontal
meridian, peripheral astigmatism beside the schematic eyes.
"""

from __future__ import annotations

from pathlib import Path

from vissim.validation.engine.protocol import Campaign, ItemPlan

__all__ = ["BENCH", "PopulationKind"]


class PopulationKind:
    """The `vissim.validation.engine.protocol.BenchKind` of measured-eye populations."""

    name = "population"
    tables = ()
    items_on_threads = False  # each item spreads its eyes over --workers processes or a Dask cluster

    def read(self, doc: dict, head: dict, path: Path):
        from vissim.validation.population.schema import read_campaign

        settings, items = read_campaign(head, str(path))
        return settings, items, None

    def build(self, configuration, settings):
        return None  # nothing to render: the eyes are chosen once per run (`compute_item`)

    def check_memory(self, campaign: Campaign) -> None:
        pass  # a few numbers per eye

    def plan_items(self, campaign: Campaign, todo: list[tuple[str, int]]) -> tuple[dict[str, ItemPlan], list[str]]:
        return {key: ItemPlan() for key, _ in todo}, []

    def render(self, spec):
        raise NotImplementedError("a population campaign makes no renders")

    def compute_item(self, key: str, campaign: Campaign, index: int, images: dict, plan: ItemPlan,
                     render_provenance: dict, item_dir: Path) -> dict:
        from vissim.atomic import write_json_atomic
        from vissim.errors import VissimInputError
        from vissim.optics.eyes.measured.population import evaluate_population
        from vissim.validation.engine.scheduler import connect_scheduler

        settings, item = campaign.settings, campaign.configurations[index]
        eyes = settings.selected()
        if not eyes:
            raise VissimInputError(f"{campaign.source}: no eye of {settings.dataset} matches the selection given")
        client = None if campaign.scheduler is None else connect_scheduler(campaign.scheduler)
        try:
            results = evaluate_population(eyes, [item.condition], settings.mtf_cyc_per_deg, workers=campaign.workers,
                                          client=client)
        finally:
            if client is not None:
                client.close()
        record = {"key": key, "configuration": item.as_json(), "eyes_selected": len(eyes),
                  "eyes": [r.as_json() for r in results]}
        Path(item_dir).mkdir(parents=True, exist_ok=True)
        write_json_atomic(Path(item_dir) / "result.json", record, overwrite=True)
        return record

    def input_files(self, record: dict) -> list[Path]:
        return []

    def report(self, results: list, run_dir: Path, record: dict, progress=None):
        from vissim.validation.population.report import population_report

        return population_report(results, record)

    def summary_lines(self, rows) -> list[str]:
        from vissim.validation.population.report import summary_lines

        return summary_lines(rows)


BENCH = PopulationKind()
