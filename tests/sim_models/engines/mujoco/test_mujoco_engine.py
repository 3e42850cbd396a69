"""MuJoCo against the analytic solution: instantaneous mode and short runs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analytic import Linkage, case_names, load_case
from analytic.sweep import input_values
from reports.regression.run_cache import session_run
from sim_models.builders.mjcf import MujocoSettings, direct_solref
from sim_models.runs.driven import EngineRun, mujoco_instantaneous, run

from ...conftest import ENGINE_RELATIVE, MUJOCO_INSTANTANEOUS, assert_run_within

pytest.importorskip("mujoco")


def test_instantaneous_seed_four_bar_at_36_angles():
    """mj_forward at the analytic state: alpha, drive torque and every pin force."""
    mech = load_case("seed-four-bar")
    lk = Linkage(mech)
    vals, _, _ = input_values(lk, 36)
    r = mujoco_instantaneous(mech, MujocoSettings(), vals)
    kin = lk.kinematics(vals)
    frc = lk.forces(kin)
    pk = np.abs(kin.alpha).max()
    assert np.abs(r.alpha - kin.alpha).max() <= MUJOCO_INSTANTANEOUS * pk
    assert np.abs(r.drive_effort - frc.effort).max() <= \
        MUJOCO_INSTANTANEOUS * np.abs(frc.effort).max()
    for j, name in enumerate(r.joint_names):
        ref = frc.joint_force[name]
        err = np.linalg.norm(r.joint_force[:, j] - ref, axis=1).max()
        assert err <= MUJOCO_INSTANTANEOUS * np.linalg.norm(ref, axis=1).max(), name
    # the S4 reference values at 60 deg (ENGINE_NOTES.md)
    r60 = mujoco_instantaneous(mech, MujocoSettings(), math.radians(60))
    b = {n: i for i, n in enumerate(r60.body_names)}
    assert r60.alpha[0, b["coupler"]] == pytest.approx(42.267, abs=1e-3)
    assert r60.alpha[0, b["rocker"]] == pytest.approx(95.504, abs=1e-3)
    assert r60.drive_effort[0] == pytest.approx(0.67334, abs=1e-5)


@pytest.mark.parametrize("case", [c for c in case_names() if load_case(c).has_mass])
def test_instantaneous_all_cases_with_masses(case):
    mech = load_case(case)
    vals, _, _ = input_values(Linkage(mech), 36)
    r = mujoco_instantaneous(mech, MujocoSettings(), vals)
    assert_run_within(r, MUJOCO_INSTANTANEOUS, case)


@pytest.mark.parametrize("case", ["seed-four-bar", "seed-slider-crank"])
def test_short_run_matches_analytic(case):
    """Two revolutions with the default settings (RK4, dt <= 2.5e-4 s, near-hard loops
    with a 10 ms critically damped correction, armature 1e8); the 2nd is sampled."""
    mech = load_case(case)
    r = run(mech, "mujoco", MujocoSettings(), revolutions=2, samples=36)
    assert isinstance(r, EngineRun) and r.ok, r.reason
    lk = Linkage(mech)
    vals, _, _ = input_values(lk, 36)
    np.testing.assert_array_equal(r.values, vals)
    np.testing.assert_allclose(np.remainder(r.measured_values - vals + 1, 2 * math.pi) - 1, 0,
                               atol=1e-6)
    assert_run_within(r, ENGINE_RELATIVE, case)
    assert np.max(np.abs(r.speed_deviation)) < 1e-6 * abs(mech.driver.velocity)
    assert np.max(r.loop_violation) < 1e-6
    assert r.wall_per_rev > 0
    df = r.frame()
    assert {"input", "rocker.alpha" if case == "seed-four-bar" else "slide.a",
            "drive.torque"} <= set(df.columns)


@pytest.mark.parametrize("case", [c for c in case_names()
                                  if c not in ("seed-four-bar", "seed-slider-crank")])
def test_every_case_runs(case):
    """The recommended settings, two revolutions: every built-in case runs and agrees."""
    mech = load_case(case)
    # the session's run (reports.regression.pytest_plugin), shared with the committed-baseline check
    r = session_run(mech, "mujoco", MujocoSettings(), revolutions=2, samples=24)
    assert r.ok, r.reason
    assert_run_within(r, ENGINE_RELATIVE, case)


def test_divergence_is_a_failed_run_not_a_crash():
    mech = load_case("seed-slider-crank")
    bad = MujocoSettings(integrator="Euler", timestep=5e-3, solref=direct_solref(1e-4))
    r = run(mech, "mujoco", bad, revolutions=2, samples=36)
    assert not r.ok
    assert "diverged" in r.reason and "'A'" in r.reason
    assert math.isfinite(r.fail_value)
    assert np.isnan(r.alpha).all()


def test_lost_drive_is_reported():
    mech = load_case("seed-slider-crank")
    r = run(mech, "mujoco", MujocoSettings(armature=1e-3), revolutions=2, samples=36)
    assert not r.ok and "driver rate" in r.reason


def test_limited_range_driver():
    """A prismatic input that cannot cycle: run once from the reference value forward;
    samples behind it or at the limit position are NaN."""
    mech = load_case("hibbeler-16-30")
    r = run(mech, "mujoco", MujocoSettings(), samples=36)
    assert r.ok, r.reason
    reached = np.isfinite(r.alpha).all(axis=1)
    assert 0 < reached.sum() < len(reached)
    assert np.all(r.values[reached] >= mech.driver.value - 1e-12)
    assert_run_within(r, ENGINE_RELATIVE, "hibbeler-16-30")
