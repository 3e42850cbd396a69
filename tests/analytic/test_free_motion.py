"""Free motion (issue 20): the exact trajectory against independent references.

Expected values: the pendulum's period from the complete elliptic integral; the
published Andrews reference (Test Set for IVP Solvers, PSIDE at 1e-14); the
work-energy balance; an absolute-coordinate Newton-Euler solution with Lagrange
multipliers integrated here by another method (Radau).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipk

from analytic import load_case
from analytic.free_motion import simulate
from analytic.motion_spec import FreeMotion, Motor, PointDamper, PointSpring

#: The period from two turning points located on the dense output: the integration's
#: 1e-13 tolerance plus root-finding, with margin.
PERIOD_REL = 1e-12
#: Andrews' angles: the reference was computed at rtol = atol = 1e-14 and printed to 16
#: digits; we ask 1e-9 relative (the issue's bar) and report the reached agreement.
ANDREWS_REL = 1e-9
#: Work-energy balance, as a fraction of the run's energy scale (the issue's bar).
ENERGY_REL = 1e-11
#: Agreement with the absolute-coordinate solution, fraction of the link length; that
#: solution is integrated at rtol 1e-12 with Baumgarte-stabilised constraints.
ABSOLUTE_REL = 1e-9

ANDREWS_REF = {"O": 0.1581077119629904e2, "F": -0.1575637105984298e2,
               "B": 0.4082224013073101e-1, "H": -0.5347301163226948,
               "A5": 0.5244099658805304, "G": 0.5347301163226948,
               "A7": 0.1048080741042263e1}


def _pendulum_period(mech, amplitude: float) -> float:
    b = mech.body("link")
    i_o = b.mass * 1.0 + b.inertia
    return 4.0 * ellipk(math.sin(amplitude / 2) ** 2) * math.sqrt(i_o / (b.mass * 9.81 * 1.0))


@pytest.mark.parametrize("start_deg", [0.0, -85.0])
def test_a01_period_against_elliptic_integral(start_deg):
    """A01 released at rest at ``start_deg`` (0: horizontal, 90 deg amplitude; -85: 5 deg):
    the time between two turning points is half the closed-form period."""
    mech = load_case("iftomm-a01-pendulum")
    mech = replace(mech, motion=replace(mech.motion, value=math.radians(start_deg)))
    T = _pendulum_period(mech, math.radians(start_deg + 90.0))
    traj = simulate(mech, duration=2.2 * T)
    turns = [e.t for e in traj.events if e.kind == "turn"]
    assert len(turns) >= 2
    assert turns[0] == pytest.approx(T / 2, rel=PERIOD_REL)
    assert turns[1] - turns[0] == pytest.approx(T / 2, rel=PERIOD_REL)


def test_a03_andrews_against_published_reference():
    traj = simulate(load_case("iftomm-a03-andrews"))
    s = traj.at([0.03], forces=False)
    for joint, ref in ANDREWS_REF.items():
        assert s.joint(joint)[0, 0] == pytest.approx(ref, rel=ANDREWS_REL), joint


def _energy_scale(s) -> float:
    return float(np.max(s.kinetic) + np.ptp(s.potential)
                 + np.max(np.abs(s.work_motor)) + np.max(s.dissipated))


def _seed_released(elements: bool):
    m = load_case("seed-four-bar")
    fm = FreeMotion("O2", math.radians(60.0), 0.0, 10.0)
    if elements:
        fm = replace(fm, springs=(PointSpring("coupler", "B", "ground", "O2", 30.0, 0.25),),
                     dampers=(PointDamper("crank", "A", "ground", "O4", 0.5),),
                     motors=(Motor("O2", 0.0, (0.0, 2.0, 5.0, 10.0),
                                   (0.0, 0.1, -0.1, 0.05)),))
    return replace(m, gravity=(0.0, -9.81), motion=fm)


@pytest.mark.parametrize("elements", [False, True], ids=["conservative", "spring-damper-motor"])
def test_seed_four_bar_work_energy_balance(elements):
    """Kinetic + potential energy change = motor and load work - dissipated energy,
    over 10 s; the kinetostatics with every force element applied asks no drive effort."""
    traj = simulate(_seed_released(elements))
    s = traj.at(np.linspace(0.0, 10.0, 41))
    scale = _energy_scale(s)
    assert np.max(np.abs(s.energy_residual)) <= ENERGY_REL * scale
    if elements:
        assert np.max(s.dissipated) > 1e-3 * scale  # the damper did work: a real test
    assert np.max(np.abs(s.drive_residual)) <= 1e-9


# --- non-Grashof rocker: coordinate switching against absolute coordinates -------------
L_IN, L_CP, L_OUT, L_GND = 0.35, 0.30, 0.30, 0.40   # s + l = 0.7 > p + q = 0.65


def _rocker_mech():
    from analytic import Body, Driver, Mechanism, Revolute
    def rod(L, m):
        return (dict(points={"P": (0.0, 0.0), "Q": (L, 0.0)}, mass=m,
                                 com=(L / 2, 0.0), inertia=m * L * L / 12))
    bodies = (Body("ground", {"O2": (0.0, 0.0), "O4": (L_GND, 0.0)}),
              Body("crank", **rod(L_IN, 0.3)), Body("coupler", **rod(L_CP, 0.4)),
              Body("rocker", **rod(L_OUT, 0.5)))
    joints = (Revolute("O2", "ground", "O2", "crank", "P"),
              Revolute("A", "crank", "Q", "coupler", "P"),
              Revolute("B", "rocker", "Q", "coupler", "Q"),
              Revolute("O4", "ground", "O4", "rocker", "P"))
    from analytic.mechanism import Assembly
    return Mechanism("non-grashof", "ground", bodies, joints, Driver("O2", 1.2, 0.0),
                     gravity=(0.0, -9.81),
                     assembly=Assembly(points={"coupler.Q": (0.5, 0.25)}),
                     motion=FreeMotion("O2", 1.2, 6.0, 3.0))


def _absolute_reference(mech, traj, times):
    """Newton-Euler in absolute coordinates (x, y, theta per body), pin constraints
    with Lagrange multipliers, index 1 with Baumgarte stabilisation, Radau."""
    bodies = [b for b in mech.bodies if b.name != "ground"]
    nb = len(bodies)
    idx = {b.name: i for i, b in enumerate(bodies)}
    Mdiag = np.concatenate([[b.mass, b.mass, b.inertia] for b in bodies])
    g = np.array(mech.gravity)
    gpts = mech.body("ground").points
    pins = []
    for j in mech.joints:
        pins.append((j.body_a, mech.body(j.body_a).points[j.point_a],
                     j.body_b, mech.body(j.body_b).points[j.point_b]))

    def place(p, th, b, pt):  # world point of body-frame point pt of body b (its com origin)
        c = np.array(bodies[idx[b]].com)
        r = np.array(pt) - c
        R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
        return p + R @ r, R, r

    def constraint_terms(z, zd):
        C, Jc, gam = [], np.zeros((2 * len(pins), 3 * nb)), []
        for k, (ba, pa, bb, pb) in enumerate(pins):
            side = []
            for sgn, b, pt in ((1.0, ba, pa), (-1.0, bb, pb)):
                if b == "ground":
                    side.append((sgn * np.array(pt), np.zeros(2)))
                    continue
                i = idx[b]
                P, R, r = place(z[3 * i:3 * i + 2], z[3 * i + 2], b, pt)
                w = zd[3 * i + 2]
                Rr = R @ r
                Jc[2 * k:2 * k + 2, 3 * i:3 * i + 2] += sgn * np.eye(2)
                Jc[2 * k:2 * k + 2, 3 * i + 2] += sgn * np.array([-Rr[1], Rr[0]])
                side.append((sgn * P, sgn * (-w * w) * Rr))
            C.append(side[0][0] + side[1][0])
            gam.append(-(side[0][1] + side[1][1]))  # -(d/dt(J) zd)
        return np.concatenate(C), Jc, np.concatenate(gam)

    def rhs(t, y):
        z, zd = y[:3 * nb], y[3 * nb:]
        C, Jc, gam = constraint_terms(z, zd)
        a, b = 50.0, 50.0 ** 2 / 4  # Baumgarte: critically damped drift
        rhs_c = gam - 2 * a * (Jc @ zd) - b * C
        F = np.concatenate([[b_.mass * g[0], b_.mass * g[1], 0.0] for b_ in bodies])
        n = 3 * nb
        A = np.zeros((n + len(C), n + len(C)))
        A[:n, :n] = np.diag(Mdiag)
        A[:n, n:] = Jc.T
        A[n:, :n] = Jc
        sol = np.linalg.solve(A, np.concatenate([F, rhs_c]))
        return np.concatenate([zd, sol[:n]])

    s0 = traj.at([0.0], forces=False)
    y0 = []
    for b in bodies:
        i = mech.bodies.index(b)
        y0 += [s0.theta[0, i]]
    z0, zd0 = np.zeros(3 * nb), np.zeros(3 * nb)
    kin = traj.segments[0].lk.kinematics(np.array([mech.motion.value]), mech.motion.rate, 0.0)
    for b in bodies:
        i, k = mech.bodies.index(b), idx[b.name]
        r, v, _ = kin.com(i)
        z0[3 * k:3 * k + 3] = [r[0, 0], r[0, 1], kin.theta[0, i]]
        zd0[3 * k:3 * k + 3] = [v[0, 0], v[0, 1], kin.omega[0, i]]
    del gpts
    sol = solve_ivp(rhs, (0.0, times[-1]), np.concatenate([z0, zd0]), method="Radau",
                    rtol=1e-12, atol=1e-14, t_eval=times)
    assert sol.success
    out = {}
    for b in bodies:
        k = idx[b.name]
        out[b.name] = np.array([place(sol.y[3 * k:3 * k + 2, n], sol.y[3 * k + 2, n], b.name,
                                      b.points["Q"])[0] for n in range(len(times))])
    return out


@pytest.mark.slow
def test_non_grashof_rocker_switches_and_matches_absolute_coordinates():
    mech = _rocker_mech()
    traj = simulate(mech)
    limits = [e for e in traj.events if e.kind == "limit"]
    assert traj.switches, "the input's limit positions need a coordinate switch"
    assert limits
    times = np.linspace(0.0, 3.0, 13)
    ref = _absolute_reference(mech, traj, times)
    for seg in traj.segments:
        del seg
    for name in ("crank", "coupler", "rocker"):
        got = np.array([_point_at(traj, name, "Q", t) for t in times])
        assert np.max(np.abs(got - ref[name])) <= ABSOLUTE_REL * L_IN, name


def _point_at(traj, body, point, t):
    y, si = traj.state([t])
    seg = traj.segments[int(si[0])]
    kin = seg.lk.kinematics(np.array([y[0, 0]]), 1.0, 0.0, on_singular="flag")
    return kin.point(body, point)[0][0]


#: DOP853 at 1e-13 against Radau (implicit, order 5) at 1e-12 on the pendulum: both
#: reach ~1e-11 of a radian over a second; a wrong equation would differ at once.
SECOND_METHOD = 1e-9


def test_second_method_agrees():
    mech = load_case("iftomm-a01-pendulum")
    a = simulate(mech, duration=1.0)
    b = simulate(mech, duration=1.0, rtol=1e-12, method="Radau")
    t = np.linspace(0.0, 1.0, 11)
    xa, xb = a.at(t, forces=False).x[:, 0], b.at(t, forces=False).x[:, 0]
    assert np.max(np.abs(xa - xb)) <= SECOND_METHOD


def test_slider_crank_released_from_its_slider():
    """A prismatic initial coordinate, with a spring, a damper and a motor on the slider:
    the slider is a poor coordinate there (it switches at once), the balance closes and
    the kinetostatics with the slider's efforts applied as loads asks no drive effort."""
    from analytic import Linkage
    from analytic.motion_spec import JointDamper, JointSpring
    m = load_case("seed-slider-crank")
    s0 = float(Linkage(m).kinematics(np.radians([30.0])).slider("slide")[0][0])
    fm = FreeMotion("slide", s0, 0.0, 0.05, springs=(JointSpring("slide", 2000.0, s0 - 0.01),),
                    dampers=(JointDamper("slide", 1.0),), motors=(Motor("slide", 5.0),))
    traj = simulate(replace(m, gravity=(0.0, -9.81), motion=fm))
    s = traj.at(np.linspace(0.0, 0.05, 11))
    assert traj.switches and traj.switches[0][1] == "slide"
    assert np.max(np.abs(s.energy_residual)) <= ENERGY_REL * _energy_scale(s)
    assert np.max(np.abs(s.drive_residual)) <= 1e-9
    assert s.joint("slide")[0, 0] == pytest.approx(s0, abs=1e-15)
