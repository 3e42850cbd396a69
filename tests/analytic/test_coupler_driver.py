"""A coupler joint driven: the ``driven_RRR`` closed form (issue 34).

With the relative angle at a coupler joint known, its two bodies are one rigid body, a
virtual link from their ground pivot to the far coupler joint; that joint lies where the
circle of the virtual link meets the circle of the other ground link (an RRR dyad).
Checked here against independent answers: Newton's method on the loop equations from
the closed form's own pose as hints (the general path), the loop residual, finite
differences of the positions for the rates, and the same configuration solved with the
crank driven (the ordinary RRR plan).
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from analytic import Assembly, AssemblyError, Linkage, load_case
from analytic.free_motion.dynamics import coefficients, terms
from analytic.free_motion.integrate import rebased
from analytic.mechanism import Revolute
from analytic.position_solver import PositionSolver
from analytic.positions import q_from_poses
from analytic.toml_io import load_mechanism

from .conftest_helpers import four_bar

#: Loop closure of the closed form, fraction of the mechanism's size: rounding of a few
#: complex products and square roots (measured ~2e-16).
CLOSURE_REL = 1e-14
#: Newton's assembly against the closed form, fraction of the size: Newton stops at
#: LOOP_RESIDUAL (1e-12 of the size) of the loop equations; away from the limit
#: positions (10% of the range left at each end) the pose is within a few times that.
NEWTON_REL = 1e-10
#: Central differences of positions at step 1e-5 rad: truncation h^2/6 * third
#: derivative (~1e-10 of the rate's scale here) plus rounding 1e-16/h; 1e-6 of the
#: peak leaves a margin of 1e3 and still fails for a wrong sign or a missing term.
FD_REL = 1e-6
H = 1e-5
#: A coupler joint's equation of motion next to its limit position against the ground
#: joint's (regular there, a different plan): B'' = dB/dO4 O4'' + d2B/dO4^2 O4'^2.  Both
#: sides are rounding (measured <= 2.6e-15 of |B''|) times the conditioning of the
#: change of coordinate (1/|dB/dO4| <= 8 here); 1e-13 fails the Newton path that served
#: the coupler joints before the closed form (1.2e-12 at dB/dO4 = 0.285, the switch).
LIMIT_RHS_REL = 1e-13
BUGS = Path(__file__).resolve().parents[1] / "data" / "bugs" / "turn4"


def _swapped(mech, joint: str):
    """``mech`` with ``joint``'s two bodies in the other order (the coordinate is then
    the negative angle): both orientations of the driver."""
    joints = tuple(Revolute(j.name, j.body_b, j.point_b, j.body_a, j.point_a)
                   if j.name == joint else j for j in mech.joints)
    return replace(mech, joints=joints)


def _four_bars():
    """Random four-bars (both assembly modes) that assemble at the crank angle 1 rad,
    and the non-Grashof rocker of the free-motion tests."""
    from .test_free_motion import _rocker_mech
    rng = np.random.default_rng(34)
    out = [("rocker", _rocker_mech())]
    while len(out) < 7:
        crank, coupler, rocker = rng.uniform(0.3, 1.5, 3)
        for open_branch in (True, False):
            m = four_bar(1.0, crank, coupler, rocker, theta=1.0, masses=None,
                         open_branch=open_branch)
            try:
                Linkage(m).kinematics(1.0, 1.0, 0.0)
            except AssemblyError:
                break
            out.append((f"fb{len(out)}{'o' if open_branch else 'c'}", m))
    return out


def _driven_at(mech, joint: str):
    """``mech`` driven at ``joint`` from the pose the crank-driven linkage has at its
    reference (hints: every point and angle of that pose), and that linkage."""
    lk = Linkage(mech)
    co = coefficients(lk, mech.driver.value)
    k = [j.name for j in mech.joints].index(joint)
    return Linkage(rebased(mech, joint, float(co.x[0, k]), co.kin)), lk, co, k


def _inner_values(lk, n: int) -> np.ndarray:
    """``n`` values inside the driver's first feasible interval, 10% of it from each end
    (a full turn: the turn around the reference)."""
    lo, hi = next((a, b) for a, b in lk.positions.feasible()
                  if a <= lk.mech.driver.value <= b)
    m = 0.1 * (hi - lo)
    return np.sort(np.random.default_rng(7).uniform(lo + m, hi - m, n))


CASES = _four_bars()


@pytest.mark.parametrize("swap", [False, True])
@pytest.mark.parametrize("joint", ["A", "B"])
@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_coupler_driver_closed_form(name, joint, swap):
    mech = dict(CASES)[name]
    if swap:
        mech = _swapped(mech, joint)
    lk, _, _, _ = _driven_at(mech, joint)
    assert [st.kind for st in lk.topo.plan] == ["driven_RRR"]
    size = lk.positions.size
    x = _inner_values(lk, 6)
    sg = lk.positions.signs
    th, E, O, disc, _ = lk.positions.cf.run(x, sg)
    assert np.all(disc > 0)
    # the loops close to rounding, and the driver's angle is the input
    q = q_from_poses(lk.topo, th, E, O)
    assert np.max(np.abs(lk.eqs.residual(q))) <= CLOSURE_REL * size
    jt = lk.mech.driver_joint
    a, b = lk.body_index(jt.body_a), lk.body_index(jt.body_b)
    rel = np.angle(np.exp(1j * (th[:, b] - th[:, a] - x)))
    assert np.max(np.abs(rel)) <= 1e-15 * 8
    # Newton's method on the loop equations, hinted with each closed-form pose
    for i, v in enumerate(x):
        pts = {f"{body.name}.{p}": tuple(map(float, (z.real, z.imag)))
               for bi, body in enumerate(lk.mech.bodies) if body.name != lk.mech.ground
               for p, c in body.points.items()
               for z in [O[i, bi] + E[i, bi] * complex(*c)]}
        nl = Linkage(replace(lk.mech, driver=replace(lk.mech.driver, value=float(v)),
                             assembly=Assembly(pts, {})))
        nl.topo.plan = None  # the general path
        nl.positions = PositionSolver(nl.topo, nl.eqs)
        kn = nl.kinematics(float(v), 1.0, 0.0)
        assert np.max(np.abs(kn.zO[0] - O[i])) <= NEWTON_REL * size
        dth = np.angle(np.exp(1j * (kn.theta[0] - th[i])))
        assert np.max(np.abs(dth)) <= NEWTON_REL


@pytest.mark.parametrize("joint", ["A", "B"])
@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_coupler_driver_rates_are_derivatives_of_positions(name, joint):
    lk, _, _, _ = _driven_at(dict(CASES)[name], joint)
    x = _inner_values(lk, 5)
    kin = lk.kinematics(x, 1.0, 0.0, branch="held")
    hi = lk.kinematics(x + H, 1.0, 0.0, branch="held")
    lo = lk.kinematics(x - H, 1.0, 0.0, branch="held")
    w_fd = np.angle(np.exp(1j * (hi.theta - lo.theta))) / (2 * H)
    v_fd = (hi.zO - lo.zO) / (2 * H)
    a_fd = (hi.omega - lo.omega) / (2 * H)
    aO_fd = (hi.zv - lo.zv) / (2 * H)
    for got, fd in ((kin.omega, w_fd), (kin.zv, v_fd), (kin.alpha, a_fd), (kin.za, aO_fd)):
        assert np.max(np.abs(got - fd)) <= FD_REL * max(np.max(np.abs(fd)), 1.0)


@pytest.mark.parametrize("joint", ["A", "B"])
def test_six_bar_coupler_driver_matches_crank_driven(joint):
    """The six-bar driven at a coupler joint of its first loop (a driven_RRR, then the
    second loop's RRR): the pose the crank-driven linkage has there, and every body's
    rate per unit of the joint's rate (its rate per crank rate over the joint's)."""
    lk, lk0, co, k = _driven_at(load_case("six-bar"), joint)
    assert [st.kind for st in lk.topo.plan] == ["driven_RRR", "RRR"]
    x = float(co.x[0, k])
    kin = lk.kinematics(x, 1.0, 0.0)
    k0 = co.kin
    size = lk.positions.size
    assert np.max(np.abs(kin.zO[0] - k0.zO[0])) <= CLOSURE_REL * size
    assert np.max(np.abs(np.angle(np.exp(1j * (kin.theta[0] - k0.theta[0]))))) <= 1e-14
    xq = float(co.x_q[0, k])
    np.testing.assert_allclose(kin.omega[0], k0.omega[0] / xq, rtol=1e-12,
                               atol=1e-12 * np.max(np.abs(k0.omega[0] / xq)))
    assert math.isfinite(xq) and xq != 0.0


def test_free_rocker_has_no_newton_segment():
    """The switching rocker's free run: every coordinate it integrates in has a closed
    form (before: the coupler joints' segments were on the Newton path)."""
    from analytic.free_motion import simulate

    from .test_free_motion import _rocker_mech
    traj = simulate(_rocker_mech(), duration=0.5)
    assert {seg.joint for seg in traj.segments} & {"A", "B"}
    assert all(seg.lk.topo.plan is not None for seg in traj.segments)


@pytest.mark.parametrize("joint", ["A", "B"])
def test_fused_kernel_serves_a_coupler_driver(joint):
    """The generated kernel of a driven_RRR plan (the driver's row in the square system)
    gives the numpy path's numbers (test_fused's bar: AGREEMENT of peak, kappa eps next
    to a limit), kinematics and forces, over the joint's feasible range."""
    pytest.importorskip("numba")
    from analytic.fused import FusedKernel
    from analytic.sweep import input_values

    from .test_free_motion import _rocker_mech
    from .test_fused import POINTS, _compare, _numpy_kinematics
    lk, _, _, _ = _driven_at(_rocker_mech(), joint)
    assert lk.topo.driven_var is None
    x = input_values(lk, POINTS)[0]
    kin0, frc0 = _numpy_kinematics(lk, x)
    kin, frc = FusedKernel(lk).solve(x, on_singular="flag", forces=True)
    errs = _compare(lk, kin, frc, kin0, frc0, conditioned=True)
    worst = max(errs, key=errs.get)
    assert errs[worst] <= 1.0, (worst, errs[worst])


def test_free_rocker_body_angles_continue_across_segments():
    """Body angles of the samples are continuous over the run, across switches into the
    coupler joints' coordinates (fails before: the closed form's angles lie within one
    turn, so a sample after a switch jumped by 2 pi: 6.13 rad between samples), and each
    is the solver's angle up to whole turns."""
    from analytic.free_motion import simulate

    from .test_free_motion import _rocker_mech
    traj = simulate(_rocker_mech(), duration=1.0)
    t = np.linspace(0.0, 1.0, 201)
    s = traj.at(t, forces=False)
    # the fastest body turns < 0.5 rad between samples (its peak rate 60 rad/s, 5 ms)
    assert np.max(np.abs(np.diff(s.theta, axis=0))) < 0.5
    _, si = traj.state(t)
    for k in np.unique(si):
        seg, sel = traj.segments[k], np.flatnonzero(si == k)
        kin = seg.lk.kinematics(traj.state(t[sel])[0][:, 0], 1.0, 0.0, branch="continued")
        d = np.angle(np.exp(1j * (s.theta[sel] - kin.theta)))
        assert np.max(np.abs(d)) <= 1e-12


def _accel(lk, co, qd: float) -> float:
    """The coordinate's acceleration (rad/s^2) from the equation of motion at ``co``'s
    state with rate ``qd`` (rad/s), at t = 0."""
    tm = terms(lk, co, co.x, qd, 0.0)
    return float(((tm.Q - tm.C * qd * qd) / tm.M)[0])


def test_coupler_coordinate_equation_of_motion_next_to_its_limit():
    """free01 (issue 30's reproducer) driven at its coupler joint B, 0.2 .. 0.01 rad from
    each end of B's range (dB/dO4 from 0.6 down to 0.13: past the switches' 1/4): B''
    from B's equation of motion equals B'' from O4's at the same state (fails before,
    on the Newton path: 1.2e-12 of |B''| at dB/dO4 = 0.285)."""
    mech = load_mechanism(BUGS / "free01_s3_switch_error.toml")
    names = [j.name for j in mech.joints]
    kb, ko = names.index("B"), names.index("O4")
    co = coefficients(Linkage(mech), mech.driver.value)
    lkb = Linkage(rebased(mech, "B", float(co.x[0, kb]), co.kin))
    lo, hi = next((a, b) for a, b in lkb.positions.feasible()
                  if a <= lkb.mech.driver.value <= b)
    qd = 3.0  # rad/s of B: its rate near the limit in the run
    for q in [lo + g for g in (0.2, 0.1, 0.05, 0.03, 0.02, 0.01)] + \
             [hi - g for g in (0.2, 0.1, 0.05, 0.03, 0.02, 0.01)]:
        c = coefficients(lkb, q)
        b_own = _accel(lkb, c, qd)
        lko = Linkage(rebased(lkb.mech, "O4", float(c.x[0, ko]), c.kin))
        c2 = coefficients(lko, float(c.x[0, ko]))
        od = float(c.x_q[0, ko]) * qd
        b_o4 = float(c2.x_q[0, kb]) * _accel(lko, c2, od) + float(c2.x_qq[0, kb]) * od * od
        assert abs(b_own - b_o4) <= LIMIT_RHS_REL * abs(b_o4), (q, b_own, b_o4)
