"""The exact integration's wall-clock limit (issue 30): checked at every evaluation of
the equation of motion, so a long run stops within a fraction of a second of the limit
with one line naming it and how far the run got."""

from __future__ import annotations

from pathlib import Path

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
