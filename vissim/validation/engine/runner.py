"""Run a campaign into a run folder: renders first (in parallel), then items (one per core at once: shared with the
campaign's helper process where one was started, else on threads); reuse what is done.

Run folder layout::

    RUN/campaign.json             what was run (kind, settings, configurations, item keys)
    RUN/renders/<key>.exr         every render, keyed by its inputs (reused on re-runs)
    RUN/items/<key>/result.json   one item's numbers; written last, so its presence = finished
    RUN/items/<key>/*.exr|*.png   its images and maps
    RUN/metrics.*, tables.md, figure_*.png, report.html

Re-running reuses finished renders and items and redoes nothing; every file is written
atomically, so an interrupted run leaves no corrupt file and resumes where it stopped.
Renders run here (``workers=1``), in a process pool (``workers=N``), or on a Dask cluster
(``scheduler=ADDRESS``, `vissim.validation.engine.renders`).  The run folder is checked to hold
none of the campaign's inputs and is locked for the whole run (`vissim.validation.engine.run_lock`).
"""

from __future__ import annotations

import contextlib
import logging
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

from vissim.atomic import check_outputs_apart, write_json_atomic
from vissim.checks import MAX_WORKERS, instance_of, path_arg, samples_per_pixel
from vissim.errors import VissimInputError
from vissim.imageio import read_image
from vissim.optics.runtime.threads import map_on_threads, single_threaded_blas
from vissim.progress import Progress, counter, terminal_progress
from vissim.provenance import make_provenance
from vissim.validation.engine.inputs import campaign_inputs
from vissim.validation.engine.helper_process import share_work, started_helper
from vissim.validation.engine.keys import item_dir, render_path
from vissim.validation.engine.protocol import Campaign
from vissim.validation.engine.registry import bench_kind
from vissim.validation.engine.renders import make_renders, render_any, spec_key
from vissim.validation.engine.run_lock import run_folder_lock
from vissim.validation.engine.scheduler import connect_scheduler

__all__ = ["run_campaign", "run_unlocked", "RunSummary", "check_run", "check_run_options", "progress_of"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class RunSummary:
    run_dir: Path
    items_total: int
    items_reused: int
    renders_made: int
    renders_reused: int
    skipped: tuple[str, ...] = ()  # one message per item that could not run (e.g. an absent capture)
    renders_seconds: float = 0.0  # wall time of this run's renders (none made: 0)
    item_seconds: tuple[tuple[str, float], ...] = ()  # (item key, wall seconds) of each item computed, slowest first
    item_names: tuple[tuple[str, str], ...] = ()  # (item key, its configuration's name) of every item
    items_seconds: float = 0.0  # wall time of this run's items (several at once: less than their sum)


def progress_of(show_progress: bool, progress: Progress | None):
    """The campaign's progress reports: to ``progress`` if given, else bars on a terminal if ``show_progress``."""
    if progress is not None or not show_progress:
        return contextlib.nullcontext(progress)
    return terminal_progress()


def check_run(campaign: Campaign, run_dir: Path, workers: int, spp: int | None, scheduler: str | None) -> None:
    """Before anything is written: the run folder holds none of the campaign's inputs; ``-o``, ``--workers``,
    ``--spp`` and ``--scheduler`` are sound."""
    check_outputs_apart(campaign_inputs(campaign), folders=[run_dir])
    check_run_options(run_dir, workers, spp)
    if spp is not None and not hasattr(campaign.settings, "spp"):
        raise VissimInputError(f"--spp {spp}: a {campaign.kind} campaign makes no renders; leave the option out")
    if scheduler is not None and not scheduler.strip():
        raise VissimInputError("--scheduler is empty; expected tcp://HOST:PORT, e.g. tcp://127.0.0.1:8786 "
                               "(leave the option out to render here)")


def check_run_options(run_dir: Path, workers: int, spp: int | None) -> None:
    """``-o``, ``--workers`` and ``--spp``, before anything is written."""
    if run_dir.exists() and not run_dir.is_dir():
        raise VissimInputError(f"-o {run_dir} is a file, not a run folder")
    if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= MAX_WORKERS:
        raise VissimInputError(f"--workers must be 1 to {MAX_WORKERS} worker processes, got {workers!r}")
    if spp is not None:
        samples_per_pixel(spp, "--spp")


def nothing_to_compare(source: str, total: int, skipped: list[str]) -> VissimInputError:
    """The error of a campaign all of whose items were skipped (no report is written)."""
    which = "its only item was" if total == 1 else f"all {total} items were"
    return VissimInputError(f"{source}: {which} skipped, nothing to compare: {'; '.join(skipped)}")


def _with_spp(campaign: Campaign, spp: int | None) -> Campaign:
    """``campaign`` with every render at ``spp`` samples per pixel; its configurations built again for it."""
    if spp is None:
        return campaign
    settings, kind = replace(campaign.settings, spp=spp), bench_kind(campaign.kind)
    return replace(campaign, settings=settings, built=tuple(kind.build(c, settings) for c in campaign.configurations))


def run_campaign(campaign: Campaign, run_dir: str | Path, *, workers: int = 1, scheduler: str | None = None,
                 spp: int | None = None, render: Callable | None = None, show_progress: bool = True,
                 progress: Progress | None = None) -> RunSummary:
    """Run (or resume) ``campaign`` into ``run_dir``; returns what was made and reused.

    Every check (the run folder apart from the inputs, options, captures, the scheduler) runs
    before the first file is written; a campaign whose every item would be skipped raises
    `VissimInputError` and writes nothing.

    Parameters
    ----------
    campaign : Campaign
        From `vissim.load_campaign`, of any bench kind.
    run_dir : str or Path
        Directory for renders, simulations, metrics and the report; an existing run there is
        resumed (finished items are reused).
    workers : int
        Local processes that make the renders (1: in this process).  Items are computed one per core at
        once (the cores this process may use: ``taskset`` limits them), each with OpenBLAS on one thread:
        shared with the campaign's helper process inside a `vissim.validation.engine.helper_process.campaign_helper`
        block (``vissim validate`` starts one for a DSLR campaign on `HELPER_CORES` cores), else on this process's threads; a
        kind whose items spread their own work (a population's eyes over the same ``workers``, a depth scene's layers over
        the cores) computes them one after another.
    scheduler : str, optional
        A Dask scheduler's address (``host:port``) to make the renders on instead of
        ``workers`` (and a population's eyes); checked to answer before the renders are written (a
        population, which makes none, connects when its first item starts).
    spp : int, optional
        Override the campaign's samples per pixel for every render.
    render : callable, optional
        ``render(spec)``: pixels (linear light, row 0 at the top) or a result with ``pixels``;
        default: the bench kind's Mitsuba renderer.  Must be picklable for workers.
    show_progress : bool
        Without ``progress``: draw progress bars on a terminal (`vissim.progress.terminal_progress`).
    progress : callable, optional
        ``progress(stage, done, total)`` after each render ("rendering") and item ("items").

    Returns
    -------
    RunSummary
        ``run_dir``, items total and reused, renders made and reused, and one message per
        skipped item.

    Examples
    --------
    Needs Mitsuba (the default ``render``) and a campaign file; see tutorial 3:

    >>> import vissim
    >>> campaign = vissim.load_campaign("campaign.toml")  # doctest: +SKIP
    >>> summary = vissim.run_campaign(campaign, "runs/demo", workers=2)  # doctest: +SKIP
    >>> summary.renders_made  # doctest: +SKIP
    4
    """
    instance_of(campaign, Campaign, "run_campaign's campaign", "a Campaign (from vissim.load_campaign(path))")
    run_dir = path_arg(run_dir, "run_campaign's run_dir")
    check_run(campaign, run_dir, workers, spp, scheduler)
    with run_folder_lock(run_dir):
        return run_unlocked(campaign, run_dir, workers=workers, scheduler=scheduler, spp=spp, render=render,
                            show_progress=show_progress, progress=progress)


def run_unlocked(campaign: Campaign, run_dir: Path, *, workers: int, scheduler: str | None, spp: int | None,
                 render: Callable | None, show_progress: bool, progress: Progress | None) -> RunSummary:
    """`run_campaign` once its checks are done and the run folder is locked."""
    campaign, kind = _with_spp(campaign, spp), bench_kind(campaign.kind)
    campaign = replace(campaign, workers=workers, scheduler=scheduler)
    keys = [campaign.item_key(c) for c in campaign.configurations]
    todo = [(k, i) for i, k in enumerate(keys) if not (item_dir(run_dir, k) / "result.json").exists()]
    plans, skipped = kind.plan_items(campaign, todo)
    if todo and len(skipped) == len(keys):
        raise nothing_to_compare(campaign.source, len(keys), skipped)
    for message in skipped:
        log.warning("%s", message)
    needed = {spec_key(spec): spec for plan in plans.values() for spec in plan.renders.values()}
    timed = []
    with progress_of(show_progress, progress) as report:
        start = time.perf_counter()
        made = _make_missing_renders(run_dir, needed, campaign.record(keys), workers=workers, scheduler=scheduler,
                                     render=render or render_any, progress=report,
                                     items=f"{len(todo)} of {len(keys)} items")
        renders_seconds = time.perf_counter() - start
        advance = counter(report, "items", len(todo))

        def compute(pair):  # kinds whose items spread their own work run it here as it is
            key, index = pair
            if key in plans:
                start = time.perf_counter()
                _compute_item(kind, campaign, key, index, plans[key], run_dir)
                timed.append((key, time.perf_counter() - start))
            advance()

        start = time.perf_counter()
        helper = started_helper()
        if getattr(kind, "items_on_threads", True) and helper is not None:
            timed += _items_with_helper(campaign, plans, todo, run_dir, helper, advance)
        elif getattr(kind, "items_on_threads", True):
            map_on_threads(compute, todo)  # items are independent: one per core at once
        else:
            for pair in todo:
                compute(pair)
        items_seconds = time.perf_counter() - start
    names = tuple((key, str(getattr(c, "name", ""))) for key, c in zip(keys, campaign.configurations))
    return RunSummary(run_dir, len(keys), len(keys) - len(todo), made, len(needed) - made, tuple(skipped),
                      renders_seconds, tuple(sorted(timed, key=lambda pair: -pair[1])), names, items_seconds)


def _items_with_helper(campaign: Campaign, plans: dict, todo: list, run_dir: Path, helper, advance) -> list:
    """The items of ``todo`` shared between this process and the campaign's helper process
    (`vissim.validation.engine.helper_process`), one at a time each: (item key, seconds) of each."""
    planned = [(key, index) for key, index in todo if key in plans]
    for _ in range(len(todo) - len(planned)):
        advance()
    calls = [(timed_item, (campaign, key, index, plans[key], run_dir)) for key, index in planned]
    return list(zip((key for key, _ in planned), share_work(calls, helper, advance)))


def timed_item(campaign: Campaign, key: str, index: int, plan, run_dir: Path) -> float:
    """`_compute_item` on this process's core alone (OpenBLAS on one thread, no threads of its own): its seconds.
    Made here or in the campaign's helper process."""
    start = time.perf_counter()
    with single_threaded_blas():
        _compute_item(bench_kind(campaign.kind), campaign, key, index, plan, run_dir)
    return time.perf_counter() - start


def _compute_item(kind, campaign: Campaign, key: str, index: int, plan, run_dir: Path) -> None:
    """One item from its renders in ``run_dir`` and its given images; a refusal names the item."""
    renders = {role: read_image(render_path(run_dir, spec_key(spec))) for role, spec in plan.renders.items()}
    images = {**plan.given, **{role: image.pixels for role, image in renders.items()}}
    provenance = {**plan.given_provenance, **{role: image.provenance for role, image in renders.items()}}
    try:
        kind.compute_item(key, campaign, index, images, plan, provenance, item_dir(run_dir, key))
    except VissimInputError as error:
        name = getattr(campaign.configurations[index], "name", key)
        raise VissimInputError(f"{campaign.source}: configuration {name!r} (item {key}): {error}; its renders are "
                               "kept, and a run after the fix reuses them") from None


def _make_missing_renders(run_dir: Path, needed: dict, record: dict, *, workers: int, scheduler: str | None,
                          render: Callable, progress: Progress | None, items: str) -> int:
    """Write ``campaign.json`` (``record``) and the ``needed`` renders ({key: spec}) not yet in ``run_dir``.

    The scheduler is connected before anything is written.  Returns the number of renders made.
    """
    pending = [spec for key, spec in needed.items() if not render_path(run_dir, key).exists()]
    client = connect_scheduler(scheduler) if scheduler is not None and pending else None
    try:
        provenance = make_provenance(campaign=record["source"])
        write_json_atomic(run_dir / "campaign.json", {**record, "provenance": provenance}, overwrite=True)
        log.info("%s to do; %d renders to make, %d reused", items, len(pending), len(needed) - len(pending))
        if pending:
            make_renders(pending, run_dir, workers, client, render, progress)
    finally:
        if client is not None:
            client.close()
    return len(pending)
