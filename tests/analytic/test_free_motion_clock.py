"""The exact integration's wall-clock limit (issue 30): checked at every evaluation of
the equation of motion, so a long run stops within a fraction of a second of the limit
with one line naming it and how far the run got."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from analytic.errors import LinkageError
from analytic.free_motion import MAX_WALL_LIMIT, WallLimitError, simulate
from analytic.toml_io import load_mechanism

BUGS = Path(__file__).resolve().parents[1] / "data" / "bugs" / "turn4"


def test_duration_1e4_stops_at_the_wall_limit_with_one_line():
    mech = load_mechanism(BUGS / "F6_duration_1e4.toml")
    with pytest.raises(WallLimitError, match=r"wall-clock limit of 1 s at t = .* of 10000 s"):
        simulate(mech, duration=1e4, wall_limit=1.0)


@pytest.mark.parametrize("bad", [0.0, -1.0, MAX_WALL_LIMIT * 2, float("nan"), True])
def test_wall_limit_range(bad):
    mech = load_mechanism(BUGS / "F6_duration_1e4.toml")
    with pytest.raises(LinkageError, match="wall_limit"):
        simulate(mech, duration=1.0, wall_limit=bad)


def test_sim_models_range_uses_the_same_bound():
    from sim_models.engines.ranges import WALL_LIMIT
    assert WALL_LIMIT.hi == MAX_WALL_LIMIT


class _PacedClock:
    """A wall clock that moves :data:`TICK_S` at every reading: the run's progress is
    paced by its own evaluations, not by the machine's load (under ``pytest -n 2`` on a
    busy machine the set-up alone took the real 1 s limit and nothing was reported)."""

    TICK_S = 0.05

    def __init__(self):
        self.now = 0.0

    def monotonic(self) -> float:
        self.now += self.TICK_S
        return self.now


def test_progress_is_reported_with_the_time_reached(monkeypatch):
    """The command line shows it on a terminal; the library reports (t, duration) every
    quarter second of wall-clock time."""
    from analytic.free_motion import clock
    mech = load_mechanism(BUGS / "F6_duration_1e4.toml")
    monkeypatch.setattr(clock, "time", _PacedClock())  # a reading every evaluation
    seen = []
    with pytest.raises(WallLimitError):
        simulate(mech, duration=1e4, wall_limit=1.0, progress=lambda t, T: seen.append((t, T)))
    assert seen and all(T == 1e4 for _, T in seen)
    assert [t for t, _ in seen] == sorted(t for t, _ in seen) and seen[-1][0] > 0.0


class FakeTime:
    """A monotonic clock that advances ``step`` s at every reading (no real waiting)."""

    def __init__(self, step: float):
        self.now, self.step = 0.0, step

    def __call__(self) -> float:
        self.now += self.step
        return self.now


def _short_run():
    from reports.comparison.free_cases import free_case
    return simulate(free_case("seed-four-bar"), duration=0.05)


def test_sampling_checks_the_wall_clock_between_chunks():
    """Sampling (issue 30's shortfall: 1e6 samples ran 155 s past any limit) checks the
    same clock before every chunk of SAMPLE_CHUNK samples and stops past its limit with
    the samples done of N.  A fake clock advancing 1 s per reading, limit 1.5 s: the
    readings at construction (1 s), before chunk 0 (2 s: 1 s elapsed) and before chunk 1
    (3 s: 2 s elapsed, past the limit) stop it with one chunk done."""
    from analytic.free_motion.clock import SAMPLE_CHUNK, WallClock
    traj = _short_run()
    clock = WallClock("run", traj.duration, 1.5, now=FakeTime(1.0))
    n = 5 * SAMPLE_CHUNK
    with pytest.raises(WallLimitError, match=rf"sampling the exact trajectory reached the "
                       rf"wall-clock limit of 1.5 s at {SAMPLE_CHUNK:,} of {n:,} samples"):
        traj.at(np.linspace(0.0, traj.duration, n), forces=False, clock=clock)


def test_sampling_in_chunks_gives_the_samples_at_once_and_reports_progress():
    """Chunks change nothing: each sample of a chunked call equals the same time sampled
    alone (forces included: a chunk's load scale differs, so to rounding); progress
    reports (done, N) in chunk steps."""
    from analytic.free_motion.clock import SAMPLE_CHUNK, WallClock
    traj = _short_run()
    n = 2 * SAMPLE_CHUNK + 7
    t = np.linspace(0.0, traj.duration, n)
    seen = []
    clock = WallClock("run", traj.duration, None, sample_progress=lambda k, N: seen.append(
        (k, N)), now=FakeTime(1.0))
    many = traj.at(t, clock=clock)
    for i in (0, SAMPLE_CHUNK - 1, SAMPLE_CHUNK, n - 1):
        one = traj.at(t[i:i + 1])
        np.testing.assert_allclose(many.x[i], one.x[0], rtol=0, atol=1e-14)
        np.testing.assert_allclose(many.xdd[i], one.xdd[0], rtol=1e-13, atol=1e-12)
        for j, f in one.reactions.items():
            np.testing.assert_allclose(many.reactions[j][i], f[0], rtol=1e-12, atol=1e-12)
    assert seen == [(k, n) for k in range(0, n, SAMPLE_CHUNK)]


def test_progress_reports_the_time_reached_with_a_fake_clock():
    """The integration's progress callback gets (t, duration) from the clock's checks,
    t increasing to the duration (a fake clock: a report at every check)."""
    from analytic.free_motion import clock as clk
    seen = []
    c = clk.WallClock("run", 2.0, None, progress=lambda t, T: seen.append((t, T)),
                      now=FakeTime(1.0))
    for t in (0.1, 0.5, 0.4, 1.9):
        c.check(t)
    assert seen == [(0.1, 2.0), (0.5, 2.0), (0.5, 2.0), (1.9, 2.0)]
