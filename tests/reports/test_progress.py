"""Progress of long engine runs: on a terminal only, after a delay, gone at the end."""

from __future__ import annotations

import io
import time

from reports.comparison.progress import engine_progress


class Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_shows_on_a_terminal_after_the_delay():
    out = Tty()
    with engine_progress("pybullet: seed-four-bar, 1000 revolutions", out, after=0.05):
        time.sleep(0.6)
    assert "pybullet: seed-four-bar, 1000 revolutions" in out.getvalue()


def test_no_progress_when_not_a_terminal_or_short():
    out = io.StringIO()  # a pipe or a file: nothing, however long
    with engine_progress("x", out, after=0.0):
        time.sleep(0.2)
    assert out.getvalue() == ""
    tty = Tty()
    with engine_progress("short run", tty, after=5.0):
        pass
    assert "short run" not in tty.getvalue()
