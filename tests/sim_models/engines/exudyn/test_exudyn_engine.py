"""Exudyn against the analytic solution: every built-in case at the recommended settings.

Independent expectations: the analytic solver (:mod:`analytic`, itself checked against
REFERENCE.md, closed forms and finite differences), the S4 figures of ENGINE_NOTES.md,
and the multibody convention that a massless link adds no inertia.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from analytic import Linkage, case_names, load_case
from analytic.mechanism import Driver, Load, Revolute
from analytic.sweep import input_values
from sim_models import compile_linkage
from sim_models.engines.protocol import EngineRefusal, SettingsError
from sim_models.engines.registry import get_engine
from sim_models.runs.driven import instantaneous, run

from ...conftest import ENGINE_RELATIVE, assert_run_within

pytest.importorskip("exudyn")

#: What issue 9 asks of Exudyn at its recommended settings: every judged quantity
#: (accelerations, every joint reaction including a prismatic joint's normal force and
#: couple, the drive effort) within 1e-4 of its peak.  The settings' grid puts the worst
#: built-in case at 3.7e-5 (hibbeler-16-30, linkCB.alpha next to its limit position),
#: so this is a must-show with a factor of 2.7 to spare, not a loosened bound.
EXUDYN_MUST_SHOW = 1e-4


def _prismatic_reactions(r, mech, tol):
    """Normal force and couple of every prismatic joint within ``tol``.  A ground-guided
    slider's couple is identically zero, so the couple is judged on the scale of the
    normal force times the mechanism's size (the couple a normal force could make)."""
    if not mech.has_mass or not r.prismatic_names:
        return
    from reports.comparison.compare import analytic_at, compare
    _, kin, frc = analytic_at(r)
    keep = (kin.condition <= 100.0) & np.all(np.isfinite(r.alpha), axis=1)
    size = compile_linkage(mech).size
    for p, name in enumerate(r.prismatic_names):
        n_ref, m_ref = frc.normal[name][keep], frc.moment[name][keep]
        at = r.values[keep]
        c = compare(f"{name}.normal", n_ref, r.normal[keep, p], at, tol)
        assert c.passed, str(c)
        c = compare(f"{name}.moment", m_ref, r.moment[keep, p], at, tol,
                    peak_floor=float(np.max(np.abs(n_ref))) * size)
        assert c.passed, str(c)


@pytest.mark.parametrize("case", case_names())
def test_every_case_at_recommended_settings(case):
    """Two revolutions (limited-range inputs: their range) at the recommended settings:
    the verdict tolerance and the stricter must-show of issue 9."""
    mech = load_case(case)
    r = run(compile_linkage(mech), "exudyn", revolutions=2, samples=36)
    assert r.ok, r.reason
    assert r.settings == get_engine("exudyn").settings()
    assert_run_within(r, ENGINE_RELATIVE, case)
    assert_run_within(r, EXUDYN_MUST_SHOW, case)
    _prismatic_reactions(r, mech, EXUDYN_MUST_SHOW)
    done = np.isfinite(r.alpha).all(axis=1)
    assert np.max(r.loop_violation[done]) < 1e-9 * compile_linkage(mech).size
    assert np.max(np.abs(r.speed_deviation[done])) < 1e-9 * max(
        abs(mech.driver.velocity), abs(mech.driver.acceleration))


#: Exudyn's own initial-value solve at the exact analytic state (its forward dynamics,
#: the instantaneous mode): measured 1e-8 to 1.2e-6 of peak over the built-in cases (the
#: constraint's quadratic velocity term is not exact in it); 1e-5 leaves room for
#: round-off on another machine and still separates it from the runs' 1e-5 to 6e-5.
EXUDYN_INSTANTANEOUS = 1e-5


@pytest.mark.parametrize("case", case_names())
def test_instantaneous_mode_every_case(case):
    tree = compile_linkage(load_case(case))
    vals, _, _ = input_values(tree.linkage, 36)
    r = instantaneous(tree, "exudyn", None, vals)
    assert_run_within(r, EXUDYN_INSTANTANEOUS, case)


#: Sampling by state at the exact analytic state: one linear solve with Exudyn's mass
#: matrix, constraint Jacobian and forces and the exact velocity terms.  Measured
#: 1e-15..3e-11 of the state's own scale over the built-in cases (Exudyn's own
#: initial-value solve, whose velocity term is a finite difference: 1e-8..1.2e-6), so
#: 1e-9 holds round-off and fails a wrong sign or term of any joint's velocity term.
EXUDYN_STATE_EXACT = 1e-9


@pytest.mark.parametrize("case", case_names())
def test_state_readout_is_exact_at_the_exact_state(case):
    """The deferred readout (record, then convert) at the analytic reference state: the
    accelerations and reactions must be the analytic ones up to round-off."""
    from sim_models.engines.protocol import Recorder, plan_samples
    tree = compile_linkage(load_case(case))
    session = get_engine("exudyn").session_class(tree)
    try:
        rec = Recorder(tree, plan_samples(tree, 1, 4))
        session.reset(0.0, 1e-3)
        raw, ahead, why = session.record(0.0)
        assert why is None and ahead == 0.0
        session.convert(np.zeros(1), [raw], [[0]], rec)
    finally:
        session.close()
    kin = tree.kin_ref
    scale = max(np.max(np.abs(kin.alpha[0])), np.max(np.abs(kin.omega[0])) ** 2)
    np.testing.assert_allclose(rec.alpha[0], kin.alpha[0], rtol=0, atol=EXUDYN_STATE_EXACT * scale)
    if tree.has_mass:
        frc = tree.linkage.forces(kin)
        F = np.array([frc.joint_force[j.name][0] for j in tree.mech.joints])
        fscale = np.max(np.abs(F))
        np.testing.assert_allclose(rec.force[0], F, rtol=0, atol=EXUDYN_STATE_EXACT * fscale)
        np.testing.assert_allclose(rec.effort[0], frc.effort[0], rtol=0,
                                   atol=EXUDYN_STATE_EXACT * max(abs(frc.effort[0]),
                                                                 fscale * tree.size))


@pytest.mark.parametrize("velocity, acceleration", [(15.0, -10.0), (0.0, 300.0)])
def test_reversing_and_from_rest_inputs(velocity, acceleration):
    """A crank that slows down and turns back (sampled by time, from t = 0) and one that
    starts from rest: the t = 0 sample is Exudyn's own initial solve with the drive
    acceleration it leaves out added, the rest the integration."""
    m = load_case("offset-slider-crank" if velocity == 0 else "seed-four-bar")
    mech = dataclasses.replace(m, name="varied", driver=Driver(m.driver.joint, m.driver.value,
                                                               velocity, acceleration))
    r = run(mech, "exudyn", revolutions=2, samples=36)
    assert r.ok, r.reason
    assert_run_within(r, EXUDYN_MUST_SHOW, mech.name)


@pytest.mark.parametrize("case", ["quick-return", "hibbeler-16-31"])
def test_integrator_readout_at_twice_the_steps(case):
    """The generalized-alpha step's own accelerations and multipliers (sample_by =
    integrator) need 2016 steps for what sampling by state reaches with 1008: checked on
    the worst constant-speed case and an accelerating input."""
    s = get_engine("exudyn").settings({"sample_by": "integrator", "steps_per_rev": "2016",
                                       "spectral_radius": "0.7"})
    mech = load_case(case)
    r = run(mech, "exudyn", s, revolutions=2, samples=36)
    assert r.ok, r.reason
    assert_run_within(r, EXUDYN_MUST_SHOW, case)


def test_sampling_by_state_leaves_the_integration_untouched():
    """Sampling by state solves at the integrated state and hands the integrator its state
    back: positions and velocities at every sample are bit-identical to the integrator's
    readout of the same run; only the accelerations (and forces) differ."""
    mech = load_case("hibbeler-16-31")
    runs = [run(mech, "exudyn", get_engine("exudyn").settings({"sample_by": by}),
                revolutions=2, samples=12) for by in ("state", "integrator")]
    np.testing.assert_array_equal(runs[0].theta, runs[1].theta)
    np.testing.assert_array_equal(runs[0].omega, runs[1].omega)
    assert not np.array_equal(runs[0].alpha, runs[1].alpha)


def test_seed_four_bar_figures_of_engine_notes():
    """The S4 four-bar at 60 deg (ENGINE_NOTES.md): coupler and rocker alpha, drive torque."""
    mech = load_case("seed-four-bar")
    r = run(mech, "exudyn", revolutions=2, samples=36)
    k = int(np.argmin(np.abs(np.remainder(r.values - math.radians(60) + 1, 2 * math.pi) - 1)))
    b = {n: i for i, n in enumerate(r.body_names)}
    assert r.alpha[k, b["coupler"]] == pytest.approx(42.267, abs=2e-3)
    assert r.alpha[k, b["rocker"]] == pytest.approx(95.504, abs=2e-3)
    assert r.drive_effort[k] == pytest.approx(0.67334, abs=2e-5)


def test_massless_link_is_massless_in_the_model():
    """The seed slider-crank's crank has mass 0: the model keeps it at exactly 0 (no floor
    mass), and the run still agrees (checked in the every-case test)."""
    session = get_engine("exudyn").session_class(compile_linkage(load_case("seed-slider-crank")))
    try:
        crank = session.tree.body_names.index("crank")
        obj = session.mbs.GetObject(session.obj[crank])
        assert obj["mass"] == 0.0 and obj["inertia"] == 0.0
    finally:
        session.close()


def test_all_massless_linkage_gives_the_statics():
    """With every link massless the reactions are the statics of the gas load alone; the
    mass matrix is zero, the Newton matrix still regular (square constraint Jacobian).
    The multipliers then carry no integration error: round-off agreement."""
    m = load_case("offset-slider-crank")
    bodies = tuple(dataclasses.replace(b, mass=0.0, inertia=0.0) if b.name != m.ground
                   else b for b in m.bodies)
    mech = dataclasses.replace(m, name="massless", bodies=bodies)
    r = run(mech, "exudyn", revolutions=2, samples=36)
    assert r.ok, r.reason
    assert_run_within(r, EXUDYN_MUST_SHOW, mech.name)
    from reports.comparison.compare import compare_run
    forces = [c for c in compare_run(r) if c.quantity.endswith(".force")
              or c.quantity == "drive.effort"]
    assert forces and max(c.normalised for c in forces) < 1e-9


@pytest.mark.parametrize("key, value", [("spectral_radius", "1.5"), ("spectral_radius", "-0.1"),
                                        ("timestep", "0"), ("steps_per_rev", "0"),
                                        ("newton_tolerance", "-1"), ("sample_by", "magic")])
def test_bad_setting_is_one_line_naming_it(key, value):
    with pytest.raises(SettingsError, match=f"exudyn.*{key}"):
        get_engine("exudyn").settings({key: value})


def _slider_driven(acc, com=None):
    """The offset slider-crank driven at its slider (a limited-range prismatic input with
    forces; the built-in prismatic inputs are kinematics-only), optionally with the
    piston's centre of mass off the slider point."""
    m = load_case("offset-slider-crank")
    s0 = float(Linkage(m).kinematics().slider("slide")[0][0])
    bodies = m.bodies if com is None else tuple(
        dataclasses.replace(b, com=com) if b.name == "piston" else b for b in m.bodies)
    return dataclasses.replace(m, name="slider-driven", bodies=bodies,
                               driver=Driver("slide", s0, -1.0, acc))


@pytest.mark.parametrize("com", [None, (0.01, 0.005)])
def test_prismatic_driver_with_forces(com):
    """Drive force on the slider, normal force and couple of the driven prismatic joint;
    with the centre of mass off the slider point the drive force's moment enters the
    couple (a wrong sign would be off by 0.15 of the scale)."""
    mech = _slider_driven(-5.0, com)
    r = run(mech, "exudyn", revolutions=1, samples=24)
    assert r.ok, r.reason
    assert_run_within(r, ENGINE_RELATIVE, mech.name)
    _prismatic_reactions(r, mech, ENGINE_RELATIVE)


def test_accelerating_crank_with_forces():
    """A crank with alpha != 0 (the drive offset is a time function) on a case with
    masses, gravity and a load: the built-in accelerating inputs are kinematics-only."""
    m = load_case("offset-slider-crank")
    mech = dataclasses.replace(m, name="accelerating", driver=Driver("O", m.driver.value,
                                                                      60.0, 200.0))
    r = run(mech, "exudyn", revolutions=2, samples=36)
    assert r.ok, r.reason
    assert_run_within(r, EXUDYN_MUST_SHOW, mech.name)


def test_driver_turning_the_ground_relative_to_the_crank():
    """The driven pin written the other way round (body_b is the ground: the value is
    minus the crank angle, the effort acts on the ground) and a load on the ground."""
    m = load_case("seed-four-bar")
    joints = tuple(Revolute("O2", "crank", "O2", "ground", "O2") if j.name == "O2" else j
                   for j in m.joints)
    mech = dataclasses.replace(m, name="reversed-pin", joints=joints,
                               driver=Driver("O2", -m.driver.value, -m.driver.velocity),
                               loads=(Load("ground", None, (5.0, 0.0)),))
    r = run(mech, "exudyn", revolutions=2, samples=36)
    assert r.ok, r.reason
    assert_run_within(r, EXUDYN_MUST_SHOW, mech.name)
    np.testing.assert_allclose(np.remainder(r.measured_values - r.values + 1, 2 * math.pi) - 1,
                               0, atol=1e-9)


def test_prismatic_driver_on_a_moving_guide_is_refused():
    m = load_case("inverted-slider-crank")
    s0 = float(Linkage(m).kinematics().slider("slot")[0][0])
    mech = dataclasses.replace(m, driver=Driver("slot", s0, 0.1))
    with pytest.raises(EngineRefusal, match="slot.*moving body 'rocker'"):
        run(mech, "exudyn", revolutions=1, samples=6)


def test_failed_newton_is_a_failed_run_not_an_exception():
    """A Newton tolerance at round-off cannot be met: the run ends with a reason.  1e-15
    is the smallest the settings accept (1e-30 is refused, sim_models/engines/ranges.py); the
    seed four-bar's Newton fails there at 120 deg (measured; 1e-14 passes)."""
    s = get_engine("exudyn").settings({"newton_tolerance": "1e-15"})
    r = run(load_case("seed-four-bar"), "exudyn", s, revolutions=1, samples=6)
    assert not r.ok and "Exudyn solver failed" in r.reason
    assert np.isnan(r.alpha[r.times > 0]).all()  # the t = 0 sample precedes any step


def test_change_point_is_a_failed_run_that_names_it():
    """The parallelogram four-bar's links are collinear at theta2 = 0 and 180 deg (its
    description): a change point, where Exudyn's index-3 Newton is not to be trusted.
    Assembled at 30 deg and turning forward, the first one met is 180 deg: the run fails
    there with a reason naming it, and no sample is read past it."""
    from pathlib import Path
    mech = load_case(Path(__file__).parents[4] / "analytic/cases/hard/parallelogram-four-bar.toml")
    r = run(mech, "exudyn", revolutions=2, samples=36)
    assert not r.ok
    assert "change point of driver 'O2' at 180 deg" in r.reason
    assert np.isnan(r.alpha).all() and np.isnan(r.joint_force).all()
