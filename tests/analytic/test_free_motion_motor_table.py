"""A motor table at the documented cap (issue 30): 100,000 rows over 0.6 s restarted the
integration at every row (hours); only sharp kinks restart it now."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from analytic import load_case
from analytic.free_motion import simulate
from analytic.free_motion.integrate import kinks
from analytic.motion_spec import MAX_TABLE, FreeMotion, Motor

T = 0.6
#: Two integrations of the same equation (the same effort, tabulated in 2 or 100,000
#: rows): equal to the integration's tolerance, 1e-13, over the run.
SAME_MOTION = 1e-10


def _released(times, efforts):
    fm = FreeMotion("O2", math.radians(60.0), 0.0, T,
                    motors=(Motor("O2", 0.0, tuple(times), tuple(efforts)),))
    return replace(load_case("seed-four-bar"), gravity=(0.0, -9.81), motion=fm)


def test_dense_table_of_a_ramp_is_the_ramp():
    ts = np.linspace(0.0, T, MAX_TABLE)
    dense = simulate(_released(ts, 0.5 + 2.0 * ts))
    two = simulate(_released([0.0, T], [0.5, 0.5 + 2.0 * T]))
    assert len(dense.segments) == 1  # no restart at rows where nothing kinks
    t = np.linspace(0.0, T, 11)
    assert np.max(np.abs(dense.at(t, forces=False).x - two.at(t, forces=False).x)) \
        <= SAME_MOTION


def test_sharp_kinks_still_restart():
    ts = [0.0, 0.2, 0.4, T]
    es = [0.0, 1.0, -1.0, 0.0]
    assert kinks((Motor("O2", 0.0, tuple(ts), tuple(es)),), T) == [0.2, 0.4]
    smooth = np.linspace(0.0, T, 1000)
    assert kinks((Motor("O2", 0.0, tuple(smooth), tuple(np.sin(smooth))),), T) == []
