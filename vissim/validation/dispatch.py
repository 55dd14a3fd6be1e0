"""Either kind of campaign file: run it or rebuild its report (``vissim validate`` / ``vissim report``).

A depth campaign (`vissim.validation.depth_campaign`) or a single-plane one
(`vissim.validation.campaign`) is told apart by its tables when run, and by the ``kind`` in
``campaign.json`` when its report is rebuilt; each is handed to its own runner and report.

The run folder is checked to hold none of the campaign's inputs (`campaign_inputs`) and
is locked for the whole run or rebuild (`vissim.validation.run_lock`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from vissim.atomic import check_outputs_apart
from vissim.errors import VissimInputError
from vissim.progress import Progress
from vissim.validation.depth_campaign import is_depth_campaign, load_depth_campaign
from vissim.validation.depth_runner import run_depth_campaign
from vissim.validation.fields import read_campaign_toml
from vissim.validation.run_lock import run_folder_lock
from vissim.validation.runner import RunSummary, check_run_options

__all__ = ["CampaignRun", "campaign_inputs", "run_any_campaign", "rebuild_any_report"]


@dataclass(frozen=True)
class CampaignRun:
    """What `run_any_campaign` did: the kind, the run summary, the report files and summary lines."""

    kind: str  # "depth" or "single-plane"
    summary: RunSummary
    report_files: tuple[Path, ...]
    lines: tuple[str, ...]

    def text(self) -> str:
        return "\n".join(self.lines)


def run_any_campaign(path: str | Path, out: str | Path, *, workers: int = 1, scheduler: str | None = None,
                     spp: int | None = None, show_progress: bool = True,
                     progress: Progress | None = None) -> CampaignRun:
    """Run the campaign file at ``path`` into ``out`` -- a depth campaign or a single-plane one -- and report it.

    ``progress(stage, done, total)`` (`vissim.progress`): renders, items, then the report's steps.
    """
    path, out = Path(path), Path(out)
    depth = is_depth_campaign(read_campaign_toml(path))
    if depth:
        load, run = load_depth_campaign, run_depth_campaign
    else:
        from vissim.validation.campaign import load_campaign as load
        from vissim.validation.runner import run_campaign as run
    campaign = load(path)
    check_outputs_apart(campaign_inputs(campaign, path), folders=[out])
    check_run_options(out, workers, spp)
    build_report, summary_lines = _report_of(depth)
    with run_folder_lock(out):
        summary = run(campaign, out, workers=workers, scheduler=scheduler, spp=spp, show_progress=show_progress,
                      progress=progress)
        written, lines = build_report(out, progress=progress), summary_lines(out)
    head = (f"{summary.items_total} items ({summary.items_reused} reused), {summary.renders_made} renders made, "
            f"{summary.renders_reused} reused")
    report = out / ("report.html" if (out / "report.html").exists() else "tables.md")
    return CampaignRun("depth" if depth else "single-plane", summary, tuple(written),
                       (head, *lines, f"report: {report} ({len(written)} files)"))


def rebuild_any_report(run_dir: str | Path, progress: Progress | None = None) -> tuple[list[Path], list[str]]:
    """Rebuild the report of a run folder of either kind (``vissim report``): (files written, summary lines).

    ``progress(stage, done, total)`` after each of the report's steps (`vissim.progress`).
    """
    run_dir = Path(run_dir)
    order = run_dir / "campaign.json"
    if not order.exists():
        raise VissimInputError(f"{run_dir} is not a vissim run folder (no campaign.json)")
    record = json.loads(order.read_text())
    check_outputs_apart(recorded_inputs(record), folders=[run_dir])
    build_report, summary_lines = _report_of(record.get("kind") == "depth")
    with run_folder_lock(run_dir):
        return build_report(run_dir, progress=progress), summary_lines(run_dir)


def campaign_inputs(campaign, path: Path) -> list[Path]:
    """Every file a campaign run reads: the campaign file, its depth scenes, its manifest and captures."""
    configurations = campaign.configurations
    return _input_files(path, getattr(campaign, "manifest", None),
                        [getattr(c, "scene_file", None) for c in configurations],
                        any(getattr(c, "capture", None) for c in configurations))


def recorded_inputs(record: dict) -> list[Path]:
    """The files a run folder's ``campaign.json`` says its campaign read (those that still exist)."""
    configurations = record.get("configurations", [])
    inputs = _input_files(record.get("source"), record.get("manifest"), [c.get("scene_file") for c in configurations],
                          any(c.get("capture") for c in configurations))
    return [p for p in inputs if p.exists()]


def _input_files(source, manifest, scene_files, uses_captures: bool) -> list[Path]:
    inputs = [Path(p) for p in (source, *scene_files) if p]
    if manifest is not None:
        inputs.append(Path(manifest))
        if Path(manifest).is_file() and uses_captures:
            from vissim.validation.captures import load_manifest

            inputs += [capture.file for capture in load_manifest(manifest).values()]
    return inputs


def _report_of(depth: bool):
    """(write the report, its terminal summary lines): functions of a run folder of a depth or single-plane run."""
    if depth:
        from vissim.validation.depth_report import build_depth_report, depth_summary_lines

        return build_depth_report, depth_summary_lines
    from vissim.validation.report import build_report

    return build_report, _single_plane_lines


def _single_plane_lines(run_dir: Path) -> list[str]:
    """The terminal summary of a single-plane run: one line per comparison (no floor: ``—``)."""
    from vissim.validation.report import format_number, load_results, metrics_rows
    from vissim.validation.wave_bench_report import is_wave_bench_row

    rows = metrics_rows(load_results(run_dir))
    width = min(max([len("configuration"), *(len(r["configuration"]) for r in rows)]), 72)  # names whole, up to 72
    lines = [(f"{'configuration':{width}s} {'simulation':>16s} {'input':>9s} {'SSIM':>7s} {'PSNR dB':>8s} "
              f"{'floor dB':>8s} {'against':>10s}")]
    for r in rows:
        against = "wave bench" if is_wave_bench_row(r) else "render"
        lines.append(f"{r['configuration'][:width]:{width}s} {r['simulation']:>16s} {r['input']:>9s} {r['ssim']:7.4f} "
                     f"{format_number(r['psnr_db'], 2):>8s} {format_number(r['noise_floor_psnr_db'], 2):>8s} "
                     f"{against:>10s}")
    return lines
