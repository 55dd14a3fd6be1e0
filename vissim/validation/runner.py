"""Run a campaign into a run folder: renders first (in parallel), then comparisons.

Run folder layout::

    RUN/campaign.json             what was run (settings, configurations, item keys)
    RUN/renders/<key>.exr         every bench render, keyed by its inputs (reused on re-runs)
    RUN/items/<key>/result.json   one item's numbers; written last, so its presence = finished
    RUN/items/<key>/*.exr|*.png   its images and maps
    RUN/metrics.*, tables.md, figure_*.png, report.html

Re-running reuses finished renders and items and redoes nothing; every file is written
atomically, so an interrupted run leaves no corrupt file and resumes where it stopped.
Renders run here (``workers=1``), in a process pool (``workers=N``), or on a Dask cluster
(``scheduler=ADDRESS``): workers return arrays and this process writes them, so a remote
cluster needs no shared file system.
"""

from __future__ import annotations

import concurrent.futures
import logging
import multiprocessing
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Callable

import numpy as np

from vissim.atomic import write_json_atomic
from vissim.errors import VissimInputError
from vissim.imageio import read_image, write_image
from vissim.provenance import make_provenance
from vissim.validation.campaign import Campaign
from vissim.validation.captures import capture_problem, capture_tile, load_manifest
from vissim.validation.item import compute_item
from vissim.validation.renders import RenderSpec, no_lens_spec, render_spec, truth_specs

__all__ = ["run_campaign", "RunSummary"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class RunSummary:
    run_dir: Path
    items_total: int
    items_reused: int
    renders_made: int
    renders_reused: int
    skipped: tuple[str, ...] = ()  # one message per item that could not run (absent capture)


def _capture_inputs(campaign: Campaign, config, captures: dict):
    """(truth_a, truth_b | None, no_lens) from RAW captures, or a message saying why not."""
    if campaign.manifest is None:
        return f"{config.name}: capture {config.capture!r} but the campaign names no manifest"
    capture = captures.get(config.capture)
    if capture is None:
        return f"{config.name}: capture {config.capture!r} is not in {campaign.manifest}"
    ids = [capture.id, capture.no_lens_capture, capture.repeat_capture]
    if ids[1] is None:
        return f"{config.name}: capture {capture.id!r} names no no_lens_capture (the simulation input)"
    tiles = []
    for capture_id in ids:
        if capture_id is None:
            tiles.append(None)
            continue
        if capture_id not in captures:
            return f"{config.name}: capture {capture_id!r} is not in {campaign.manifest}"
        problem = capture_problem(captures[capture_id])
        if problem:
            return f"{config.name}: skipped, {problem}"
        tiles.append(capture_tile(captures[capture_id], campaign.settings.arcmin_per_px, campaign.settings.tile_px))
    return tiles[0], tiles[2], tiles[1]


def _render_path(run_dir: Path, spec: RenderSpec) -> Path:
    return run_dir / "renders" / f"{spec.key}.exr"


def _progress(total: int, label: str):
    try:
        from rich.progress import Progress

        progress = Progress(transient=False)
        task = progress.add_task(label, total=total)
        return progress, lambda: progress.advance(task)
    except ImportError:  # pragma: no cover
        return None, lambda: None


def _make_renders(pending: list[RenderSpec], run_dir: Path, workers: int, scheduler: str | None,
                  render: Callable[[RenderSpec], np.ndarray], show_progress: bool) -> None:
    def save(spec: RenderSpec, pixels: np.ndarray) -> None:
        prov = make_provenance(render=spec.as_json())
        write_image(_render_path(run_dir, spec), np.asarray(pixels, np.float32), provenance=prov, overwrite=True)

    progress, advance = _progress(len(pending), "rendering") if show_progress else (None, lambda: None)
    if progress:
        progress.start()
    try:
        if scheduler:
            try:
                from distributed import Client, as_completed
            except ImportError:  # pragma: no cover
                raise VissimInputError("--scheduler needs Dask distributed: pip install 'dask[distributed]'") from None
            with Client(scheduler) as client:
                futures = {client.submit(render, spec, pure=False): spec for spec in pending}
                for future in as_completed(futures):
                    save(futures[future], future.result())
                    advance()
        elif workers > 1 and len(pending) > 1:
            context = multiprocessing.get_context("spawn")  # Dr.Jit state does not survive fork
            with concurrent.futures.ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
                futures = {pool.submit(render, spec): spec for spec in pending}
                for future in concurrent.futures.as_completed(futures):
                    save(futures[future], future.result())
                    advance()
        else:
            for spec in pending:
                save(spec, render(spec))
                advance()
    finally:
        if progress:
            progress.stop()


def run_campaign(
    campaign: Campaign,
    run_dir: str | Path,
    *,
    workers: int = 1,
    scheduler: str | None = None,
    spp: int | None = None,
    render: Callable[[RenderSpec], np.ndarray] | None = None,
    show_progress: bool = True,
) -> RunSummary:
    """Run (or resume) ``campaign`` into ``run_dir``; returns what was made and reused.

    ``render`` makes one bench render from a :class:`RenderSpec` (default: Mitsuba via
    :func:`vissim.validation.renders.render_spec`); it must be picklable for workers.
    """
    render = render or render_spec
    if workers < 1:
        raise VissimInputError(f"--workers must be at least 1, got {workers}")
    if spp is not None:
        if spp < 1:
            raise VissimInputError(f"--spp must be a positive number of samples per pixel, got {spp}")
        campaign = replace(campaign, settings=replace(campaign.settings, spp=spp))
    run_dir = Path(run_dir)
    settings = campaign.settings
    keys = [campaign.item_key(c) for c in campaign.configurations]
    write_json_atomic(
        run_dir / "campaign.json",
        {"name": campaign.name, "description": campaign.description, "source": campaign.source,
         "settings": asdict(settings), "items": keys,
         "configurations": [c.as_json() for c in campaign.configurations]},
        overwrite=True,
    )
    todo = [(k, c) for k, c in zip(keys, campaign.configurations) if not (run_dir / "items" / k / "result.json").exists()]
    captures = load_manifest(campaign.manifest) if campaign.manifest and any(c.capture for _, c in todo) else {}
    needed: dict[str, RenderSpec] = {}
    for _, config in todo:
        if config.capture:
            continue
        for spec in (*truth_specs(config, settings), no_lens_spec(config, settings)):
            needed[spec.key] = spec
    pending = [s for s in needed.values() if not _render_path(run_dir, s).exists()]
    log.info("%d of %d items to do; %d renders to make, %d reused", len(todo), len(keys), len(pending), len(needed) - len(pending))
    if pending:
        _make_renders(pending, run_dir, workers, scheduler, render, show_progress)
    skipped = []
    for key, config in todo:
        if config.capture:
            inputs = _capture_inputs(campaign, config, captures)
            if isinstance(inputs, str):
                log.warning("%s", inputs)
                skipped.append(inputs)
                continue
            truth_a, truth_b, no_lens = inputs
            source = {"ground_truth": "capture", "capture": config.capture}
        else:
            truth_a, truth_b = (read_image(_render_path(run_dir, s)).pixels for s in truth_specs(config, settings))
            no_lens = read_image(_render_path(run_dir, no_lens_spec(config, settings))).pixels
            source = {"ground_truth": "bench render",
                      "render_keys": [s.key for s in (*truth_specs(config, settings), no_lens_spec(config, settings))]}
        compute_item(key, config, settings, truth_a, truth_b, no_lens, run_dir / "items" / key, source=source)
    return RunSummary(run_dir, len(keys), len(keys) - len(todo), len(pending), len(needed) - len(pending), tuple(skipped))
