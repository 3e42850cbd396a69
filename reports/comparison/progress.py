"""A progress line for engine runs that take a while (``xval plot --engine``, ``xval
compare``, ``xval animate --engine``): on standard error, only when it is a terminal,
and only once a run has lasted :data:`SHOW_AFTER_S` (a short run prints nothing).

An engine steps to its first sample in one call (a 1000-revolution run: 999 turns at
once), so the run's fraction done is not known while it steps; the line says what is
running (engine, case, revolutions) with a spinner and the time elapsed, as the
report's progress does (rich), and disappears when the run ends.  Where the run knows
how far it got (the exact free integration and its sampling, through their wall clock's
checks: :class:`analytic.free_motion.clock.WallClock`), the yielded
:class:`ProgressLine` adds that to the line: ``t = 1.2 s of 3 s``, ``120,000 of
1,000,000 samples``.
"""

from __future__ import annotations

import sys
import threading
from contextlib import contextmanager

from rich.console import Console
from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

#: Seconds a run lasts before its progress line appears.
SHOW_AFTER_S = 3.0


def _is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # a closed or replaced stream
        return False


class ProgressLine:
    """How far a run got, shown after the line's ``what`` (the callbacks of
    :class:`analytic.free_motion.clock.WallClock`); does nothing off a terminal."""

    def __init__(self, what: str):
        self.what, self.detail = what, ""
        self._show = None  # set once the line is on screen: shows a new description

    def __call__(self, detail: str) -> None:
        self.detail = detail
        if self._show is not None:
            self._show(self.text())

    def text(self) -> str:
        return f"{self.what}: {self.detail}" if self.detail else self.what

    def time(self, t: float, duration: float) -> None:
        """The integration reached ``t`` of ``duration`` s."""
        self(f"t = {t:.4g} s of {duration:g} s")

    def samples(self, done: int, total: int) -> None:
        """``done`` of ``total`` samples reconstructed."""
        self(f"{done:,} of {total:,} samples")


@contextmanager
def engine_progress(what: str, stream=None, after: float = SHOW_AFTER_S):
    """Around an engine run: after ``after`` seconds, a rich spinner line ``what`` with
    the elapsed time on ``stream`` (default standard error) if it is a terminal;
    nothing otherwise.  Yields a :class:`ProgressLine` (how far the run got, for a run
    that knows); the line is removed on exit."""
    stream = sys.stderr if stream is None else stream
    line = ProgressLine(what)
    if not _is_terminal(stream):
        yield line
        return
    pg = Progress(SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(),
                  console=Console(file=stream), transient=True)
    lock = threading.Lock()
    state = {"started": False, "done": False}

    def show():
        with lock:
            if state["done"]:
                return
            pg.start()
            task = pg.add_task(line.text(), total=None)
            line._show = lambda text: pg.update(task, description=text)
            state["started"] = True

    timer = threading.Timer(after, show)
    timer.daemon = True
    timer.start()
    try:
        yield line
    finally:
        timer.cancel()
        with lock:
            state["done"] = True
            line._show = None
            if state["started"]:
                pg.stop()


__all__ = ["SHOW_AFTER_S", "ProgressLine", "engine_progress"]
