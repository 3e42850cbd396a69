"""The solver defects the hypothesis fuzz found (tests/test_fuzz.py), each checked
against an independent source: closed forms, virtual work, finite differences of the
positions (never the rates or forces under test pasted back).

1. A sweep sample exactly on a change point: the rates are the branch's, the drive
   torque is the virtual-work (power-balance) limit, and the joint forces are either
   their limits or, where the load has a component in the motion the collinear links
   leave free, unbounded (growing as 1/distance) -- then NaN, and said so.
2. Next to a change point the toggle snap must not refuse an assembly that exists.
3. The condition number (and so the singular test) does not depend on the mechanism's
   size: a nanometre limited-range slider-crank sweeps as its metre copy does.
4. No inf/NaN from the solver at the engines' samples on the parallelogram hard case.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from analytic import Linkage
from analytic.cases import load_case
from analytic.tolerances import FINITE_DIFFERENCE, LOOP_RESIDUAL, SINGULAR_CONDITION
from tests.conftest import four_bar, slider_crank

PARA = "analytic/cases/hard/parallelogram-four-bar.toml"
G = 9.81


def _fuzz_parallelogram(omega=0.0):
    """The fuzz's case: crank = rocker = 0.5 m, ground = coupler = 0.05 m, uniform rods
    (conftest), masses 7.5 / 9.7 / 9.7 kg, gravity -y; its branch through 0 deg is the
    crossed one (the hint's side)."""
    from tests.test_fuzz import with_exact_hint
    kw = dict(ground=0.05, crank=0.5, coupler=0.05, rocker=0.5, theta=5.347818936874179,
              omega=omega, alpha=0.0, masses=(7.5, 9.7, 9.7), open_branch=True,
              gravity=(0.0, -G))
    return Linkage(with_exact_hint("four-bar", four_bar(**kw), kw)), kw


def _fd_ratio(lk, x, b, d=1e-4):
    """d(theta_b)/d(input) at ``x`` by central differences of the positions."""
    th = lk.kinematics_along(np.array([x - d, x + d]), 0.0, 0.0).theta[:, b]
    return float((th[1] - th[0]) / (2 * d))


def test_change_point_torque_is_the_virtual_work_limit():
    """At the change point (0 deg, the links on the x axis) the static drive torque is,
    by virtual work along the branch, g (m1 x1' + m2 (yA' + yB') / 2 + m3 x3' r) with
    r = d(theta4)/d(theta2) from finite differences of the positions: crank COM lever
    0.25 m, A's 0.5 m, B's 0.5 r, rocker COM's 0.25 r."""
    lk, kw = _fuzz_parallelogram()
    m1, m2, m3 = kw["masses"]
    x = 2 * math.pi  # the sweep's 0 deg, reached from the reference 306 deg
    r = _fd_ratio(lk, x, lk.body_index("rocker"))
    expected = G * (m1 * 0.25 + m2 * (0.5 + 0.5 * r) / 2 + m3 * 0.25 * r)
    res = lk.sweep(6, start=0.0)
    f = res.frame
    i = int(np.flatnonzero(np.isclose(f["input"], 0.0))[0])
    assert f["singular"][i] == 2
    assert f["drive.torque"][i] == pytest.approx(expected, rel=FINITE_DIFFERENCE)
    assert np.isfinite(f["drive.torque"]).all() and np.isfinite(f["drive.power"]).all()
    assert any("unbounded there" in n for n in res.notes)
    assert (res.events.kind == "unbounded_force").sum() == 2  # 0 and 180 deg


def test_change_point_joint_forces_grow_as_one_over_distance():
    """Why the joint forces are left empty there: at 1e-2 and 1e-3 rad from the change
    point the force along the line grows tenfold (1/distance) and flips sign across it
    -- no limit.  Checked on regular samples, independent of the limit code."""
    lk, _ = _fuzz_parallelogram()
    x = 2 * math.pi + np.array([1e-2, 1e-3, -1e-3])
    kin = lk.kinematics_along(x, 0.0, 0.0)
    assert np.all(kin.condition < SINGULAR_CONDITION)
    fx = lk.forces(kin).joint_force["B"][:, 0]
    assert fx[1] / fx[0] == pytest.approx(10.0, rel=1e-2)
    assert fx[2] == pytest.approx(-fx[1], rel=1e-2)


def test_change_point_rates_are_the_branch_velocity():
    """With the crank at 10 rad/s the rates at the change point are the branch's:
    omega_b = 10 d(theta_b)/d(theta2), from finite differences of the positions; and the
    power balance holds there (drive power = dKE/dt - load power)."""
    lk, _ = _fuzz_parallelogram(omega=10.0)
    res = lk.sweep(6, start=0.0)
    f = res.frame
    i = int(np.flatnonzero(np.isclose(f["input"], 0.0))[0])
    for body in ("coupler", "rocker"):
        w = 10.0 * _fd_ratio(lk, 2 * math.pi, lk.body_index(body))
        assert f[f"{body}.omega"][i] == pytest.approx(w, rel=FINITE_DIFFERENCE, abs=1e-9)
    frc = res.forces
    assert abs(frc.power_residual[i]) <= 1e-6 * np.max(np.abs(frc.power))


def test_parallelogram_flat_position_forces_are_bounded_limits():
    """The hard-case parallelogram (no gravity, constant 15 rad/s): every inertia force at
    the flat position lies along the links' line, nothing loads the free motion, so the
    reactions have limits: by symmetry of the parallelogram (crank and rocker alike),
    the pins at O2 and O4 share the x inertia (m_crank w^2 0.05 + m_coupler w^2 0.1 +
    m_rocker w^2 0.05 = 22.5 N) equally, 11.25 N each, and A and B the coupler's 18 N, 9 N
    each; the torque is 0 (dKE/dt = 0, no load)."""
    lk = Linkage(load_case(PARA))
    f = lk.sweep(360, start=0.0).frame.set_index("input")
    for x, sgn in ((0.0, -1.0), (180.0, 1.0)):
        assert f.loc[x, "singular"] == 1
        assert f.loc[x, "O2.fx"] == pytest.approx(sgn * 11.25, rel=1e-5)
        assert f.loc[x, "O4.fx"] == pytest.approx(sgn * 11.25, rel=1e-5)
        assert f.loc[x, "A.fx"] == pytest.approx(sgn * 9.0, rel=1e-5)
        assert f.loc[x, "B.fx"] == pytest.approx(sgn * 9.0, rel=1e-5)
        assert abs(f.loc[x, "drive.torque"]) < 1e-9 * 11.25 * 0.1


@pytest.mark.parametrize("ratio", [1.0, 3.0, 12.208, 100.0])
@pytest.mark.parametrize("dist", [1e-7, 5.3447869591918986e-06, 1e-4])
@pytest.mark.parametrize("open_branch", [True, False])
def test_assembles_next_to_a_change_point(ratio, dist, open_branch):
    """A parallelogram (crank = rocker = L, ground = coupler = L / ratio) at ``dist`` rad
    from its change point assembles (the triangle closes: closed form), B lies where
    the circle intersection puts it, and the loops close to LOOP_RESIDUAL."""
    L = 1.325721818434985
    g = L / ratio
    kw = dict(ground=g, crank=L, coupler=g, rocker=L, theta=0.0052359877559829, omega=0.0,
              alpha=0.0, masses=None, open_branch=open_branch, gravity=(0.0, 0.0))
    from tests.test_fuzz import with_exact_hint
    lk = Linkage(with_exact_hint("four-bar", four_bar(**kw), kw))
    kin = lk.kinematics_along(np.array([dist]))
    A = complex(L * math.cos(dist), L * math.sin(dist))
    u = complex(g, 0.0) - A
    d = abs(u)
    assert L - g <= d <= L + g
    along = (g * g - L * L + d * d) / (2 * d)
    h = math.sqrt(max(g * g - along * along, 0.0))
    cands = [A + u / d * complex(along, s * h) for s in (1, -1)]
    B = complex(*kin.point("coupler", "P1")[0][0])
    # the closed form's B is sensitive to rounding near the toggle (h ~ sqrt): 1e-7
    assert min(abs(B - c) for c in cands) <= 1e-7 * L
    res = np.abs(lk.eqs.residual(kin.q))
    assert np.max(res) <= LOOP_RESIDUAL * L


def _slider_crank(scale):
    from tests.test_fuzz import with_exact_hint
    kw = dict(crank=0.811 * scale, rod_len=0.4817 * scale, offset=-0.1523 * scale,
              theta=0.2818, omega=432.0, alpha=0.0, masses=None, gravity=(0.0, 0.0))
    return Linkage(with_exact_hint("slider-crank", slider_crank(**kw), kw)), kw


def test_condition_number_does_not_depend_on_size():
    """Similar mechanisms have the same condition number at the same input: the sliders'
    column in sizes (a length unit is a choice, not physics)."""
    x = np.radians([-51.4, -20.0, 23.9])
    ref = _slider_crank(1.0)[0].kinematics(x).condition
    for s in (1e-9, 1e-3, 1e3):
        np.testing.assert_allclose(_slider_crank(s)[0].kinematics(x).condition, ref,
                                   rtol=1e-6)


@pytest.mark.parametrize("scale", [1e-9, 1.0])
def test_nanometre_limited_range_ends_are_regular(scale):
    """The limited-range sweep's end samples are regular at any scale, and the piston's
    velocity there is the closed form's: s = r cos(t) + sqrt(L^2 - (r sin(t) - e)^2),
    ds/dt = -r w sin(t) - r w cos(t) (r sin(t) - e) / sqrt(L^2 - (r sin(t) - e)^2)."""
    lk, kw = _slider_crank(scale)
    res = lk.sweep(6)
    kin = res.kinematics
    assert np.all(kin.condition < SINGULAR_CONDITION)
    assert (res.frame["singular"] == 0).all() and np.isfinite(res.frame.to_numpy()).all()
    r, L, e, w = kw["crank"], kw["rod_len"], kw["offset"], kw["omega"]
    t = kin.value
    y = r * np.sin(t) - e
    v = -r * w * np.sin(t) - r * w * np.cos(t) * y / np.sqrt(L * L - y * y)
    _, sd, _ = kin.slider("slide")
    np.testing.assert_allclose(sd, v, rtol=1e-6, atol=1e-9 * np.max(np.abs(v)))


def test_parallelogram_engine_samples_leave_no_inf_or_nan():
    """The compare's analytic reference at a 10-deg engine grid (0 and 180 deg are the
    flat positions): no RuntimeWarning (no division by zero in the statics), finite
    rates equal to the parallelogram's closed form (rocker at the crank's speed, coupler
    translating), finite forces at the flat positions."""
    lk = Linkage(load_case(PARA))
    x = np.radians(np.arange(0.0, 360.0, 10.0))
    w = lk.mech.driver.velocity
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        kin = lk.kinematics_along(x, np.full(len(x), w), np.zeros(len(x)))
        frc = lk.forces(kin)
    np.testing.assert_allclose(kin.omega[:, lk.body_index("rocker")], w, rtol=1e-6)
    np.testing.assert_allclose(kin.omega[:, lk.body_index("coupler")], 0.0, atol=1e-6 * w)
    for F in frc.joint_force.values():
        assert np.isfinite(F).all()
    assert np.isfinite(frc.effort).all()
    assert list(np.flatnonzero(frc.at_singular)) == [0, 18]


def test_reference_on_a_change_point_is_crossed_smoothly():
    """Found by the fuzz: a parallelogram assembled exactly at its change point (180 deg).
    The branch is smooth through the reference: the one-sided difference quotients of the
    positions either side agree (a held kink would differ by the speed ratio), and the
    sweep's samples there are limits (singular 1 or 2), not 'not determined'."""
    kw = dict(ground=0.287, crank=1.1118, coupler=1.1118, rocker=0.287, theta=math.pi,
              omega=363.7, alpha=0.0, masses=(4.6, 1.6, 6.8), open_branch=False,
              gravity=(0.0, -9.81))
    from tests.test_fuzz import with_exact_hint
    lk = Linkage(with_exact_hint("four-bar", four_bar(**kw), kw))
    d = 1e-4
    th = lk.kinematics_along(math.pi + np.array([-2 * d, -d, d, 2 * d]), 0.0, 0.0).theta
    left = (th[1] - th[0]) / d
    right = (th[3] - th[2]) / d
    np.testing.assert_allclose(left, right, atol=1e-2)
    st = lk.sweep(6, start=0.0).frame["singular"].to_numpy()
    assert set(st[[0, 3]]) <= {1, 2} and not (st == 3).any()


def test_tiny_limited_range_sweep_ends_are_regular():
    """Found by the fuzz: a four-bar with a rocker 1e-6 of its other links, feasible over
    3e-7 rad only: the sweep's ends stay inside the limit positions far enough to be
    regular (no row singular, every cell finite)."""
    kw = dict(ground=2.575207176278855e-07, crank=2.2756063160020336e-07,
              coupler=4.4612105295080817e-07, rocker=6.815326071148512e-14,
              theta=-2.3329117064344254, omega=1000.0, alpha=-89148.02406538547,
              masses=None, open_branch=False, gravity=(3.0, -1000.0))
    from tests.test_fuzz import with_exact_hint
    lk = Linkage(with_exact_hint("four-bar", four_bar(**kw), kw))
    f = lk.sweep(6).frame
    assert (f["singular"] == 0).all() and np.isfinite(f.to_numpy()).all()
