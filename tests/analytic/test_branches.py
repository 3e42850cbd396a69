"""Branches continued through change points, checked against the parallelogram's own
geometry: on the parallelogram branch the rocker stays parallel to the crank and the
coupler translates (theta4 = theta2, omega3 = alpha3 = 0), and with uniform rods at
constant speed without loads the kinetic energy is constant, so the drive torque is 0."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from analytic import Linkage, load_case
from analytic.sweep import nearest_event
from reports.cli.xval import main

from .conftest_helpers import four_bar

DATA = Path(__file__).parent / "data"
PARA = DATA / "parallelogram-four-bar.toml"

#: Angles and rates on the continued branch match the parallelogram's to rounding; the
#: samples stay 0.25 deg from the flat positions, where the closed form's snapping to the
#: toggle (TOGGLE_SNAP) does not act.
ANGLE_TOL = 1e-9


def _wrap(a):
    return (np.asarray(a) + math.pi) % (2 * math.pi) - math.pi


def _engine_like_inputs():
    """An engine's sampled inputs: four turns forward from the reference, then back
    over two turns (not monotonic), avoiding the flat positions by 0.25 deg."""
    fwd = np.radians(30 + np.arange(0, 1440, 2.5))
    back = fwd[-1] - np.radians(np.arange(0, 720, 3.5))
    x = np.concatenate([fwd, back])
    keep = np.abs(_wrap(x * 2) / 2) > np.radians(0.25)  # away from 0 and 180 deg
    return x[keep]


def test_parallelogram_stays_a_parallelogram_over_turns_and_reversals():
    lk = Linkage(load_case(PARA))
    x = _engine_like_inputs()
    kin = lk.kinematics_along(x)
    b = {n: lk.body_index(n) for n in ("crank", "coupler", "rocker")}
    np.testing.assert_allclose(_wrap(kin.theta[:, b["rocker"]] - kin.theta[:, b["crank"]]),
                               0.0, atol=ANGLE_TOL)
    np.testing.assert_allclose(_wrap(kin.theta[:, b["coupler"]]), 0.0, atol=ANGLE_TOL)
    w = kin.velocity[0]
    np.testing.assert_allclose(kin.omega[:, b["rocker"]], w, atol=ANGLE_TOL * abs(w))
    np.testing.assert_allclose(kin.omega[:, b["coupler"]], 0.0, atol=ANGLE_TOL * abs(w))
    np.testing.assert_allclose(kin.alpha[:, b["coupler"]], 0.0, atol=ANGLE_TOL * w * w)
    # constant kinetic energy, no loads: the drive torque is zero.  Scale: the torque of
    # the coupler's centripetal inertia force about O2, m3 a w^2 * a.
    frc = lk.forces(kin)
    scale = 0.8 * 0.1 * w * w * 0.1
    assert np.max(np.abs(frc.effort)) < 1e-9 * scale


def test_kinematics_order_does_not_matter():
    """The branch depends on the input value, not on the order of the batch."""
    lk = Linkage(load_case(PARA))
    x = _engine_like_inputs()
    perm = np.random.default_rng(3).permutation(len(x))
    a = lk.kinematics_along(x).theta
    b = lk.kinematics_along(x[perm]).theta
    np.testing.assert_allclose(_wrap(a[perm] - b), 0.0, atol=1e-12)


def test_holding_the_sign_gives_the_anti_parallelogram():
    """``branch_rule="hold"`` keeps the dyad sign past 180 deg: the rocker then leaves
    the crank's direction (the crossed branch), as the old solver did."""
    lk = Linkage(load_case(PARA), branch_rule="hold")
    x = np.radians([100.0, 200.0, 300.0])
    kin = lk.kinematics(x)
    d = np.abs(_wrap(kin.theta[:, lk.body_index("rocker")] - kin.theta[:, lk.body_index("crank")]))
    assert d[0] < 1e-9 and np.all(d[1:] > 0.1)
    assert Linkage(load_case(PARA)).kinematics(x, branch="held").theta[1, 3] == \
        pytest.approx(kin.theta[1, 3])


def test_sweep_reports_the_change_points(capsys):
    lk = Linkage(load_case(PARA))
    res = lk.sweep(360, start=0.0)
    cp = res.events[res.events.kind == "change_point"]
    assert set(np.round(np.mod(cp["input"].to_numpy(), 360), 6)) <= {0.0, 180.0}
    assert (np.round(cp["input"].to_numpy(), 6) == 180.0).any()
    assert all("switched" in d and "continuous" in d and d.endswith("a parallelogram")
               for d in cp["detail"])
    held = Linkage(load_case(PARA), branch_rule="hold").sweep(360, start=0.0).events
    assert all(d.endswith("an anti-parallelogram")
               for d in held[held.kind == "change_point"]["detail"])
    assert all(c.rule == "velocity" and c.switched for c in res.crossings)
    # the nearest event to 182 deg is a singular position or the change point at 180
    ev = nearest_event(res, 182.0)
    assert ev.input == pytest.approx(180.0) and ev.distance == pytest.approx(2.0)
    code = main(["sweep", str(PARA)])
    out = capsys.readouterr().out
    assert code == 0 and "change_point" in out and "switched" in out


def test_near_toggle_four_bar_never_switches():
    """A four-bar 1 mm off the Grashof boundary has no change point: its dyad's
    discriminant stays positive, the branch is held and no crossing is reported."""
    lk = Linkage(four_bar(0.4, 0.1, 0.399, 0.1, theta=math.radians(30), masses=None))
    res = lk.sweep(720)
    assert not res.crossings and "change_point" not in set(res.events.kind)
    assert lk.positions.schedule.constant


def test_grashof_boundary_kite_or_ambiguity_is_reported_as_a_rule():
    """Every crossing says which rule chose its branch."""
    lk = Linkage(four_bar(0.4, 0.1, 0.4, 0.1, theta=math.radians(30), masses=None))
    for c in lk.branch_crossings(-4 * math.pi, 4 * math.pi):
        assert c.rule in ("velocity", "hold", "switch") or c.rule.startswith("held: ")
        assert c.describe().startswith("change point at ")


def _change_point_four_bars(n, seed=2):
    """Random four-bars exactly on the Grashof boundary (s + l = p + q), assembled."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        p, q, l_ = np.sort(rng.uniform(0.1, 1.0, 3))
        s = p + q - l_
        if not 0.02 < s < p:
            continue
        g, a, b, c = rng.permutation([s, p, q, l_])
        try:
            out.append(Linkage(four_bar(g, a, b, c, theta=rng.uniform(-3, 3), masses=None)))
        except Exception:  # noqa: BLE001 - a reference angle outside the range: draw again
            continue
    return out


def test_random_change_point_linkages_move_smoothly_through():
    """On 12 random Grashof-boundary four-bars, over three turns each way: at every change
    point crossed the rates (d theta / d input) on either side agree (a held sign would
    flip them), and central differences of the positions straddling the change point
    equal the analytic rates there (the chosen branch is one smooth motion).  The step
    (1e-4) stays outside the +-1e-6 where the closed form snaps a dyad to its toggle
    (TOGGLE_SNAP); truncation leaves O(h^2) ~ 1e-6 of the rates."""
    h = 1e-4
    n_cross = 0
    for lk in _change_point_four_bars(12):
        for c in lk.branch_crossings(-6 * math.pi, 6 * math.pi):
            n_cross += 1
            x = c.value + np.array([-3e-4, 3e-4, -h, h])
            kin = lk.kinematics_along(x)
            rate = kin.omega / kin.velocity[:, None]
            peak = np.max(np.abs(rate[:2]))
            assert np.max(np.abs(rate[1] - rate[0])) < 1e-3 * peak  # O(6e-4 * curvature)
            fd = (kin.theta[3] - kin.theta[2]) / (2 * h)
            assert np.max(np.abs(fd - 0.5 * (rate[0] + rate[1]))) < 1e-3 * peak
            assert c.rule == "velocity" and c.switched
    assert n_cross >= 12


def test_where_continuity_cannot_decide_the_signs_are_held_and_said(monkeypatch):
    """With the decision threshold at 0 no candidate is clear: the signs are held, each
    crossing says why, the sweep adds a note naming the option, and ``branch_rule
    'switch'`` takes the other branch (the parallelogram again)."""
    import analytic.branches as branches
    monkeypatch.setattr(branches, "CONTINUITY_RATIO", 0.0)
    res = Linkage(load_case(PARA)).sweep(360, start=0.0)
    assert res.crossings and all(c.rule.startswith("held: ") and not c.switched
                                 for c in res.crossings)
    assert any("branch_rule='switch'" in n for n in res.notes)
    kin = Linkage(load_case(PARA), branch_rule="switch").kinematics_along(
        np.radians([100.0, 200.0, 300.0, 400.0]))
    np.testing.assert_allclose(_wrap(kin.theta[:, 3] - kin.theta[:, 1]), 0.0, atol=ANGLE_TOL)


def test_sweep_at_the_flat_positions_gives_the_motion_through_them():
    """Samples exactly at 0 and 180 deg are singular: the rates there are the
    parallelogram's (rocker at the crank's speed, coupler translating), the forces their
    limits along the branch (no gravity, constant speed: the inertia forces lie along the
    links' line, so nothing loads the motion the flat position leaves free and the
    reactions stay bounded; the drive torque is 0 by the power balance, dKE/dt = 0), and
    a note says so.  The limits are extrapolated from 1e-3 rad either side
    (analytic.singular); 1e-6 is the check."""
    lk = Linkage(load_case(PARA))
    res = lk.sweep(360, start=0.0)
    f = res.frame.set_index("input")
    w = lk.mech.driver.velocity
    for x in (0.0, 180.0):
        assert f.loc[x, "rocker.omega"] == pytest.approx(w, rel=1e-6)
        assert f.loc[x, "coupler.omega"] == pytest.approx(0.0, abs=1e-6 * w)
        assert abs(f.loc[x, "rocker.alpha"]) < 1e-6 * w * w
        scale = float(np.max(np.abs(f["A.fx"]))) * 0.1  # force x crank length, N m
        assert abs(f.loc[x, "drive.torque"]) < 1e-9 * scale
        assert f.loc[x, "singular"] == 1
        # the reactions are continuous through it: the mean of +-1 deg to O(1 deg^2)
        for j in ("O2", "A", "B", "O4"):
            side = 0.5 * (f.loc[x - 1.0 if x else 359.0, f"{j}.fx"] + f.loc[x + 1.0, f"{j}.fx"])
            assert f.loc[x, f"{j}.fx"] == pytest.approx(side, rel=1e-3)
    assert np.isfinite(f["drive.torque"]).all()
    assert any("2 sample(s) at singular positions the linkage passes through (0, 180 deg)"
               in n for n in res.notes)
