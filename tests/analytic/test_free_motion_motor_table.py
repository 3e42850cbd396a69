"""A motor table at the documented cap (issue 30): 100,000 rows over 0.6 s restarted the
integration at every row (hours); only sharp kinks restart it now."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from analytic import load_case
from analytic.errors import DescriptionError
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


@pytest.mark.parametrize("motor, message", [
    (Motor("O2", times=(), efforts=()), r"motor 0: table has 0 row\(s\): a motor table "
                                        r"needs at least 2 rows"),
    (Motor("O2", times=[], efforts=[]), r"motor 0: table has 0 row\(s\)"),
    (Motor("O2", times=(0.0, T)), r"motor 0: table: 2 times and 0 efforts"),
    (Motor("O2", efforts=(1.0, 2.0)), r"motor 0: table: 0 times and 2 efforts"),
    (Motor("O2", 1.0, (0.0, T), (1.0, 2.0)), r"motor 0: a motor needs exactly one of "
                                             r"effort .* not both"),
], ids=["empty-tuples", "empty-lists", "no-efforts", "no-times", "effort-and-table"])
def test_api_motor_table_without_rows_is_refused(motor, message):
    """The Python API's description constructor applies the file's rule: a table given
    with no rows (or half a table, or a table beside an effort) is one line naming the
    motor and the key; it ran as a motor of no effort (issue 30's xfail)."""
    fm = FreeMotion("O2", math.radians(60.0), 0.0, T, motors=(motor,))
    with pytest.raises(DescriptionError, match=message):
        replace(load_case("seed-four-bar"), gravity=(0.0, -9.81), motion=fm)


def test_constant_motor_is_not_a_table():
    """A constant motor (times and efforts not given) stays valid, equal to one built
    with the defaults after a copy or a pickle, and its identity holds () as before."""
    import pickle

    from reports.regression.model_identity import content
    m = Motor("O2", 0.4)
    assert not m.tabulated and m.times == () and m.efforts == ()
    for other in (pickle.loads(pickle.dumps(m)), replace(m, effort=0.4)):
        assert other == m and not other.tabulated
    fm = FreeMotion("O2", math.radians(60.0), 0.0, T, motors=(m,))
    mech = replace(load_case("seed-four-bar"), gravity=(0.0, -9.81), motion=fm)
    got = content(mech)
    assert got["motion.motors.0.times"] == [] and got["motion.motors.0.effort"] == 0.4
