"""A person as the observer of the threshold procedure.

* `WindowObserver` -- a black window with a single lit pixel (matplotlib ``figimage``, so
  one array element is one screen pixel) at the requested code value; the person answers with
  the keys ``y`` (seen), ``n`` (not seen) or ``q`` (quit).  A screen shows 8-bit code values, so
  intensities are quantised to steps of 1/255 on the display: a phase-2 resolution finer than that
  only repeats the same stimulus.  This is a desktop stand-in, not the thesis's tube.
* `PromptObserver` -- a terminal fallback for headless use and for operating the real
  apparatus: the prompt names the code value for the operator to set on the device, and the
  answer (y/n/q) is read with an injected ``ask`` function (``input`` by default; tests pass a
  scripted one).

`make_person_observer` picks the window when a display and an interactive matplotlib backend
are available, else the prompt.  The library never prints: all I/O goes through ``ask`` or the window.
"""

from __future__ import annotations

import builtins
import logging
import os
import sys
from collections.abc import Callable

import numpy as np

from vissim.errors import VissimError, VissimInputError

__all__ = ["ProcedureAborted", "PromptObserver", "WindowObserver", "make_person_observer"]

log = logging.getLogger(__name__)

YES = frozenset({"y", "yes", "s", "sim", "1", "seen"})
NO = frozenset({"n", "no", "nao", "não", "0", "not seen"})
QUIT = frozenset({"q", "quit", "exit"})
MAX_INVALID_ANSWERS = 20
INTERACTIVE_BACKENDS = ("TkAgg", "QtAgg", "GTK3Agg", "MacOSX")


class ProcedureAborted(VissimError):
    """The person stopped the procedure (q, end of input, or the window closed)."""


class PromptObserver:
    """Asks "seen?" through ``ask(prompt) -> str`` (the built-in ``input`` by default)."""

    def __init__(self, ask: Callable[[str], str] | None = None, *, show_intensity: bool = True):
        self._ask = ask if ask is not None else (lambda prompt: builtins.input(prompt))
        self._show_intensity = show_intensity
        self.count = 0

    def seen(self, intensity: float) -> bool:
        self.count += 1
        stimulus = f"set the pixel to code value {intensity:.4f}; " if self._show_intensity else "stimulus shown; "
        prompt = f"[{self.count}] {stimulus}seen? [y/n, q to quit] "
        for _ in range(MAX_INVALID_ANSWERS):
            try:
                answer = self._ask(prompt)
            except EOFError:
                raise ProcedureAborted("the input ended before the procedure finished") from None
            answer = (answer or "").strip().lower()
            if answer in YES:
                return True
            if answer in NO:
                return False
            if answer in QUIT:
                raise ProcedureAborted("the observer quit the procedure")
            prompt = f"[{self.count}] please answer y (seen), n (not seen) or q (quit): "
        raise ProcedureAborted(f"{MAX_INVALID_ANSWERS} unreadable answers in a row")


def _interactive_pyplot():
    """pyplot on an interactive backend, or ``None`` (no display, no GUI toolkit)."""
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return None
    import matplotlib
    import matplotlib.pyplot as plt

    current = matplotlib.get_backend()
    if current.lower() not in ("agg", "pdf", "svg", "ps", "cairo", "template") and "inline" not in current.lower():
        return plt
    for backend in INTERACTIVE_BACKENDS:
        try:
            plt.switch_backend(backend)
            return plt
        except Exception:  # noqa: BLE001 -- toolkit missing or unusable: try the next
            continue
    return None


class WindowObserver:
    """One lit pixel in the centre of a black ``size_px`` x ``size_px`` window; keys y / n / q."""

    def __init__(self, size_px: int = 401, *, pyplot=None):
        plt = pyplot or _interactive_pyplot()
        if plt is None:
            raise VissimInputError("no display for the stimulus window; use --display terminal")
        if int(size_px) < 3:
            raise VissimInputError(f"window size must be >= 3 px, got {size_px!r} px")
        self._plt = plt
        self._size = int(size_px) | 1
        dpi = 100.0
        self._fig = plt.figure(figsize=(self._size / dpi, self._size / dpi), dpi=dpi, facecolor="black")
        self._frame = np.zeros((self._size, self._size, 3))
        self._image = self._fig.figimage(self._frame, xo=0, yo=0, origin="upper")
        self._answer: str | None = None
        self._fig.canvas.mpl_connect("key_press_event", self._on_key)
        if self._fig.canvas.manager is not None:
            self._fig.canvas.manager.set_window_title("vissim ATV: y = seen, n = not seen, q = quit")
        plt.show(block=False)

    def _on_key(self, event) -> None:
        if event.key in ("y", "n", "q"):
            self._answer = event.key

    def seen(self, intensity: float) -> bool:
        c = self._size // 2
        self._frame[:] = 0.0
        self._frame[c, c, :] = float(np.clip(intensity, 0.0, 1.0))
        self._image.set_data(self._frame)
        self._fig.canvas.draw_idle()
        self._answer = None
        while self._answer is None:
            if not self._plt.fignum_exists(self._fig.number):
                raise ProcedureAborted("the stimulus window was closed")
            self._plt.pause(0.05)
        if self._answer == "q":
            raise ProcedureAborted("the observer quit the procedure")
        return self._answer == "y"

    def close(self) -> None:
        self._plt.close(self._fig)


def make_person_observer(display: str = "auto", ask: Callable[[str], str] | None = None):
    """``display``: ``"window"``, ``"terminal"`` or ``"auto"`` (window if possible)."""
    if display not in ("auto", "window", "terminal"):
        raise VissimInputError(f"display must be 'auto', 'window' or 'terminal', got {display!r}")
    if display == "terminal":
        return PromptObserver(ask)
    plt = _interactive_pyplot()
    if plt is None:
        if display == "window":
            raise VissimInputError("no display for the stimulus window (no $DISPLAY or GUI toolkit); use --display terminal")
        log.info("no display: asking in the terminal")
        return PromptObserver(ask)
    return WindowObserver(pyplot=plt)
