"""Kinematics against independent checks: finite differences of positions in time,
a hand-written closed form, and hypothesis-generated four-bars and slider-cranks."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from analytic import Linkage, LinkageError, SingularConfigurationError, case_names, load_case
from analytic.tolerances import FINITE_DIFFERENCE, LOOP_RESIDUAL

from .conftest_helpers import cycle_values, four_bar, slider_crank


def _state(lk, values, vel, acc):
    kin = lk.kinematics(values, vel, acc, on_singular="flag")
    rows = {"theta": kin.theta, "omega": kin.omega, "alpha": kin.alpha}
    pts = {}
    for body in lk.mech.moving_bodies:
        for pn in body.points:
            pts[f"{body.name}.{pn}"] = kin.point(body.name, pn)
    sl = {lk.topo.joint_names[j]: kin.slider(lk.topo.joint_names[j]) for j in lk.topo.prismatic}
    return rows, pts, sl


def _rel(err, ref, floor=0.0):
    """Max error normalised by the peak magnitude of the reference over the cycle
    (at least ``floor``: a fixed pivot's velocity is 0, so it is compared with 1e-2 of the
    peak of its kind (rounding there is ~eps * size / h), not with its own round-off)."""
    peak = max(float(np.max(np.abs(ref))), floor)
    return float(np.max(np.abs(err)) / peak)


def check_finite_differences(lk, values):
    """Central differences in time of positions (-> velocities) and of analytic
    velocities (-> accelerations) along the driver's motion
    x(t) = x0 + v t + a t^2 / 2, v(t) = v + a t."""
    d = lk.mech.driver
    v, a = d.velocity, d.acceleration
    # step: 1e-5 of the input's fastest time scale, the time it takes to move 1 rad (or
    # one mechanism size) at speed v or from rest at acceleration a: truncation
    # ~ (1e-5)^2 x (harmonic content) stays below 1e-8 relative even for a crank/rod
    # ratio of 1/1.2, rounding ~ eps / 1e-5 ~ 1e-11.
    from analytic.positions import size_of
    scale = 1.0 if lk.driver_is_revolute else size_of(lk.topo)
    tau = scale / abs(v)
    if a:
        tau = min(tau, math.sqrt(scale / abs(a)))
    h = 1e-5 * tau
    r0, p0, s0 = _state(lk, values, v, a)
    rp, pp, sp = _state(lk, values + v * h + a * h * h / 2, v + a * h, a)
    rm, pm, sm = _state(lk, values - v * h + a * h * h / 2, v - a * h, a)
    worst = {}
    moving = [b for b in range(len(lk.topo.body_names)) if b != lk.topo.ground]
    worst["omega"] = _rel((rp["theta"] - rm["theta"])[:, moving] / (2 * h) - r0["omega"][:, moving],
                          r0["omega"][:, moving])
    worst["alpha"] = _rel((rp["omega"] - rm["omega"])[:, moving] / (2 * h) - r0["alpha"][:, moving],
                          r0["alpha"][:, moving])
    vpeak = max(float(np.max(np.abs(p0[k][1]))) for k in p0)
    apeak = max(float(np.max(np.abs(p0[k][2]))) for k in p0)
    for k in p0:
        worst[f"{k}.v"] = _rel((pp[k][0] - pm[k][0]) / (2 * h) - p0[k][1], p0[k][1],
                               1e-2 * vpeak)
        worst[f"{k}.a"] = _rel((pp[k][1] - pm[k][1]) / (2 * h) - p0[k][2], p0[k][2],
                               1e-2 * apeak)
    for k in s0:
        worst[f"{k}.v"] = _rel((sp[k][0] - sm[k][0]) / (2 * h) - s0[k][1], s0[k][1])
        worst[f"{k}.a"] = _rel((sp[k][1] - sm[k][1]) / (2 * h) - s0[k][2], s0[k][2])
    return worst


@pytest.mark.parametrize("case", case_names())
def test_finite_differences_full_cycle(case):
    lk = Linkage(load_case(case))
    worst = check_finite_differences(lk, cycle_values(lk, 180))
    bad = {k: v for k, v in worst.items() if not v <= FINITE_DIFFERENCE}
    assert not bad, bad


@pytest.mark.parametrize("case", case_names())
def test_loop_residual_full_cycle(case):
    lk = Linkage(load_case(case))
    from analytic.positions import size_of
    kin = lk.kinematics(cycle_values(lk, 720), on_singular="flag")
    res = np.abs(lk.eqs.residual(kin.q))
    assert res.max() <= LOOP_RESIDUAL * size_of(lk.topo)
    # every revolute joint's two points coincide (independent of the loop choice)
    for jt in lk.mech.joints:
        if hasattr(jt, "point_a") and type(jt).__name__ == "Revolute":
            pa = kin.point(jt.body_a, jt.point_a)[0]
            pb = kin.point(jt.body_b, jt.point_b)[0]
            assert np.max(np.abs(pa - pb)) <= LOOP_RESIDUAL * size_of(lk.topo), jt.name


def freudenstein_four_bar(a, b, c, d, th2, w2, branch):
    """Textbook closed form (Norton, ch. 4-7) for O2 at the origin, O4 at (d, 0):
    theta4 from the Freudenstein constants, then omega and alpha from the
    velocity/acceleration loop, written independently of the solver."""
    K1, K2, K3 = d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)
    A = math.cos(th2) - K1 - K2 * math.cos(th2) + K3
    B = -2 * math.sin(th2)
    C = K1 - (K2 + 1) * math.cos(th2) + K3
    th4 = 2 * math.atan2(-B + branch * math.sqrt(B * B - 4 * A * C), 2 * A)
    K4, K5 = d / b, (c * c - d * d - a * a - b * b) / (2 * a * b)
    D = math.cos(th2) - K1 + K4 * math.cos(th2) + K5
    E = -2 * math.sin(th2)
    F = K1 + (K4 - 1) * math.cos(th2) + K5
    th3 = 2 * math.atan2(-E + branch * math.sqrt(E * E - 4 * D * F), 2 * D)
    w3 = a * w2 / b * math.sin(th4 - th2) / math.sin(th3 - th4)
    w4 = a * w2 / c * math.sin(th2 - th3) / math.sin(th4 - th3)
    A_ = c * math.sin(th4)
    B_ = b * math.sin(th3)
    C_ = a * w2 * w2 * math.cos(th2) + b * w3 * w3 * math.cos(th3) - c * w4 * w4 * math.cos(th4)
    D_ = c * math.cos(th4)
    E_ = b * math.cos(th3)
    F_ = -a * w2 * w2 * math.sin(th2) - b * w3 * w3 * math.sin(th3) + c * w4 * w4 * math.sin(th4)
    al3 = (C_ * D_ - A_ * F_) / (A_ * E_ - B_ * D_)
    al4 = (C_ * E_ - B_ * F_) / (A_ * E_ - B_ * D_)
    return th3, th4, w3, w4, al3, al4


@pytest.mark.parametrize("branch", [-1, 1])
def test_four_bar_against_freudenstein(branch):
    """Both assembly modes of the S4 four-bar over a full turn against Norton's
    closed form (open circuit is branch -1 in Norton's convention)."""
    a, b, c, d, w2 = 0.1, 0.3, 0.25, 0.4, 15.0
    mech = four_bar(d, a, b, c, omega=w2, open_branch=(branch == -1))
    lk = Linkage(mech)
    th2 = math.radians(60) + np.linspace(0, 2 * math.pi, 73)[:-1]
    kin = lk.kinematics(th2)
    cpl, rck = lk.body_index("coupler"), lk.body_index("rocker")
    for i, t in enumerate(th2):
        th3, th4, w3, w4, al3, al4 = freudenstein_four_bar(a, b, c, d, t, w2, branch)
        dth3 = (kin.theta[i, cpl] - th3 + math.pi) % (2 * math.pi) - math.pi
        dth4 = (kin.theta[i, rck] - th4 + math.pi) % (2 * math.pi) - math.pi
        assert abs(dth3) < 1e-12 and abs(dth4) < 1e-12
        assert kin.omega[i, cpl] == pytest.approx(w3, rel=1e-10, abs=1e-12)
        assert kin.omega[i, rck] == pytest.approx(w4, rel=1e-10, abs=1e-12)
        assert kin.alpha[i, cpl] == pytest.approx(al3, rel=1e-10, abs=1e-10)
        assert kin.alpha[i, rck] == pytest.approx(al4, rel=1e-10, abs=1e-10)


def test_slider_crank_closed_form():
    """Centred slider-crank: x = r cos t + sqrt(L^2 - r^2 sin^2 t), differentiated by hand."""
    r, L, w = 0.1, 0.2, 200.0
    lk = Linkage(slider_crank(r, L, omega=w, masses=None))
    t = np.linspace(0, 2 * np.pi, 91)[:-1]
    s, v, a = lk.kinematics(t).slider("slide")
    root = np.sqrt(L * L - r * r * np.sin(t) ** 2)
    x = r * np.cos(t) + root
    xd = -r * w * np.sin(t) - r * r * w * np.sin(t) * np.cos(t) / root
    xdd = (-r * w * w * np.cos(t) - r * r * w * w * np.cos(2 * t) / root
           - r ** 4 * w * w * np.sin(t) ** 2 * np.cos(t) ** 2 / root ** 3)
    np.testing.assert_allclose(s, x, rtol=0, atol=1e-15)
    np.testing.assert_allclose(v, xd, rtol=0, atol=1e-12 * np.max(np.abs(xd)))
    np.testing.assert_allclose(a, xdd, rtol=0, atol=1e-12 * np.max(np.abs(xdd)))


def test_singular_configuration_raises():
    """A parallelogram (change-point) four-bar at theta2 = 0 lies flat: the loop
    Jacobian is singular and the velocities are undetermined."""
    mech = four_bar(0.4, 0.1, 0.4, 0.1, theta=0.0, masses=None)
    lk = Linkage(mech)
    with pytest.raises(SingularConfigurationError, match=r"O2.* = 0 deg"):
        lk.kinematics(0.0)
    kin = lk.kinematics(0.0, on_singular="flag")
    assert not kin.condition[0] < 1e10


def test_unknown_point_is_a_typed_error():
    lk = Linkage(load_case("seed-four-bar"))
    kin = lk.kinematics()
    with pytest.raises(LinkageError, match="coupler.*'Q'"):
        kin.point("coupler", "Q")
    with pytest.raises(LinkageError, match="unknown body 'nope'"):
        kin.point("nope", "A")


# --- property tests -------------------------------------------------------------
lengths = st.floats(0.05, 1.0)


@st.composite
def grashof_crank_rockers(draw):
    """Crank the shortest link s, the longest l and the others p, q with
    s + l <= 0.97 (p + q): Grashof with a margin (away from change points)."""
    crank = draw(st.floats(0.02, 0.2))
    p = draw(st.floats(crank * 1.5, 1.0))
    q = draw(st.floats(crank * 1.5, 1.0))
    l_max = 0.97 * (p + q) - crank
    assume(l_max >= max(p, q))
    l_ = draw(st.floats(max(p, q), l_max))
    ground, coupler, rocker = draw(st.permutations([l_, p, q]))
    omega = draw(st.floats(-50, 50).filter(lambda w: abs(w) > 0.1))
    return ground, crank, coupler, rocker, draw(st.booleans()), omega


@settings(max_examples=40, deadline=None)
@given(grashof_crank_rockers())
def test_random_grashof_four_bars(params):
    ground, crank, coupler, rocker, open_branch, w = params
    lk = Linkage(four_bar(ground, crank, coupler, rocker, omega=w, open_branch=open_branch))
    vals = cycle_values(lk, 72)
    kin = lk.kinematics(vals)
    from analytic.positions import size_of
    assert np.abs(lk.eqs.residual(kin.q)).max() <= LOOP_RESIDUAL * size_of(lk.topo)
    worst = check_finite_differences(lk, vals)
    assert max(worst.values()) <= FINITE_DIFFERENCE, worst
    frc = lk.forces(kin)
    frc.check_power_balance()


@settings(max_examples=40, deadline=None)
@given(st.floats(0.02, 0.3), st.floats(1.2, 5.0), st.floats(-0.9, 0.9),
       st.floats(-300, 300).filter(lambda w: abs(w) > 0.1), st.floats(-1e3, 1e3))
def test_random_slider_cranks(r, ratio, off_frac, w, alpha):
    L = r * ratio
    offset = off_frac * (L - r)   # |offset| < L - r: the crank turns fully
    lk = Linkage(slider_crank(r, L, offset=offset, omega=w, alpha=alpha, load=(50.0, -20.0),
                              gravity=(0.0, -9.81)))
    vals = cycle_values(lk, 72)
    kin = lk.kinematics(vals)
    from analytic.positions import size_of
    assert np.abs(lk.eqs.residual(kin.q)).max() <= LOOP_RESIDUAL * size_of(lk.topo)
    worst = check_finite_differences(lk, vals)
    assert max(worst.values()) <= FINITE_DIFFERENCE, worst
    lk.forces(kin).check_power_balance()
