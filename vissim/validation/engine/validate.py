"""``vissim validate`` and ``vissim report``: run a campaign file of any kind and report it, or rebuild a report."""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

from vissim.atomic import check_outputs_apart, write_json_atomic
from vissim.errors import VissimInputError
from vissim.progress import Progress
from vissim.validation.engine.inputs import recorded_inputs
from vissim.validation.engine.helper_process import campaign_helper
from vissim.validation.engine.loader import load_campaign
from vissim.validation.engine.registry import bench_kind
from vissim.validation.engine.report import write_report
from vissim.validation.engine.run_lock import run_folder_lock
from vissim.validation.engine.runner import RunSummary, check_run, run_unlocked

__all__ = ["CampaignRun", "validate", "rebuild_report"]


@dataclass(frozen=True)
class CampaignRun:
    """What `validate` did: the bench kind, the run summary, the report files and summary lines."""

    kind: str
    summary: RunSummary
    report_files: tuple[Path, ...]
    lines: tuple[str, ...]

    def text(self) -> str:
        return "\n".join(self.lines)


def validate(path: str | Path, out: str | Path, *, workers: int = 1, scheduler: str | None = None,
             spp: int | None = None, show_progress: bool = True, progress: Progress | None = None) -> CampaignRun:
    """Run the campaign file at ``path`` into ``out`` and write its report.

    ``progress(stage, done, total)`` (`vissim.progress`): renders, items, then the report's steps.
    """
    out = Path(out)
    campaign = load_campaign(path, check_memory=False)
    check_run(campaign, out, workers, spp, scheduler)
    kind = bench_kind(campaign.kind)
    with campaign_helper(*getattr(kind, "helper_modules", ())):  # it imports while the memory is checked
        kind.check_memory(campaign)
        with run_folder_lock(out):
            return _run_and_report(campaign, out, workers, scheduler, spp, show_progress, progress)


def _run_and_report(campaign, out: Path, workers: int, scheduler: str | None, spp: int | None, show_progress: bool,
                    progress: Progress | None) -> CampaignRun:
    """`validate` once its checks are done and the run folder is locked."""
    summary = run_unlocked(campaign, out, workers=workers, scheduler=scheduler, spp=spp, render=None,
                           show_progress=show_progress, progress=progress)
    start = time.perf_counter()
    written, lines = write_report(out, progress=progress)
    timing = write_timings(out, summary, time.perf_counter() - start, workers)
    head = (f"{summary.items_total} items ({summary.items_reused} reused), {summary.renders_made} renders made, "
            f"{summary.renders_reused} reused")
    report = out / ("report.html" if (out / "report.html").exists() else "tables.md")
    return CampaignRun(campaign.kind, summary, (*written, out / TIMINGS_FILE),
                       (head, *lines, timing, f"report: {report} ({len(written) + 1} files)"))


#: Where a run's time went (`write_timings`), beside its report; it changes from run to run, so it is kept apart.
TIMINGS_FILE = "timings.json"
SLOWEST_ITEMS = 5


def write_timings(run_dir: Path, summary: RunSummary, report_seconds: float, workers: int) -> str:
    """Write ``timings.json`` (this run's wall seconds in its renders, its items (computed several at once: each
    item's own seconds add up to more), each item slowest first with its configuration's name, and its report, with
    the cores and workers it had) and return its one line for the command's summary."""
    names = dict(summary.item_names)
    record = {"renders_seconds": summary.renders_seconds, "items_seconds": summary.items_seconds,
              "report_seconds": report_seconds, "workers": workers, "cores": os.cpu_count(),
              "items": [{"key": key, "name": names.get(key, ""), "seconds": seconds}
                        for key, seconds in summary.item_seconds]}
    write_json_atomic(run_dir / TIMINGS_FILE, record, overwrite=True)
    slowest = ", ".join(f"{names.get(key) or key} {seconds:.1f} s"
                        for key, seconds in summary.item_seconds[:SLOWEST_ITEMS])
    return (f"time: renders {summary.renders_seconds:.1f} s, items {summary.items_seconds:.1f} s, report "
            f"{report_seconds:.1f} s" + (f"; slowest items: {slowest}" if slowest else ""))


def rebuild_report(run_dir: str | Path, progress: Progress | None = None) -> tuple[list[Path], list[str]]:
    """Rebuild the report of a run folder (``vissim report``): (files written, summary lines)."""
    run_dir = Path(run_dir)
    order = run_dir / "campaign.json"
    if not order.exists():
        raise VissimInputError(f"{run_dir} is not a vissim run folder (no campaign.json)")
    record = json.loads(order.read_text())
    check_outputs_apart([p for p in recorded_inputs(record) if p.exists()], folders=[run_dir])
    with run_folder_lock(run_dir):
        return write_report(run_dir, progress=progress, record=record)
