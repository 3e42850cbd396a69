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
from sim_models.builders.free_cases import released
from sim_models.engines.free_protocol import free_start
from sim_models.runs.free import free_engine_names, free_settings, open_free_session, run_free
from sim_models.runs.free_run import FreeRequest

ENGINES = free_engine_names()

#: A01 (1 m pendulum released from the horizontal, 1.5 s, ~1 swing, w ~ 3.1 rad/s):
#: worst angle error relative to its range, from each integrator's order at its
#: recommended step h: MuJoCo RK4 (h = 5e-4 s) ~ (h w)^4 w T ~ 1e-12 (measured 3e-12 over
#: 20 s); PyBullet's semi-implicit Euler (1e-4 s) ~ h w ~ 3e-4 (measured 7e-5);
#: Exudyn's generalized-alpha (5e-4 s) ~ (h w)^2 w T ~ 1e-5 (measured 2e-5 over 20 s).
#: Each tolerance is ~10x the estimate, 10-100x below a wrong model's error.
TOL_A01 = {"mujoco": 1e-8, "pybullet": 2e-3, "exudyn": 1e-4}
#: The released seed four-bar under gravity (1 s): loop gap relative to the size.
#: MuJoCo's Baumgarte-stabilised connect holds it to ~1e-8 (measured 2e-9 over 2 s),
#: PyBullet's ERP projection to its step's drift (measured 7.8e-7), Exudyn's index-3
#: solve to round-off (4e-16).
TOL_GAP = {"mujoco": 1e-6, "pybullet": 1e-4, "exudyn": 1e-8}
#: ... and its energy drift relative to the energy scale (conservative case; measured
#: over 2 s: MuJoCo 2.5e-9, PyBullet 3.6e-4 (first order in h), Exudyn 5.2e-5 (the
#: generalized-alpha's numerical dissipation, h^2)).
TOL_ENERGY = {"mujoco": 1e-6, "pybullet": 1e-2, "exudyn": 1e-3}
#: The start equals the reference's t = 0 state to round-off of a few angle sums.
TOL_START = 1e-12
#: The seed four-bar with a point spring, a joint spring, two dampers and a motor table
#: (0.5 s): x errors relative to their range (MuJoCo at 1e-3 s measured 1.0e-4, PyBullet
#: 1.5e-3, Exudyn 1e-4 over 1 s); an element with the wrong sign or size makes them O(1).
#: ... and its joint reactions relative to their peak (measured: MuJoCo 1.0e-5,
#: PyBullet 2.0e-3, Exudyn 4.9e-6; alpha 3.4e-5, 6.3e-3, 1.0e-5).  A spring's or
#: damper's force missing from a subtree, or counted twice, was measured 0.3-0.4 of
#: peak (MuJoCo, before it was found that cfrc_int already holds the tendons' forces).
TOL_FORCE = {"mujoco": 1e-3, "pybullet": 3e-2, "exudyn": 1e-3}
TOL_FORCE["pinocchio"] = 1e-6  # measured 9.3e-10 (forces), 4.1e-9 (accelerations)
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
    assert np.max(np.abs(r.theta - s0.theta[0])) < tol_start(engine)
    assert np.max(np.abs(r.omega - s0.omega[0])) < tol_start(engine)


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
    from sim_models.builders.tree import SimTree
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
    # reactions and accelerations with the elements acting (t = 0 excluded: PyBullet
    # has not stepped), relative to their peak
    s = ref.at(run.times)
    F = np.stack([s.reactions[j] for j in run.joint_names], 1)
    assert np.max(np.abs(run.joint_force[1:] - F[1:])) < TOL_FORCE[engine] * np.abs(F).max()
    assert np.max(np.abs(run.alpha[1:] - s.alpha[1:])) < \
        3 * TOL_FORCE[engine] * np.abs(s.alpha).max()


#: Settings far outside any stable step (a 50 ms explicit step on a four-bar whose
#: rocker swings at ~10 rad/s): the loop opens within a few steps.  Exudyn's implicit
#: index-3 step passes 50 ms at rho_inf 0.8; without numerical damping (rho_inf 1) and
#: with a loose Newton its energy explodes (measured 82.6 J against a 5.1 J scale at
#: 0.6 s; with the default Newton tolerance it fails there after 8 s of step reductions).
DIVERGING = {"mujoco": {"timestep": 0.05, "integrator": "Euler"},
             "pybullet": {"timestep": 0.05, "erp": 0.0},
             "exudyn": {"timestep": 0.1, "spectral_radius": 1.0, "newton_tolerance": 1e-3}}

#: Pinocchio (issue 24; RK4 at 1e-3 s, Baumgarte 0.05, optional: in ENGINES only when
#: pin is installed): A01 measured 4.6e-13 (fourth order, as MuJoCo's RK4); the released
#: four-bar's gap 5.5e-9 of the size (Baumgarte-held, as MuJoCo's connect) and energy
#: 4.6e-9 of its scale; the force elements 1.0e-9 of the range (applied at every RK4
#: stage); a 50 ms semi-implicit Euler step opens the loop at 0.15 s.
TOL_A01["pinocchio"], TOL_GAP["pinocchio"], TOL_ENERGY["pinocchio"] = 1e-8, 1e-6, 1e-6
TOL_ELEMENTS["pinocchio"] = 1e-6
DIVERGING["pinocchio"] = {"timestep": 0.05, "integrator": "euler"}

#: MuJoCo Warp (issue 24; float32, RK4 at 1e-3 s, CG, stock inverse weights; optional:
#: in ENGINES only when mujoco_warp is installed).  Its state is float32: a coordinate
#: is rounded to u32 |q| (2.4e-7 rad at 200 deg) at the start and at every step.
#: Measured: A01 2.9e-7 of the range; the released four-bar's gap 1.0e-6 of the size
#: and energy 8.2e-7 of its scale; the force elements 1.1e-4 of the range, reactions
#: 4.4e-5 and alpha 1.3e-4 of peak; the slider-crank 4.8e-4; the start 8.1e-8 rad
#: (200 deg pendulum).  Tolerances ~10-30x those, still 10-100x below a wrong model's
#: O(1e-2..1) error.
TOL_A01["mujoco_warp"], TOL_GAP["mujoco_warp"], TOL_ENERGY["mujoco_warp"] = 1e-5, 1e-5, 1e-5
TOL_ELEMENTS["mujoco_warp"] = TOL_FORCE["mujoco_warp"] = 1e-3
DIVERGING["mujoco_warp"] = {"timestep": 0.05, "integrator": "Euler"}
#: The released state read back before any step: float32 rounding of the coordinates
#: (u32 times a few rad, summed over the tree: < 1e-6 rad) for a float32 engine.
TOL_START_ENGINE = {"mujoco_warp": 1e-6}


def tol_start(engine: str) -> float:
    return TOL_START_ENGINE.get(engine, TOL_START)


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
    # CPU per simulated second counts the 0.1 s stepped, not the 1 s asked for
    assert math.isclose(run.cpu_per_simulated_second, run.wall / 0.1)


@pytest.mark.parametrize("name", ["iftomm-a03-andrews", "seed-four-bar", "quick-return",
                                  "inverted-slider-crank"])
def test_scalar_body_states_equal_propagate(name):
    """The per-step body states of the harness (scalar) equal SimTree.propagate's."""
    from sim_models.builders.tree import SimTree
    from sim_models.engines.free_protocol import bodies_at
    st = SimTree(load_case(name))
    nt = len(st.joints)
    rng = np.random.default_rng(7)
    q, qd = 0.2 * rng.normal(size=nt), rng.normal(size=nt)
    th, om, _, org, vo, _ = st.propagate(q[None], qd[None], np.zeros((1, nt)))
    for got, want in zip(bodies_at(st, q, qd), (th, om, org, vo), strict=True):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-14)


def test_bare_stepping_loop_is_timed(seed):
    """The speed study's loop: steps per second of advance() alone, from the start."""
    from sim_models.runs.timing import time_free_steps
    mech, ref = seed
    sess = open_free_session(mech, "mujoco")
    try:
        start = free_start(sess.tree, ref.at(np.array([0.0]), forces=False))
        rate = time_free_steps(sess, start, 5e-4, 200, repeats=1)
    finally:
        sess.close()
    assert rate > 0 and math.isfinite(rate)


#: The released seed slider-crank (a prismatic joint, a massless crank, a 500 N load;
#: 0.3 s): every joint coordinate relative to its range (measured over 1 s: MuJoCo
#: 4.8e-5, PyBullet 2.4e-2, Exudyn 2.6e-3); a slider displacement read with the wrong
#: origin or sign would be O(1).
TOL_SLIDER = {"mujoco": 1e-3, "pybullet": 5e-2, "exudyn": 1e-2}
TOL_SLIDER["pinocchio"] = 1e-4  # measured 1.4e-5 (RK4 at 1e-3 s, the crank's fast swing)
TOL_SLIDER["mujoco_warp"] = 3e-3  # measured 4.8e-4 (float32, CG, stock inverse weights)


@pytest.fixture(scope="module")
def slider_crank():
    mech = released(load_case("seed-slider-crank"), duration=0.3)
    return mech, simulate(mech)


@pytest.mark.parametrize("engine", ENGINES)
def test_prismatic_coordinates_follow_reference(engine, slider_crank):
    mech, ref = slider_crank
    run = run_free(mech, engine, request=FreeRequest(0.3, samples=15), reference=ref)
    assert run.ok, run.reason
    s = ref.at(run.times, forces=False)
    assert np.max(np.abs(run.x[0] - s.x[0])) < tol_start(engine)
    assert np.max(np.abs(run.xd[0] - s.xd[0])) < tol_start(engine)
    assert _rel_err(run, ref) < TOL_SLIDER[engine]
    assert np.isfinite(run.joint_force[1:]).all()  # every joint read (t = 0: see PyBullet)


@pytest.mark.parametrize("engine", ENGINES)
def test_body_angles_carry_the_reference_turns(engine):
    """Released at 200 deg (more than half a turn from the tree's reference pose at
    0 deg), the run's body angles are the reference's, not 2 pi off."""
    from dataclasses import replace
    mech = load_case("iftomm-a01-pendulum")
    mech = replace(mech, motion=replace(mech.motion, value=math.radians(200.0),
                                        duration=0.2))
    ref = simulate(mech)
    run = run_free(mech, engine, request=FreeRequest(0.2, samples=4), reference=ref)
    s = ref.at(run.times, forces=False)
    assert run.ok, run.reason
    assert np.max(np.abs(run.theta[0] - s.theta[0])) < tol_start(engine)
    assert np.max(np.abs(run.x[0] - s.x[0])) < tol_start(engine)
    assert np.max(np.abs(run.theta - s.theta)) < 1e-2  # no whole turn anywhere


@pytest.mark.parametrize("limit", [0.0, -1.0, math.inf, math.nan, 1e6])
def test_the_wall_limit_is_range_checked(limit):
    """Every door checks sim_models.engines.ranges.WALL_LIMIT (``--wall-limit`` reads it too)."""
    from sim_models.engines.settings import SettingsError
    with pytest.raises(SettingsError, match="wall_limit"):
        FreeRequest(1.0, wall_limit=limit)
