"""A progress line for engine runs that take a while (``xval plot --engine``, ``xval
compare``, ``xval animate --engine``): on standard error, only when it is a terminal,
and only once a run has lasted :data:`SHOW_AFTER_S` (a short run prints nothing).

An engine steps to its first sample in one call (a 1000-revolution run: 999 turns at
once), so the run's fraction done is not known while it steps; the line says what is
running (engine, case, revolutions) with a spinner and the time elapsed, as the
report's progress does (rich), and disappears when the run ends.
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


@contextmanager
def engine_progress(what: str, stream=None, after: float = SHOW_AFTER_S):
    """Around an engine run: after ``after`` seconds, a rich spinner line ``what`` with
    the elapsed time on ``stream`` (default standard error) if it is a terminal;
    nothing otherwise.  Yields nothing; the line is removed on exit."""
    stream = sys.stderr if stream is None else stream
    if not _is_terminal(stream):
        yield
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
            pg.add_task(what, total=None)
            state["started"] = True

    timer = threading.Timer(after, show)
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()
        with lock:
            state["done"] = True
            if state["started"]:
                pg.stop()


__all__ = ["SHOW_AFTER_S", "engine_progress"]
