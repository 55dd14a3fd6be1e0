"""A report's figures drawn on every core.

Drawing is most of a report's time (0.3-1 s a figure, all of it on one core) and matplotlib is
not thread-safe, so a spare core draws in a process of its own: it takes the figures from the end
of the list while this process takes them from the front, until they meet.  The process is spawned
(this one may hold Dr.Jit's threads, which do not survive a fork) and needs about a second to
start; this process draws meanwhile, so nothing waits for it.  The helper is handed one figure at a
time, so neither waits for figures the other has queued.  A campaign starts it before its renders
(`figure_helper`), so that it is ready when the report begins.  Each figure is drawn whole by one
process, by the same code, so a figure does not depend on where it was drawn.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import importlib
import multiprocessing
import logging
import threading
from concurrent.futures.process import BrokenProcessPool
from typing import Callable

from vissim.optics.runtime.threads import available_cores

__all__ = ["draw_figures", "figure_helper", "FIGURES_WORTH_A_PROCESS"]

log = logging.getLogger(__name__)

#: Fewer figures than this are drawn here: a helper process costs about a second to start.
FIGURES_WORTH_A_PROCESS = 4


_STARTED: list = []  # the helper a `figure_helper` block started, while it lasts


@contextlib.contextmanager
def figure_helper(*modules: str):
    """Within the block, `draw_figures` shares its figures with a helper process started now, which imports
    ``modules`` (the report's) while this process goes on; none without a spare core or modules."""
    if available_cores() < 2 or not modules or _STARTED:
        yield
        return
    helper = _spawn_helper()
    helper.submit(_import_all, modules)
    _STARTED.append(helper)
    try:
        yield
    finally:
        _STARTED.clear()
        helper.shutdown(wait=True, cancel_futures=True)


def _spawn_helper() -> concurrent.futures.ProcessPoolExecutor:
    return concurrent.futures.ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"))


def _import_all(modules: tuple[str, ...]) -> None:
    for name in modules:
        importlib.import_module(name)


def draw_figures(calls: list[tuple[Callable, tuple]], advance: Callable[[], None] = lambda: None) -> list:
    """``[draw(*arguments) for draw, arguments in calls]``, shared with a helper process when a core is spare.

    Each ``draw`` must be a module-level function and its arguments picklable (they travel to the
    helper); put the slowest first, where this process starts.  ``advance()`` is called here after each
    figure, wherever it was drawn.
    """
    if available_cores() < 2 or len(calls) < FIGURES_WORTH_A_PROCESS:
        return [_drawn(draw, arguments, advance) for draw, arguments in calls]
    if _STARTED:
        return _shared(calls, advance, _STARTED[0])
    with _spawn_helper() as helper:
        return _shared(calls, advance, helper)


def _shared(calls: list[tuple[Callable, tuple]], advance: Callable[[], None], helper) -> list:
    """This process draws from the front of ``calls``, the helper from the back, one figure at a time each."""
    out: list = [None] * len(calls)
    ends = [0, len(calls) - 1]  # the next figure this process draws, the next the helper draws
    lock = threading.Lock()

    def take(side: int) -> int | None:
        with lock:
            if ends[0] > ends[1]:
                return None
            index = ends[side]
            ends[side] += 1 if side == 0 else -1
            return index

    left: list[int] = []  # figures the helper took but could not draw: it died (killed for memory, say)

    def feed() -> None:  # a thread here hands the helper one figure at a time and waits for it
        while (index := take(1)) is not None:
            draw, arguments = calls[index]
            try:
                out[index] = helper.submit(draw, *arguments).result()
            except BrokenProcessPool:
                log.warning("the figure helper process stopped; this process draws the rest of the figures")
                left.append(index)
                with lock:
                    left.extend(range(ends[0], ends[1] + 1))
                    ends[1] = ends[0] - 1
                return
            advance()

    feeder = concurrent.futures.ThreadPoolExecutor(max_workers=1)
    fed = feeder.submit(feed)
    try:
        while (index := take(0)) is not None:
            draw, arguments = calls[index]
            out[index] = _drawn(draw, arguments, advance)
    finally:
        with lock:
            ends[1] = ends[0] - 1  # on a failure here, the helper takes nothing more
        feeder.shutdown(wait=True)
    fed.result()  # the helper's failure, if any
    for index in sorted(left):
        draw, arguments = calls[index]
        out[index] = _drawn(draw, arguments, advance)
    return out


def _drawn(draw: Callable, arguments: tuple, advance: Callable[[], None]):
    figure = draw(*arguments)
    advance()
    return figure
