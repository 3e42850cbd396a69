"""Free-motion descriptions written back to TOML (issue 20): ``mechanism_to_toml`` keeps
``[motion]``, ``[[springs]]``, ``[[dampers]]`` and ``[[motors]]``.

Expected: the description read from the shipped case file itself.  Lengths, masses,
rates and efforts are written with ``repr`` and read back exactly; angles pass through
degrees, so they read back to the rounding of that conversion (:data:`ANGLE_ABS`).
"""

from __future__ import annotations

import dataclasses
import math
import tomllib

import pytest

from analytic import load_case
from analytic.cases import free_case_names
from analytic.motion_spec import (
    FreeMotion,
    JointDamper,
    JointSpring,
    Motor,
    PointDamper,
    PointSpring,
)
from analytic.toml_io import mechanism_from_dict, mechanism_to_toml

#: rad -> deg -> rad: a few units of double rounding on angles of a few radians.
ANGLE_ABS = 1e-14


def _same(a, b, where="mech"):
    """Equal trees of dataclasses, tuples, dicts and numbers; floats to ANGLE_ABS
    (exact for everything the writer does not convert, which the float repr keeps)."""
    if dataclasses.is_dataclass(a):
        assert type(a) is type(b), where
        for fl in dataclasses.fields(a):
            if fl.name != "source":
                _same(getattr(a, fl.name), getattr(b, fl.name), f"{where}.{fl.name}")
    elif isinstance(a, dict):
        assert set(a) == set(b), where
        for k in a:
            _same(a[k], b[k], f"{where}[{k!r}]")
    elif isinstance(a, tuple | list):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _same(x, y, f"{where}[{i}]")
    elif isinstance(a, float) and not isinstance(b, str):
        assert math.isclose(a, b, rel_tol=0.0, abs_tol=ANGLE_ABS) or a == b, (where, a, b)
    else:
        assert a == b, where


def _round_trip(mech):
    return mechanism_from_dict(tomllib.loads(mechanism_to_toml(mech)), "<round trip>")


@pytest.mark.parametrize("name", free_case_names())
def test_free_case_round_trip(name):
    m = load_case(name)
    assert m.motion is not None
    _same(m, _round_trip(m))


def test_every_element_kind_round_trips():
    """Point and joint springs and dampers on revolute and prismatic joints, a constant
    motor and a table motor: all written and read back."""
    m = load_case("seed-slider-crank")
    fm = FreeMotion("A", 0.5, -3.0, 2.5, 17,
                    springs=(PointSpring("rod", "G3", "ground", "A", 30.0, 0.25),
                             JointSpring("slide", 2000.0, 0.123), JointSpring("A", 0.5, 0.3)),
                    dampers=(PointDamper("crank", "B", "piston", "C", 0.5),
                             JointDamper("slide", 1.0), JointDamper("B", 0.01)),
                    motors=(Motor("A", 0.7), Motor("slide", 0.0, (0.0, 1.0, 2.5),
                                                    (0.0, -2.0, 1.5))))
    m = dataclasses.replace(m, motion=fm)
    back = _round_trip(m)
    _same(m, back)
    assert back.motion.samples == 17 and len(back.motion.motors[1].times) == 3
