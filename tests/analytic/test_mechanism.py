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


def scaled(mech, k):
    """The mechanism with every length multiplied by k (masses kept, inertia x k^2)."""
    def sc(p):
        return (p[0] * k, p[1] * k)
    bodies = tuple(replace(b, points={n: sc(p) for n, p in b.points.items()}, com=sc(b.com),
                           inertia=None if b.inertia is None else b.inertia * k * k)
                   for b in mech.bodies)
    hints = replace(mech.assembly, points={n: sc(p) for n, p in mech.assembly.points.items()})
    return replace(mech, bodies=bodies, assembly=hints)


@pytest.mark.parametrize("k", [1e-9, 1e-6, 1e3])
def test_validity_does_not_depend_on_scale(fb, k):
    """A 1e-9 m linkage is as valid as a 1 m one, and a link 1e-10 of the size is still
    a zero-length link at every scale (thresholds relative to the size)."""
    from analytic import Linkage
    m = scaled(fb, k)
    kin = Linkage(m).kinematics()
    assert kin.theta == pytest.approx(Linkage(fb).kinematics().theta, abs=1e-9)
    with pytest.raises(DescriptionError, match="zero link length"):
        replace(m, bodies=bodies_with(m, "coupler", points={"A": (0, 0), "B": (4e-11 * k, 0)}))


@pytest.mark.parametrize("change, message", [
    (lambda m: replace(m, bodies=bodies_with(m, "rocker", mass=1e308)),
     r"body 'rocker': mass = 1e\+308 kg is out of range: the accepted range is 0 to 1e\+09 kg"),
    (lambda m: replace(m, driver=Driver("O2", 1.0, 1e200)),
     r"driver: velocity = 1e\+200 rad/s is out of range"),
    (lambda m: replace(m, driver=Driver("O2", 1e308, 1.0)),
     r"driver: value = .* deg is out of range: .*<= 360000 deg"),
    (lambda m: replace(m, gravity=(0.0, float("nan"))), r"gravity must be a finite number"),
    (lambda m: scaled(m, 1e-13), r"the mechanism's size .* must be at least 1e-12 m"),
])
def test_out_of_range_values_through_the_api(fb, change, message):
    """The Python API enforces the ranges a file does (documented in analytic.mechanism)."""
    with pytest.raises(DescriptionError, match=message):
        change(fb)


@pytest.mark.parametrize("loops", [
    (("O2", "A", "B", "O4"),), (("B", "O4", "O2", "A"),), (("O4", "B", "A", "O2"),)])
def test_user_loops_any_start_and_direction(fb, loops):
    from analytic import Linkage
    k = Linkage(replace(fb, loops=loops)).kinematics()
    assert k.alpha == pytest.approx(Linkage(fb).kinematics().alpha, rel=1e-12)


def test_dependent_user_loops_are_rejected():
    six = load_case("six-bar")
    with pytest.raises(DescriptionError, match="loops: the loops are not independent"):
        replace(six, loops=(("O2", "A", "B", "O4"), ("O4", "B", "A", "O2")))
