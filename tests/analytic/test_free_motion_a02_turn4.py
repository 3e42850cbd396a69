"""A02's N four-bar chains (issue 30 reproducers): event location that cannot raise,
each stretched pass listed once, and a release at rest in the upright equilibrium."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from analytic.free_motion import simulate
from analytic.toml_io import load_mechanism

BUGS = Path(__file__).resolve().parents[1] / "data" / "bugs" / "turn4"


def _crossings_of_multiples_of_pi(traj) -> int:
    """How often the integrated angle passes a multiple of pi (where the N four-bar's
    parallelograms all stretch), counted from the trajectory sampled every 0.5 ms."""
    t = np.linspace(0.0, traj.duration, int(traj.duration / 5e-4) + 1)
    y, _ = traj.state(t)
    k = np.floor(y[:, 0] / math.pi)
    return int(np.sum(np.abs(np.diff(k))))


def _check_each_pass_once(name):
    traj = simulate(load_mechanism(BUGS / name), duration=20.0)
    sing = [e for e in traj.events if e.kind == "singular"]
    assert len(sing) == _crossings_of_multiples_of_pi(traj)
    assert np.all(np.diff([e.t for e in sing]) > 1e-3)


def test_a02_n9_events_without_traceback():
    """Before: RuntimeError from brentq (100 iterations) in find_events after 13 s."""
    _check_each_pass_once("A02_N9_brentq_traceback.toml")


def test_a02_n21_each_stretched_pass_listed_once():
    """Before: 30 singular events for 20 passes (the determinant's flat root 2e-7 s from
    the change point's, both listed)."""
    _check_each_pass_once("A02_N21_duplicate_events.toml")


def test_a02_n4_released_at_rest_upright_is_held():
    """At rest in the upright (unstable) equilibrium the exact motion is rest; before, the
    chain fell (B0 2 m off at 12 s) from amplified round-off, with no note."""
    traj = simulate(load_mechanism(BUGS / "A02_N4_v0_upright_rest.toml"), duration=20.0)
    s = traj.at(np.linspace(0.0, 20.0, 21), forces=False)
    assert np.ptp(s.x, axis=0).max() == 0.0
    stops = [e for e in traj.events if e.kind == "stop"]
    assert len(stops) == 1 and "held" in stops[0].detail
