"""A campaign's helper process: a second Python process that computes items and draws figures beside this one.

A campaign's items and its report's figures are independent pieces of work.  Threads share the
cores badly for them -- much of an item is Python or FITPACK holding the GIL, and matplotlib is
not thread-safe -- so a spare core works in a process of its own.  The helper takes pieces from the
end of a list while this process takes them from the front, one at a time each, until they meet
(`share_work`); each piece is done whole by one process and by the same code, so its result does
not depend on where it was done.  The helper is spawned (this process may hold Dr.Jit's threads,
which do not survive a fork) and needs about a second to start, so a campaign starts it before its
renders (`campaign_helper`), the modules it will need imported meanwhile: on `HELPER_CORES` cores, where
it was measured to beat threads.  A report drawn alone (`draw_figures`) starts one wherever a core is spare.
A helper that dies (killed for memory, say) leaves its pieces to this process.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import importlib
import logging
import multiprocessing
import pickle
import threading
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Callable

from vissim.optics.runtime.threads import available_cores

__all__ = ["Helper", "campaign_helper", "started_helper", "share_work", "draw_figures", "FIGURES_WORTH_A_PROCESS",
           "HELPER_CORES"]

log = logging.getLogger(__name__)

#: Fewer figures than this are drawn here when no helper was started: starting one costs about a second.
FIGURES_WORTH_A_PROCESS = 4

_STARTED: list = []  # the helper a `campaign_helper` block started, while it lasts


#: Cores for which a campaign starts a helper process: where it was measured to beat threads (items 6.4-7.2 s
#: against 11.5-12.3 s on one thread a core).  With more, items run on one thread a core, as they scale there.
HELPER_CORES = 2


@dataclass(frozen=True)
class Helper:
    """A one-process pool and that process (to stop it at once: a pool only waits for its processes)."""

    pool: concurrent.futures.ProcessPoolExecutor
    process: multiprocessing.process.BaseProcess

    def submit(self, work: Callable, *arguments) -> concurrent.futures.Future:
        return self.pool.submit(work, *arguments)


@contextlib.contextmanager
def campaign_helper(*modules: str):
    """Within the block, `started_helper` is a helper process started now, which imports ``modules`` while this
    process goes on; none without modules, or on other than `HELPER_CORES` cores.  The block's end stops it
    (`share_work` has waited for every piece it took)."""
    if available_cores() != HELPER_CORES or not modules or _STARTED:
        yield
        return
    with _stopped_at_end(_spawn_helper(modules)) as helper:
        _STARTED.append(helper)
        try:
            yield
        finally:
            _STARTED.clear()


@contextlib.contextmanager
def _stopped_at_end(helper: Helper):
    """``helper`` within the block; at its end (its work handed back, or a refusal, or Ctrl-C) its process is stopped,
    not waited for: neither its imports nor its interpreter's teardown (0.1-0.2 s) delay this one."""
    try:
        yield helper
    finally:
        helper.process.terminate()
        helper.pool.shutdown(wait=True, cancel_futures=True)


def started_helper() -> Helper | None:
    """The helper process of the `campaign_helper` block this runs in, or None."""
    return _STARTED[0] if _STARTED else None


def _spawn_helper(modules: tuple[str, ...] = ()) -> Helper:
    """A helper process, started now (the pool starts it at its first piece of work: importing ``modules``)."""
    root = logging.getLogger()
    formatter = root.handlers[0].formatter if root.handlers else None
    try:
        pickle.dumps(formatter)
    except (TypeError, pickle.PicklingError, AttributeError):  # a formatter bound to this process (a test runner's)
        formatter = None
    pool = concurrent.futures.ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"),
                                                  initializer=_log_as, initargs=(root.level, formatter))
    before = set(multiprocessing.active_children())
    pool.submit(_import_all, tuple(modules))  # the pool starts its one process here, in this call (Python >= 3.9)
    started = [child for child in multiprocessing.active_children() if child not in before]
    if len(started) != 1:  # another thread started a child meanwhile, or the process died at once
        pool.shutdown(wait=False, cancel_futures=True)
        raise RuntimeError(f"the helper process could not be told apart: {len(started)} new child processes")
    return Helper(pool, started[0])


def _log_as(level: int, formatter) -> None:
    """The helper logs as this process does: its level, its line format."""
    handler = logging.StreamHandler()
    if formatter is not None:
        handler.setFormatter(formatter)
    logging.basicConfig(level=level, handlers=[handler])


def _import_all(modules: tuple[str, ...]) -> None:
    for name in modules:
        importlib.import_module(name)


def draw_figures(calls: list[tuple[Callable, tuple]], advance: Callable[[], None] = lambda: None) -> list:
    """``[draw(*arguments) for draw, arguments in calls]``, shared with a helper process when a core is spare:
    the campaign's, or one started for them when there are enough (`FIGURES_WORTH_A_PROCESS`).

    Each ``draw`` must be a module-level function and its arguments picklable; put the slowest first, where this
    process starts.  ``advance()`` is called here after each figure, wherever it was drawn.
    """
    if started_helper() is not None:
        return share_work(calls, started_helper(), advance)
    if available_cores() == 1 or len(calls) < FIGURES_WORTH_A_PROCESS:  # no core to spare, or too few figures
        return [_done(work, arguments, advance) for work, arguments in calls]
    with _stopped_at_end(_spawn_helper()) as helper:
        return share_work(calls, helper, advance)


def share_work(calls: list[tuple[Callable, tuple]], helper, advance: Callable[[], None] = lambda: None) -> list:
    """``[work(*arguments) for work, arguments in calls]``: this process from the front, ``helper`` (a one-process
    pool) from the back, one call at a time each; the first failure is raised once both have stopped."""
    out: list = [None] * len(calls)
    ends = [0, len(calls) - 1]  # the next call this process makes, the next the helper makes
    lock = threading.Lock()
    left: list[int] = []  # calls the helper took but could not make: it died

    def take(side: int) -> int | None:
        with lock:
            if ends[0] > ends[1]:
                return None
            index = ends[side]
            ends[side] += 1 if side == 0 else -1
            return index

    def feed() -> None:  # a thread here hands the helper one call at a time and waits for it
        while (index := take(1)) is not None:
            work, arguments = calls[index]
            try:
                out[index] = helper.submit(work, *arguments).result()
            except BrokenProcessPool:
                log.warning("the helper process stopped; this process does the rest of its work")
                with lock:
                    left.extend([index, *range(ends[0], ends[1] + 1)])
                    ends[1] = ends[0] - 1
                return
            advance()

    feeder = concurrent.futures.ThreadPoolExecutor(max_workers=1)
    fed = feeder.submit(feed)
    try:
        while (index := take(0)) is not None:
            out[index] = _done(*calls[index], advance)
    finally:
        with lock:
            ends[1] = ends[0] - 1  # on a failure here, the helper takes nothing more
        feeder.shutdown(wait=True)
    fed.result()  # the helper's failure, if any
    for index in sorted(left):
        out[index] = _done(*calls[index], advance)
    return out


def _done(work: Callable, arguments: tuple, advance: Callable[[], None]):
    result = work(*arguments)
    advance()
    return result
