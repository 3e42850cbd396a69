"""Validation of the description: every inconsistency is a typed error naming its place."""

from __future__ import annotations

from dataclasses import replace

import pytest

from analytic import Body, DescriptionError, Driver, Load, Revolute, load_case
from analytic.cases import load_case as load


@pytest.fixture
def fb():
    return load_case("seed-four-bar")


def bodies_with(mech, name, **kw):
    return tuple(replace(b, **kw) if b.name == name else b for b in mech.bodies)


def joints_with(mech, name, new):
    return tuple(new if j.name == name else j for j in mech.joints)


@pytest.mark.parametrize("change, message", [
    (lambda m: replace(m, joints=joints_with(m, "A", Revolute("A", "crank", "A", "coupling",
                                                                "A"))),
     r"joint 'A'.*unknown body 'coupling'"),
    (lambda m: replace(m, joints=joints_with(m, "A", Revolute("A", "crank", "A", "coupler",
                                                                "Q"))),
     r"joint 'A'.*body 'coupler' has no point 'Q'"),
    (lambda m: replace(m, joints=joints_with(m, "A", Revolute("A", "crank", "A", "crank",
                                                                "O2"))),
     r"joint 'A'.*joins body 'crank' to itself"),
    (lambda m: replace(m, bodies=bodies_with(m, "coupler", points={"A": (0, 0), "B": (0, 0)})),
     r"body 'coupler'.*same point \(zero link length\)"),
    (lambda m: replace(m, bodies=bodies_with(m, "rocker", mass=-0.5)),
     r"body 'rocker'.*mass must be >= 0"),
    (lambda m: replace(m, bodies=bodies_with(m, "rocker", inertia=0.0)),
     r"body 'rocker'.*inertia .* must be > 0"),
    (lambda m: replace(m, bodies=bodies_with(m, "rocker", inertia=None)),
     r"body 'rocker'.*needs an inertia"),
    (lambda m: replace(m, joints=m.joints[:3]),
     r"3 degrees of freedom by Gruebler"),
    (lambda m: replace(m, bodies=m.bodies + (Body("loose", {"P": (0, 0)}),)),
     r"not connected to ground"),
    (lambda m: replace(m, driver=Driver("Q", 0.0, 1.0)), r"driver joint 'Q' is not a joint"),
    (lambda m: replace(m, ground="base"), r"ground body 'base' is not among the bodies"),
    (lambda m: replace(m, loads=(Load("rocker", "X", (1.0, 0.0)),)),
     r"load 0 on body 'rocker'.*no point 'X'"),
    (lambda m: replace(m, joints=m.joints + (m.joints[0],)), r"duplicate joint names \['O2'\]"),
    (lambda m: replace(m, bodies=bodies_with(m, "crank", points={"O2": (0, 0),
                                                                 "A": (float("inf"), 0)})),
     r"body 'crank'.*point 'A' must be a finite number"),
])
def test_bad_descriptions(fb, change, message):
    with pytest.raises(DescriptionError, match=message) as e:
        change(fb)
    assert "seed-four-bar.toml" in str(e.value), "the error names the file"


def test_unknown_case():
    with pytest.raises(DescriptionError, match=r"no built-in case 'four-bar'.*seed-four-bar"):
        load("four-bar")
