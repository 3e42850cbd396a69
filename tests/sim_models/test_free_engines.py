"""Free motion in the engines (issue 21): each engine released from the exact state
against the exact reference (:func:`analytic.free_motion.simulate`, DOP853 at rtol
1e-13: its own error is far below every tolerance here).

Expected values are independent of the engines: the reference trajectory, the
conservation of energy, the loop's closure."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analytic import load_case
from analytic.free_motion import simulate
from analytic.motion_spec import JointDamper, JointSpring, Motor, PointDamper, PointSpring
from sim_models.free_base import free_start
from sim_models.free_cases import released
from sim_models.free_engine import free_engine_names, free_settings, open_free_session, run_free
from sim_models.free_run import FreeRequest

ENGINES = free_engine_names()

#: A01 (1 m pendulum released from the horizontal, 1.5 s, ~1 swing): worst angle error
#: relative to its range.  MuJoCo RK4 at 1e-3 s: fourth order, h^4 w^5 T ~ 1e-12 x 300
#: ~ 3e-10 (measured 1e-12); PyBullet's semi-implicit Euler is first order in h:
#: h w^2 T ~ 1e-4 x 10 x 1.5 ~ 1.5e-3 at its 1e-4 s... (see TOL_A01 per engine);
#: Exudyn's generalized-alpha is second order: h^2 w^3 T ~ 1e-6 x 30 ~ 3e-5.
TOL_A01 = {"mujoco": 1e-8, "pybullet": 2e-3, "exudyn": 1e-4}
#: The released seed four-bar under gravity (1 s): loop gap relative to the size.
#: MuJoCo's Baumgarte-stabilised connect holds it to ~1e-8 of the size (measured 3e-9),
#: PyBullet's ERP projection to its step's drift, Exudyn's index-3 solve to Newton's
#: tolerance.
TOL_GAP = {"mujoco": 1e-6, "pybullet": 1e-4, "exudyn": 1e-8}
#: ... and its energy drift relative to the energy scale (conservative case).  RK4:
#: measured 3e-8; semi-implicit Euler is symplectic for the tree but ERP removes
#: energy with the gap; generalized-alpha at rho_inf < 1 damps the highest modes only.
TOL_ENERGY = {"mujoco": 1e-6, "pybullet": 1e-2, "exudyn": 1e-3}
#: The start equals the reference's t = 0 state to round-off of a few angle sums.
TOL_START = 1e-12
#: The seed four-bar with a point spring, a joint spring, two dampers and a motor table
#: (0.5 s): x errors relative to their range (short run, small range: MuJoCo measured
#: 1.0e-4, its gravity-only error of ~1e-5 of a 4x larger range); the elements' signs
#: wrong would make them O(1).
TOL_ELEMENTS = {"mujoco": 1e-3, "pybullet": 1e-2, "exudyn": 1e-3}


@pytest.fixture(scope="module")
def a01():
    mech = load_case("iftomm-a01-pendulum")
    return mech, simulate(mech, duration=1.5)


@pytest.fixture(scope="module")
def seed():
    mech = released(load_case("seed-four-bar"), duration=1.0)
    return mech, simulate(mech)


@pytest.fixture(scope="module")
def seed_elements():
    m = load_case("seed-four-bar")
    mech = released(m, duration=0.5, springs=[
        PointSpring("coupler", "B", "ground", "O2", 30.0, 0.25), JointSpring("O4", 0.5, 0.0)],
        dampers=[JointDamper("O4", 0.01), PointDamper("coupler", "A", "ground", "O4", 0.2)],
        motors=[Motor("O2", times=(0.0, 0.25, 0.5), efforts=(0.0, 0.3, 0.1))])
    return mech, simulate(mech)


def _rel_err(run, ref):
    s = ref.at(run.times, forces=False)
    rng = np.maximum(np.ptp(s.x, axis=0), 1e-9)
    return float(np.nanmax(np.abs(run.x - s.x) / rng))


@pytest.mark.parametrize("engine", ENGINES)
def test_start_is_the_reference_state(engine, seed):
    mech, ref = seed
    s0 = ref.at(np.array([0.0]), forces=False)
    sess = open_free_session(mech, engine)
    try:
        start = free_start(sess.tree, s0)
        sess.start(start, 1e-4)
        r = sess.read(0.0)
    finally:
        sess.close()
    assert np.max(np.abs(r.theta - s0.theta[0])) < TOL_START
    assert np.max(np.abs(r.omega - s0.omega[0])) < TOL_START


@pytest.mark.parametrize("engine", ENGINES)
def test_a01_matches_reference(engine, a01):
    mech, ref = a01
    run = run_free(mech, engine, request=FreeRequest(1.5, samples=30), reference=ref)
    assert run.ok, run.reason
    assert _rel_err(run, ref) < TOL_A01[engine]


@pytest.mark.parametrize("engine", ENGINES)
def test_released_four_bar_keeps_loop_and_energy(engine, seed):
    mech, ref = seed
    run = run_free(mech, engine, request=FreeRequest(1.0, samples=20), reference=ref)
    assert run.ok, run.reason
    from sim_models.tree import SimTree
    size = SimTree(mech).size
    assert np.nanmax(run.loop_gap) < TOL_GAP[engine] * size
    E = run.kinetic + run.potential
    assert np.max(np.abs(E - run.extra["E0"])) < TOL_ENERGY[engine] * run.extra["energy_scale"]
    # the energy function is the reference's: equal at t = 0
    s0 = ref.at(np.array([0.0]), forces=False)
    assert E[0] == pytest.approx(s0.kinetic[0] + s0.potential[0], abs=1e-12)


@pytest.mark.parametrize("engine", ENGINES)
def test_force_elements_follow_reference(engine, seed_elements):
    mech, ref = seed_elements
    run = run_free(mech, engine, request=FreeRequest(0.5, samples=10), reference=ref)
    assert run.ok, run.reason
    assert _rel_err(run, ref) < TOL_ELEMENTS[engine]
    assert run.motor_effort_engine is not None


#: Settings far outside any stable step (a 50 ms explicit step on a four-bar whose
#: rocker swings at ~10 rad/s): the loop opens within a few steps.  Exudyn's implicit
#: index-3 step passes 50 ms at rho_inf 0.8; without numerical damping (rho_inf 1) its
#: Newton fails (measured at t = 0.6 s).
DIVERGING = {"mujoco": {"timestep": 0.05, "integrator": "Euler"},
             "pybullet": {"timestep": 0.05, "erp": 0.0},
             "exudyn": {"timestep": 0.1, "spectral_radius": 1.0}}

#: Pinocchio (issue 24; RK4 at 1e-3 s, Baumgarte 0.05, optional: in ENGINES only when
#: pin is installed): A01 measured 4.6e-13 (fourth order, as MuJoCo's RK4); the released
#: four-bar's gap 5.5e-9 of the size (Baumgarte-held, as MuJoCo's connect) and energy
#: 4.6e-9 of its scale; the force elements 1.0e-9 of the range (applied at every RK4
#: stage); a 50 ms semi-implicit Euler step opens the loop at 0.15 s.
TOL_A01["pinocchio"], TOL_GAP["pinocchio"], TOL_ENERGY["pinocchio"] = 1e-8, 1e-6, 1e-6
TOL_ELEMENTS["pinocchio"] = 1e-6
DIVERGING["pinocchio"] = {"timestep": 0.05, "integrator": "euler"}


@pytest.mark.parametrize("engine", ENGINES)
def test_diverging_setting_is_a_result(engine, seed):
    mech, ref = seed
    run = run_free(mech, engine, free_settings(engine, DIVERGING[engine]),
                   FreeRequest(1.0, samples=20), ref)
    assert not run.ok and run.reason and run.t_fail is not None
    late = run.times >= run.t_fail
    assert np.isnan(run.x[late]).all() and np.isfinite(run.x[~late]).all()


def test_wall_clock_limit_is_a_result(seed):
    mech, ref = seed
    run = run_free(mech, ENGINES[0], request=FreeRequest(1.0, samples=10, wall_limit=1e-9),
                   reference=ref)
    assert not run.ok and "wall-clock" in run.reason
    assert math.isclose(run.t_fail, 0.1)
