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
import contextlib
import logging
import multiprocessing
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Callable

import numpy as np

from vissim.atomic import write_json_atomic
from vissim.errors import VissimInputError
from vissim.imageio import read_image, write_image
from vissim.progress import Progress, counter, terminal_progress
from vissim.provenance import make_provenance
from vissim.validation.campaign_types import Campaign
from vissim.checks import instance_of, path_arg, samples_per_pixel
from vissim.validation.captures import capture_problem, capture_provenance, capture_tile, load_manifest, read_capture
from vissim.validation.item import compute_item
from vissim.validation.renders import RenderSpec, no_lens_spec, render_spec, truth_specs
from vissim.validation.scheduler_probe import probe_scheduler

__all__ = ["run_campaign", "RunSummary", "plan_run", "make_missing_renders"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class RunSummary:
    run_dir: Path
    items_total: int
    items_reused: int
    renders_made: int
    renders_reused: int
    skipped: tuple[str, ...] = ()  # one message per item that could not run (absent capture)


def _capture_plan(campaign: Campaign, config, captures: dict) -> tuple | str:
    """The captures (truth, repeat | None, no-lens) an item uses, or why it is skipped.

    Each capture's own file (presence, sha256) is checked before what it refers to, so a
    corrupt capture is reported as such, not as a missing reference.
    """
    if campaign.manifest is None:
        return f"{config.name}: capture {config.capture!r} but the campaign names no manifest"

    def checked(capture_id: str):  # the capture, or why the item is skipped
        if capture_id not in captures:
            return f"{config.name}: capture {capture_id!r} is not in {campaign.manifest}"
        problem = capture_problem(captures[capture_id])
        return f"{config.name}: skipped, {problem}" if problem else captures[capture_id]

    capture = checked(config.capture)
    if isinstance(capture, str):
        return capture
    if capture.no_lens_capture is None:
        return f"{config.name}: capture {capture.id!r} names no no_lens_capture (the simulation input)"
    references = (capture.repeat_capture, capture.no_lens_capture)
    plan = [capture, *(None if c is None else checked(c) for c in references)]
    return next((p for p in plan if isinstance(p, str)), tuple(plan))


def _capture_inputs(campaign: Campaign, plan: tuple):
    """(truth_a, truth_b | None, no_lens) tiles of a capture plan, and their provenance."""
    settings = campaign.settings
    raws = [None if c is None else read_capture(c) for c in plan]
    tiles = [None if c is None else capture_tile(c, settings.arcmin_per_px, settings.tile_px, raw=r)
             for c, r in zip(plan, raws)]
    provenance = {name: None if c is None else capture_provenance(c, r)
                  for name, c, r in zip(("truth_a", "truth_b", "no_lens"), plan, raws)}
    return (*tiles, provenance)


def _render_path(run_dir: Path, spec: RenderSpec) -> Path:
    return run_dir / "renders" / f"{spec.key}.exr"


def progress_of(show_progress: bool, progress: Progress | None):
    """The campaign's progress reports: to ``progress`` if given, else bars on a terminal if ``show_progress``."""
    if progress is not None or not show_progress:
        return contextlib.nullcontext(progress)
    return terminal_progress()


#: How long ``--scheduler`` waits for a Dask scheduler to answer.
SCHEDULER_TIMEOUT_S = 2.0
MAX_WORKERS = 1024


def connect_scheduler(address: str):
    """A Dask ``Client`` of the scheduler at ``address``, or one clean error within SCHEDULER_TIMEOUT_S."""
    try:
        from distributed import Client
        from distributed.comm import parse_address
    except ImportError:  # pragma: no cover
        raise VissimInputError("--scheduler needs Dask distributed: pip install 'dask[distributed]'") from None
    hint = "expected tcp://HOST:PORT, e.g. tcp://127.0.0.1:8786"
    if not address.strip():
        raise VissimInputError(f"--scheduler is empty; {hint} (leave the option out to render here)")
    try:
        scheme, location = parse_address(address)
    except (ValueError, TypeError) as exc:
        raise VissimInputError(f"--scheduler {address!r} is not a Dask scheduler address ({exc}); {hint}") from None
    host, _, port = location.rpartition(":")
    if scheme in ("tcp", "tls", "ws", "wss") and not (host and port.isdigit() and 0 < int(port) < 65536):
        raise VissimInputError(f"--scheduler {address!r} is not a Dask scheduler address; {hint}")
    if scheme == "tcp":  # a web server or another service would keep Dask waiting, or ask for exabytes
        probe_scheduler(address, host.strip("[]"), int(port))
    try:
        return Client(address, timeout=SCHEDULER_TIMEOUT_S)
    except (OSError, TimeoutError):
        raise VissimInputError(f"--scheduler {address}: no Dask scheduler answered within {SCHEDULER_TIMEOUT_S:g} s; "
                               "start one (dask scheduler) or check the address") from None
    except (ValueError, TypeError) as exc:
        raise VissimInputError(f"--scheduler {address!r} is not a Dask scheduler address ({exc}); {hint}") from None


def check_run_options(run_dir: Path, workers: int, spp: int | None) -> None:
    """``-o``, ``--workers`` and ``--spp``, before anything is written."""
    if run_dir.exists() and not run_dir.is_dir():
        raise VissimInputError(f"-o {run_dir} is a file, not a run folder")
    if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= MAX_WORKERS:
        raise VissimInputError(f"--workers must be 1 to {MAX_WORKERS} worker processes, got {workers!r}")
    if spp is not None:
        samples_per_pixel(spp, "--spp")


def render_file_provenance(spec, result) -> dict:
    """Provenance of a render file: the spec, and what the renderer says it did.

    ``result`` is an array, or an object with ``pixels`` and optionally ``variant``, ``spp``
    (recorded as ``variant``, ``spp_used``) and ``provenance`` (e.g.
    `vissim.render.run.RenderResult`), whose keys win and whose ``inputs`` are merged.
    """
    provenance = make_provenance(render=spec.as_json())
    for attribute, key in (("variant", "variant"), ("spp", "spp_used")):
        if hasattr(result, attribute):
            provenance[key] = getattr(result, attribute)
    for key, value in (getattr(result, "provenance", None) or {}).items():
        if key == "inputs" and isinstance(value, dict):
            provenance["inputs"].update(value)
        else:
            provenance[key] = value
    return provenance


def _make_renders(pending: list, run_dir: Path, workers: int, client, render: Callable,
                  progress: Progress | None) -> None:
    """Render ``pending`` specs into ``run_dir/renders``: on a connected Dask ``client``, or locally."""
    def save(spec, result) -> None:
        pixels = np.asarray(getattr(result, "pixels", result), np.float32)
        write_image(_render_path(run_dir, spec), pixels, provenance=render_file_provenance(spec, result),
                    overwrite=True)

    advance = counter(progress, "rendering", len(pending))
    if client is not None:
        from distributed import as_completed

        futures = {client.submit(render, spec, pure=False): spec for spec in pending}
        for future in as_completed(futures):
            save(futures[future], future.result())
            advance()
    elif workers > 1 and len(pending) > 1:
        context = multiprocessing.get_context("spawn")  # Dr.Jit state does not survive fork
        with concurrent.futures.ProcessPoolExecutor(max_workers=min(workers, len(pending)),
                                                    mp_context=context) as pool:
            futures = {pool.submit(render, spec): spec for spec in pending}
            for future in concurrent.futures.as_completed(futures):
                save(futures[future], future.result())
                advance()
    else:
        for spec in pending:
            save(spec, render(spec))
            advance()


def nothing_to_compare(source: str, total: int, skipped: list[str]) -> VissimInputError:
    """The error of a campaign all of whose items were skipped (no report is written)."""
    which = "its only item was" if total == 1 else f"all {total} items were"
    return VissimInputError(f"{source}: {which} skipped, nothing to compare: {'; '.join(skipped)}")


def plan_run(campaign, run_dir: Path, workers: int, spp: int | None):
    """Check ``-o``, ``--workers`` and ``--spp``; (campaign with ``spp`` applied, every item key, (key, item) to do)."""
    check_run_options(run_dir, workers, spp)
    if spp is not None:
        campaign = replace(campaign, settings=replace(campaign.settings, spp=spp))
    keys = [campaign.item_key(c) for c in campaign.configurations]
    todo = [(k, c) for k, c in zip(keys, campaign.configurations) if not (run_dir / "items" / k / "result.json").exists()]
    return campaign, keys, todo


def make_missing_renders(run_dir: Path, needed: dict, record: dict, *, workers: int, scheduler: str | None,
                         render: Callable, progress: Progress | None, items: str) -> int:
    """Write ``campaign.json`` (``record``) and the ``needed`` renders ({key: spec}) not yet in ``run_dir``.

    The scheduler is connected before anything is written; ``items`` ("3 of 5 items") is logged.
    Returns the number of renders made.
    """
    pending = [s for s in needed.values() if not _render_path(run_dir, s).exists()]
    client = connect_scheduler(scheduler) if scheduler is not None and pending else None
    try:
        provenance = make_provenance(campaign=record["source"])
        write_json_atomic(run_dir / "campaign.json", {**record, "provenance": provenance}, overwrite=True)
        log.info("%s to do; %d renders to make, %d reused", items, len(pending), len(needed) - len(pending))
        if pending:
            _make_renders(pending, run_dir, workers, client, render, progress)
    finally:
        if client is not None:
            client.close()
    return len(pending)


def run_campaign(
    campaign: Campaign,
    run_dir: str | Path,
    *,
    workers: int = 1,
    scheduler: str | None = None,
    spp: int | None = None,
    render: Callable[[RenderSpec], np.ndarray] | None = None,
    show_progress: bool = True,
    progress: Progress | None = None,
) -> RunSummary:
    """Run (or resume) ``campaign`` into ``run_dir``; returns what was made and reused.

    ``render`` makes one bench render from a `RenderSpec` (default: Mitsuba via
    `vissim.validation.renders.render_spec`); it must be picklable for workers.  Every
    check (options, captures, the scheduler) runs before the first file is written; a campaign
    whose every item would be skipped raises `VissimInputError` and writes nothing.

    Parameters
    ----------
    campaign : Campaign
        From `vissim.load_campaign`.
    run_dir : str or Path
        Directory for renders, simulations, metrics and the report; an existing run there is
        resumed (finished items are reused).
    workers : int
        Local processes that make the renders (1: in this process).  Items are computed here,
        one after another.
    scheduler : str, optional
        A Dask scheduler's address (``host:port``) to make the renders on instead of
        ``workers``; checked to answer before anything is written (`connect_scheduler`).
    spp : int, optional
        Override the campaign's samples per pixel for every render.
    render : callable, optional
        ``render(spec) -> ndarray (H, W)`` linear light, row 0 at the top.
    show_progress : bool
        Without ``progress``: draw progress bars on a terminal (`vissim.progress.terminal_progress`).
    progress : callable, optional
        ``progress(stage, done, total)`` after each render ("rendering") and item ("items")
        (`vissim.progress`).

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
    render = render or render_spec
    run_dir = path_arg(run_dir, "run_campaign's run_dir")
    campaign, keys, todo = plan_run(campaign, run_dir, workers, spp)
    settings = campaign.settings
    captures = load_manifest(campaign.manifest) if campaign.manifest and any(c.capture for _, c in todo) else {}
    plans = {k: _capture_plan(campaign, c, captures) for k, c in todo if c.capture}
    skipped = [p for p in plans.values() if isinstance(p, str)]
    # capture tiles now, so that a capture that cannot be read stops the run before it writes
    capture_inputs = {k: _capture_inputs(campaign, p) for k, p in plans.items() if not isinstance(p, str)}
    if len(skipped) == len(keys):
        raise nothing_to_compare(campaign.source, len(keys), skipped)
    for message in skipped:
        log.warning("%s", message)
    needed: dict[str, RenderSpec] = {}
    for _, config in todo:
        if config.capture:
            continue
        for spec in (*truth_specs(config, settings), no_lens_spec(config, settings)):
            needed[spec.key] = spec
    record = {"name": campaign.name, "description": campaign.description, "source": campaign.source,
              "manifest": campaign.manifest,
              "settings": asdict(settings), "items": keys,
              "configurations": [c.as_json() for c in campaign.configurations]}
    with progress_of(show_progress, progress) as report:
        made = make_missing_renders(run_dir, needed, record, workers=workers, scheduler=scheduler, render=render,
                                    progress=report, items=f"{len(todo)} of {len(keys)} items")
        _compute_items(run_dir, todo, settings, capture_inputs, counter(report, "items", len(todo)))
    return RunSummary(run_dir, len(keys), len(keys) - len(todo), made, len(needed) - made, tuple(skipped))


def _compute_items(run_dir: Path, todo: list, settings, capture_inputs: dict, advance: Callable[[], None]) -> None:
    """Each item to do, from its renders (or capture tiles) in ``run_dir``; ``advance()`` after each."""
    for key, config in todo:
        if config.capture:
            if key not in capture_inputs:
                advance()
                continue  # skipped
            truth_a, truth_b, no_lens, render_provenance = capture_inputs[key]
            source = {"ground_truth": "capture", "capture": config.capture}
        else:
            roles = dict(zip(("truth_a", "truth_b", "no_lens"),
                             (*truth_specs(config, settings), no_lens_spec(config, settings))))
            images = {role: read_image(_render_path(run_dir, spec)) for role, spec in roles.items()}
            truth_a, truth_b, no_lens = (images[role].pixels for role in roles)
            render_provenance = {role: image.provenance for role, image in images.items()}
            source = {"ground_truth": "bench render", "render_keys": [spec.key for spec in roles.values()]}
        compute_item(key, config, settings, truth_a, truth_b, no_lens, run_dir / "items" / key, source=source,
                     render_provenance=render_provenance)
        advance()
