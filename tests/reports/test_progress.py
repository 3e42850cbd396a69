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


def test_the_line_shows_how_far_the_run_got():
    """The exact side's line shows the simulated time reached of the total, then the
    samples done of N (issue 30: it showed the elapsed time only)."""
    out = Tty()
    with engine_progress("exact integration: x, free motion 3 s", out, after=0.05) as line:
        line.time(1.25, 3.0)
        time.sleep(0.4)
        line.samples(120000, 1000000)
        time.sleep(0.4)
    text = out.getvalue()
    assert "exact integration: x, free motion 3 s: t = 1.25 s of 3 s" in text
    assert "120,000 of 1,000,000 samples" in text


def test_simulate_feeds_the_line_from_the_wall_clock_checks(monkeypatch, tmp_path):
    """``xval simulate`` hands its progress line to the exact integration's and the
    sampling's clock checks: every report (here one at every check) is t of the
    duration, then samples done of N, in order."""
    from contextlib import contextmanager

    from analytic.free_motion import clock
    from reports.cli import simulate as cli
    from reports.comparison.progress import ProgressLine
    from tests.reports.cli_run import run

    shown = []

    class Recorder(ProgressLine):
        def __call__(self, detail: str) -> None:
            shown.append(detail)

    @contextmanager
    def fake(what, *a, **k):
        yield Recorder(what)

    monkeypatch.setattr(clock, "PROGRESS_EVERY_S", -1.0)
    monkeypatch.setattr(cli, "engine_progress", fake)
    code, _ = run("simulate", "seed-four-bar", "--duration", "0.05", "--samples", "5001")
    assert code == 0
    times = [d for d in shown if d.startswith("t = ")]
    samples = [d for d in shown if d.endswith(" samples")]
    assert times and all(d.endswith(" s of 0.05 s") for d in times)
    assert samples == ["0 of 5,001 samples", "2,000 of 5,001 samples",
                       "4,000 of 5,001 samples"]
    assert shown.index(samples[0]) > shown.index(times[-1])
