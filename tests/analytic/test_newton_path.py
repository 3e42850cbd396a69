"""The Newton path (no dyad plan): assembly by the hints, continuation, limit positions.

Four-bars are forced onto the Newton path (the dyad planner patched out) so that the
circle-intersection closed form and the law of cosines check it independently."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import analytic.topology as topology
from analytic import AssemblyError, Linkage, load_case

from .conftest_helpers import four_bar

DATA = Path(__file__).parent / "data"

#: The limit positions are bisected to LIMIT_BISECTION (1e-10 rad); the issue asks 1e-9.
LIMIT_TOL = 1e-9


@pytest.fixture
def newton_only(monkeypatch):
    monkeypatch.setattr(topology, "_dyad_plan", lambda topo: None)


def _rocker_by_hand(g, a, b, c, theta2, side):
    """Rocker angle (rad) of a four-bar O2 = 0, O4 = (g, 0): B on |B - A| = b,
    |B - O4| = c, on the ``side`` (+1 left of A -> O4) of the line A-O4."""
    A = a * np.stack([np.cos(theta2), np.sin(theta2)], axis=1)
    d = np.array([g, 0.0]) - A
    D = np.linalg.norm(d, axis=1)
    along = (D ** 2 + b * b - c * c) / (2 * D)
    h = np.sqrt(b * b - along ** 2)
    n = np.stack([-d[:, 1], d[:, 0]], axis=1) / D[:, None]
    B = A + along[:, None] * d / D[:, None] + side * h[:, None] * n
    return np.arctan2(B[:, 1], B[:, 0] - g)


def _wrap(a):
    return (np.asarray(a) + math.pi) % (2 * math.pi) - math.pi


@pytest.mark.parametrize("open_branch", [True, False])
def test_newton_path_full_turn_any_inputs(newton_only, open_branch):
    """Assembled by the point hint on either branch, continued over one turn (the trace
    closes: periodic), and evaluated at an engine's inputs (three turns, reversing)."""
    g, a, b, c = 0.4, 0.1, 0.3, 0.25
    lk = Linkage(four_bar(g, a, b, c, open_branch=open_branch, masses=None))
    assert lk.topo.plan is None and lk.positions.trace.period == pytest.approx(2 * math.pi)
    x = np.concatenate([np.radians(np.arange(60, 1140, 7.0)),
                        np.radians(np.arange(1140, -300, -11.0))])
    kin = lk.kinematics_along(x)
    want = _rocker_by_hand(g, a, b, c, x, 1 if open_branch else -1)
    np.testing.assert_allclose(_wrap(kin.theta[:, 3] - want), 0.0, atol=1e-10)


def test_newton_path_limited_range_by_bisection(newton_only):
    """A triple-rocker's input limits, where |A O4| = coupler + rocker (law of cosines),
    found by continuation to 1e-9 rad; the sweep ends there with limit events; outside,
    a typed error with the range."""
    g, a, b, c = 0.32, 0.25, 0.2, 0.15
    lk = Linkage(four_bar(g, a, b, c, theta=math.radians(30), masses=None))
    limit = math.acos((a * a + g * g - (b + c) ** 2) / (2 * a * g))
    (lo, hi), = lk.feasible_ranges()
    assert hi == pytest.approx(limit, abs=LIMIT_TOL)
    assert lo == pytest.approx(-limit, abs=LIMIT_TOL)
    res = lk.sweep(200)
    lim = res.events[(res.events.kind == "limit") & (res.events["where"] == "O2")]["input"]
    np.testing.assert_allclose(sorted(lim), np.degrees([-limit, limit]), atol=1e-7)
    with pytest.raises(AssemblyError, match=r"cannot close at driver 'O2' = 80 deg.*"
                                            r"feasible input range"):
        lk.kinematics(math.radians(80))
    # a whole turn off the range is the same position
    th = lk.kinematics([0.5, 0.5 + 2 * math.pi, 0.5 - 4 * math.pi]).theta
    np.testing.assert_allclose(_wrap(th[1:] - th[0]), 0.0, atol=1e-12)
    # inside the range, the open branch by hand
    x = np.linspace(-limit + 1e-6, limit - 1e-6, 101)
    kin = lk.kinematics(x, on_singular="flag")
    np.testing.assert_allclose(_wrap(kin.theta[:, 3] - _rocker_by_hand(g, a, b, c, x, 1)),
                               0.0, atol=1e-6)


def test_newton_path_hint_at_1e9_scale(newton_only):
    """The tiny-point-hint four-bar (1e-9 m) on the Newton path: the hinted open branch,
    rocker 110.753 deg (the issue's figure; the circle intersection gives the rest)."""
    lk = Linkage(load_case(DATA / "tiny-point-hint.toml"))
    got = lk.kinematics().theta[0, lk.body_index("rocker")]
    want = _rocker_by_hand(4e-10, 1e-10, 3e-10, 2.5e-10, np.radians([60.0]), 1)[0]
    assert _wrap(got - want) == pytest.approx(0.0, abs=1e-12)
    assert math.degrees(want) == pytest.approx(110.753, abs=1e-3)
    # continuation works at that scale too (the Newton tolerances are relative)
    kin = lk.kinematics_along(np.radians([0.0, 200.0, 420.0]))
    np.testing.assert_allclose(
        _wrap(kin.theta[:, 3] - _rocker_by_hand(4e-10, 1e-10, 3e-10, 2.5e-10,
                                                np.radians([0.0, 200.0, 420.0]), 1)),
        0.0, atol=1e-9)


def test_newton_path_angle_hints_pick_the_assembly(newton_only):
    """Angle hints alone choose between the two assemblies too."""
    from analytic import Assembly
    g, a, b, c = 0.4, 0.1, 0.3, 0.25
    for side in (1, -1):
        want = _rocker_by_hand(g, a, b, c, np.array([math.pi / 3]), side)[0]
        mech = four_bar(g, a, b, c, masses=None)
        mech = type(mech)(**{**mech.__dict__, "assembly": Assembly({}, {"rocker": want + 0.2})})
        lk = Linkage(mech)
        assert _wrap(lk.kinematics().theta[0, 3] - want) == pytest.approx(0.0, abs=1e-12)


def test_newton_path_continues_through_a_change_point(newton_only):
    """The parallelogram on the Newton path: the continuation crosses its flat positions
    (180 and 360 deg, located to 1e-9 rad) and stays a parallelogram (rocker parallel to
    the crank); the sweep lists the crossings as change points."""
    lk = Linkage(load_case(DATA / "parallelogram-four-bar.toml"))
    tr = lk.positions.trace
    assert tr.period == pytest.approx(2 * math.pi) and not tr.limits
    np.testing.assert_allclose(tr.crossings, [math.pi, 2 * math.pi], atol=LIMIT_TOL)
    x = np.radians(np.arange(0.5, 1080, 7.0))
    kin = lk.kinematics_along(x)
    np.testing.assert_allclose(_wrap(kin.theta[:, 3] - kin.theta[:, 1]), 0.0, atol=1e-9)
    res = lk.sweep(72, start=0.0)
    cp = res.events[res.events.kind == "change_point"]["input"].to_numpy()
    np.testing.assert_allclose(np.sort(np.mod(cp, 360)), [0.0, 180.0], atol=1e-6)
