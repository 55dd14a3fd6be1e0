"""Progress of long calls, decided once: the library reports through a callback, the command line draws it.

A library function that can run for more than a few seconds takes ``progress``, a callable
``progress(stage, done, total)``: after each step of a named stage (a render, an item, a depth
layer, a least-squares fit) it is called with the steps done so far, rising 1, 2, ... ``total``.
The library never prints; `terminal_progress` turns the calls into one bar per stage on
standard error (a terminal only), as every command of `vissim.cli` shows it.
"""

from __future__ import annotations

import contextlib
import sys
import threading
from collections.abc import Callable, Iterator

__all__ = ["Progress", "counter", "terminal_progress"]

#: ``progress(stage, done, total)``: ``done`` steps of ``stage`` finished out of ``total``.
Progress = Callable[[str, int, int], None]


def counter(progress: Progress | None, stage: str, total: int) -> Callable[[], None]:
    """A function to call after each step of ``stage``, from any thread: reports 1, 2, ... ``total`` (nothing without
    ``progress``)."""
    done = 0
    lock = threading.Lock()

    def step() -> None:  # from any thread
        nonlocal done
        with lock:
            done += 1
            if progress is not None:
                progress(stage, done, total)

    return step


@contextlib.contextmanager
def terminal_progress(stream=None) -> Iterator[Progress | None]:
    """A `Progress` that draws a bar per stage (rich) on ``stream`` (default standard error), removed at the end.

    Yields None when the stream is not a terminal (a pipe, a log file, a test): nothing is drawn.
    """
    stream = sys.stderr if stream is None else stream
    if not (hasattr(stream, "isatty") and stream.isatty()):
        yield None
        return
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    bars = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn(),
                    console=Console(file=stream), transient=True)
    tasks: dict[str, int] = {}

    def report(stage: str, done: int, total: int) -> None:
        if stage not in tasks:
            tasks[stage] = bars.add_task(stage, total=total)
        bars.update(tasks[stage], completed=done, total=total)

    with bars:
        yield report
