"""Kinetostatics against independent checks: the power balance, Newton-Euler of each
body rebuilt from the reported joint forces, and hand-solved statics."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analytic import Linkage, MissingMassError, Prismatic, case_names, load_case
from analytic.tolerances import POWER_BALANCE

from .conftest_helpers import cycle_values, four_bar, slider_crank

MASSIVE = [c for c in case_names() if load_case(c).has_mass]


def test_massive_cases_exist():
    assert set(MASSIVE) >= {"seed-four-bar", "seed-slider-crank", "offset-slider-crank",
                            "inverted-slider-crank", "quick-return", "six-bar"}


@pytest.mark.parametrize("case", MASSIVE)
def test_power_balance_full_cycle(case):
    """Drive power = dKE/dt - power of gravity and loads, to rounding, over a cycle."""
    lk = Linkage(load_case(case))
    frc = lk.forces(lk.kinematics(cycle_values(lk, 720)))
    assert frc.power_balance_error() <= POWER_BALANCE


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


@pytest.mark.parametrize("case", MASSIVE)
def test_newton_euler_of_every_body(case):
    """Rebuild each body's free-body diagram from the reported joint forces (by body_a
    on body_b; a prismatic's normal force at the slider point plus its couple), the
    drive effort, loads and gravity, and check F = m a_G and M_G = I alpha.  This checks
    the reduced tree solution and every sign convention at once."""
    mech = load_case(case)
    lk = Linkage(mech)
    kin = lk.kinematics(cycle_values(lk, 90))
    frc = lk.forces(kin)
    N = kin.n
    g = np.asarray(mech.gravity)
    scaleF = max(np.max(np.abs(v)) for v in frc.joint_force.values())
    for body in mech.moving_bodies:
        b = lk.body_index(body.name)
        rG, _, aG = kin.com(b)
        F = np.zeros((N, 2))
        M = np.zeros(N)
        for jt in mech.joints:
            if body.name not in jt.bodies:
                continue
            sgn = 1.0 if body.name == jt.body_b else -1.0
            if isinstance(jt, Prismatic):
                P = kin.point(jt.slider, jt.point)[0]
                f = frc.joint_force[jt.name] * sgn
                M += sgn * frc.moment[jt.name] + _cross(P - rG, f)
            else:
                P = kin.point(body.name, jt.point_b if sgn > 0 else jt.point_a)[0]
                f = frc.joint_force[jt.name] * sgn
                M += _cross(P - rG, f)
            F += f
            if jt.name == mech.driver.joint:
                if isinstance(jt, Prismatic):
                    gb = lk.body_index(jt.guide)
                    u = np.stack([np.cos(kin.theta[:, gb] + jt.direction),
                                  np.sin(kin.theta[:, gb] + jt.direction)], axis=1)
                    F += sgn * frc.effort[:, None] * u
                    M += _cross(P - rG, sgn * frc.effort[:, None] * u)
                else:
                    M += sgn * frc.effort
        for ld in mech.loads:
            if ld.body == body.name:
                P = kin.point(body.name, ld.point)[0] if ld.point else rG
                F += np.asarray(ld.force)
                M += ld.torque + _cross(P - rG, np.asarray(ld.force))
        F += body.mass * g
        np.testing.assert_allclose(F, body.mass * aG, rtol=0, atol=1e-10 * scaleF,
                                   err_msg=f"{case}: force balance of {body.name}")
        np.testing.assert_allclose(M, body.inertia * kin.alpha[:, b], rtol=0,
                                   atol=1e-10 * scaleF * 1.0,
                                   err_msg=f"{case}: moment balance of {body.name}")


def test_static_slider_crank_by_hand():
    """Massless centred slider-crank, quasi-static (omega -> 0), a load P on the piston
    along +x.  Statics by hand: the rod is a two-force member in tension
    F = P / cos(theta3) (x balance of the piston); it pulls the crank pin B along
    mu(theta3), a moment r F sin(theta3 - theta2) about A, which the drive torque
    cancels: T = P r sin(theta2 - theta3) / cos(theta3)."""
    r, L, P = 0.1, 0.3, 400.0
    th2 = np.radians(np.arange(5, 356, 10.0))
    mech = slider_crank(r, L, omega=1e-9, masses=(0.0, 0.0, 0.0), load=(P, 0.0))
    lk = Linkage(mech)
    frc = lk.forces(lk.kinematics(th2))
    th3 = -np.arcsin(r * np.sin(th2) / L)
    T = P * r * np.sin(th2 - th3) / np.cos(th3)
    np.testing.assert_allclose(frc.effort, T, rtol=1e-12, atol=1e-12 * P * r)
    np.testing.assert_allclose(np.hypot(*frc.joint_force["C"].T), P / np.cos(th3),
                               rtol=1e-12)


def test_four_bar_gravity_statics_by_virtual_work():
    """Quasi-static four-bar under gravity only: the drive torque equals minus the
    rate of potential energy per crank radian, from central differences of the
    centres of mass heights (an independent route through positions only)."""
    mech = four_bar(0.4, 0.1, 0.3, 0.25, omega=1e-9, gravity=(0.0, -9.81))
    lk = Linkage(mech)
    th = np.radians(np.arange(0, 360, 15.0))
    T = lk.forces(lk.kinematics(th)).effort
    h = 1e-6

    def potential(x):
        kin = lk.kinematics(x)
        return sum(b.mass * 9.81 * kin.com(lk.body_index(b.name))[0][:, 1]
                   for b in mech.moving_bodies)

    dV = (potential(th + h) - potential(th - h)) / (2 * h)
    np.testing.assert_allclose(T, dV, rtol=0, atol=1e-8 * np.max(np.abs(dV)))


def test_forces_without_masses_is_a_typed_error():
    lk = Linkage(load_case("hibbeler-16-31"))
    with pytest.raises(MissingMassError, match=r"\['crank', 'rod', 'piston'\]"):
        lk.forces(lk.kinematics())


def test_drive_torque_scales_with_omega_squared():
    """No gravity or loads: every inertia force scales as omega^2 at alpha2 = 0."""
    lk = Linkage(load_case("seed-four-bar"))
    th = np.radians(np.arange(0, 360, 30.0))
    t1 = lk.forces(lk.kinematics(th, 15.0)).effort
    t2 = lk.forces(lk.kinematics(th, 30.0)).effort
    np.testing.assert_allclose(t2, 4 * t1, rtol=1e-12, atol=1e-15)
    assert math.isfinite(float(t1.sum()))
