"""Judging a free trajectory (reports.comparison.free_compare) on synthetic engine runs whose errors
are known in closed form: IFToMM A01, the simple pendulum released from the horizontal
(amplitude 90 deg: over half a period, 1.18 s, the joint angle's range is exactly pi, its
largest kinetic energy m g L = 9.81 J equals the range of its potential energy), and the
seed four-bar released under gravity (for the reference events)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analytic import load_case
from analytic.free_motion import simulate
from reports.comparison import free_advice
from reports.comparison import free_compare as fc
from reports.comparison.iftomm import grounded_point
from sim_models.builders.free_cases import released

from .free_synthetic import synthetic_run

#: A01 from the horizontal: period 4 sqrt(L/g) K(sin 45 deg) = 2.368 s; 1.5 s covers the
#: swing to the opposite horizontal, so the joint angle's range is pi.
A01_T = 1.5
A01_N = 300
#: The sampled extremes miss the exact ones by about g/L dt^2 / 2 = 3e-5 rad of pi.
SAMPLED = 1e-4


@pytest.fixture(scope="module")
def a01():
    return simulate(load_case("iftomm-a01-pendulum"), A01_T)


def test_exact_run_passes_with_no_error(a01):
    v = fc.compare_free(synthetic_run(a01, A01_T, A01_N), a01)
    assert v.passed, [str(c) for c in v.judged if not c.passed]
    assert max(c.normalised for c in v.judged) < 1e-12
    assert math.isinf(v.horizon)
    assert v.near_event is None and v.step_note is None
    names = {c.quantity for c in v.comparisons}
    assert {"O.x", "O.xd", "link.theta", "link.omega", "link.alpha", "O.force"} <= names


def test_linear_drift_error_and_trusted_horizon(a01):
    c = 0.1  # rad/s added to the joint angle: error c t, range pi
    v = fc.compare_free(synthetic_run(a01, A01_T, A01_N, x_drift=(0, c, 0.0)), a01)
    ox = next(q for q in v.comparisons if q.quantity == "O.x")
    assert ox.scale == pytest.approx(math.pi, rel=SAMPLED)
    assert ox.normalised == pytest.approx(c * A01_T / math.pi, rel=SAMPLED)
    assert ox.at == pytest.approx(A01_T)
    # the error c t first reaches FREE_KINEMATIC * pi at this time
    assert ox.horizon == pytest.approx(fc.FREE_KINEMATIC * math.pi / c, rel=SAMPLED)
    assert not v.passed and v.worst.quantity == "O.x"
    assert v.horizon == pytest.approx(ox.horizon)
    # the body angle was not perturbed: it passes
    assert next(q for q in v.comparisons if q.quantity == "link.theta").passed
    assert "--timestep" in v.step_note


def test_energy_drift_relative_to_energy_scale(a01):
    # kinetic energy 4 % high: at its largest (m g L) that is 0.04 m g L over the scale
    # max KE + range PE = 2 m g L
    v = fc.compare_free(synthetic_run(a01, A01_T, A01_N, kinetic_factor=1.04), a01)
    assert v.energy.scale == pytest.approx(2 * 9.81, rel=SAMPLED)
    assert v.energy.normalised == pytest.approx(0.02, rel=1e-3)
    assert not v.energy.passed and not v.passed
    small = fc.compare_free(synthetic_run(a01, A01_T, A01_N, kinetic_factor=1.01), a01)
    assert small.energy.normalised == pytest.approx(0.005, rel=1e-3) and small.energy.passed


def test_loop_drift_relative_to_size(a01):
    g = 2 * fc.LOOP_DRIFT  # m, on a 1 m mechanism: crosses LOOP_DRIFT halfway
    v = fc.compare_free(synthetic_run(a01, A01_T, A01_N, gap=g), a01)
    assert v.loop.scale == pytest.approx(1.0)
    assert v.loop.normalised == pytest.approx(g)
    assert v.loop.horizon == pytest.approx(A01_T / 2, rel=1e-9)
    assert not v.passed


@pytest.mark.parametrize(("offset", "level"), [(5e-4, "1e-3"), (0.05, "1e-1"),
                                               (0.3, "none")])
def test_iftomm_classes_from_a_known_angle_offset(a01, offset, level):
    # P1 is 1 m from the pin: an angle offset d moves it by the chord 2 sin(d / 2)
    v = fc.compare_free(synthetic_run(a01, A01_T, A01_N, theta_offset=(1, offset)), a01)
    assert v.iftomm is not None
    assert v.iftomm.max_error == pytest.approx(2 * math.sin(offset / 2), rel=1e-9)
    assert v.iftomm.level == level


def test_grounded_point_is_the_pendulum_tip(a01):
    th = np.array([0.0, -0.5, -math.pi / 2, 2.0])
    p = grounded_point(a01.mech, "link", "P1", th)
    np.testing.assert_allclose(p, np.stack([np.cos(th), np.sin(th)], axis=1), atol=1e-15)


def test_stopped_run_is_not_measured_and_fails(a01):
    v = fc.compare_free(synthetic_run(a01, A01_T, A01_N, stop_at=100), a01)
    t = np.linspace(0, A01_T, A01_N + 1)
    assert not v.passed
    assert all(c.measured_until == pytest.approx(t[99]) for c in v.judged)
    assert v.horizon == pytest.approx(t[99])
    assert v.iftomm.level == "none"
    assert "not measured" in str(v.comparisons[0])


def test_horizon_interpolates_and_ignores_unmeasured():
    t = np.array([0.0, 1.0, 2.0, 3.0])
    assert fc.horizon_of(t, np.array([0.0, 0.005, 0.015, 0.02]), 0.01) == pytest.approx(1.5)
    assert math.isinf(fc.horizon_of(t, np.array([0.0, 0.005, np.nan, np.nan]), 0.01))
    assert fc.horizon_of(t, np.array([0.5, 0.0, 0.0, 0.0]), 0.01) == 0.0


def test_constant_quantity_is_judged_on_its_family_scale():
    t = np.linspace(0, 1, 11)
    ref = np.full(11, 3.0)
    c = fc.judge("q", "reaction", "N", t, ref, ref + 0.01, 0.05, family_scale=2.0)
    assert c.scale == 2.0 and "reaction scale" in c.normalisation
    assert c.normalised == pytest.approx(0.005)


def test_failed_verdict_names_the_nearest_reference_event():
    mech = released(load_case("seed-four-bar"), 1.0)
    traj = simulate(mech)
    ev = next(e for e in traj.events if e.kind in free_advice.EVENT_KINDS)
    # a joint angle that leaves the reference at the event, fast: the trust is lost
    # within a few ms of it
    run = synthetic_run(traj, 1.0, 200, x_drift=(0, 50.0, ev.t))
    v = fc.compare_free(run, traj)
    assert not v.passed
    assert v.horizon == pytest.approx(ev.t, abs=0.02)
    kind = {"limit": "limit position", "singular": "singular position",
            "switch": "coordinate switch"}[ev.kind]
    assert v.near_event is not None and kind in v.near_event
    assert f"{ev.t:.6g}" in v.near_event


def test_a_sample_the_engine_does_not_read_is_not_a_stop(a01):
    run = synthetic_run(a01, A01_T, A01_N)
    run.alpha[0] = np.nan  # as PyBullet, whose accelerations come from past velocities
    v = fc.compare_free(run, a01)
    alpha = next(c for c in v.comparisons if c.quantity == "link.alpha")
    assert alpha.measured and alpha.unread == 1 and alpha.passed
    assert v.passed


def test_a_quantity_the_engine_never_reads_is_named_not_judged(a01):
    run = synthetic_run(a01, A01_T, A01_N)
    run.joint_force[:] = np.nan  # as Exudyn's prismatic joint forces
    v = fc.compare_free(run, a01)
    assert v.not_read == ("O.force",) and v.passed
    assert "O.force" not in {c.quantity for c in v.judged}
    stopped = synthetic_run(a01, A01_T, A01_N, stop_at=0)  # a run that stopped at once
    assert not fc.compare_free(stopped, a01).passed


def test_an_event_is_named_only_nearer_than_halfway_to_its_neighbours():
    """A02's singular crossings come every ~0.52 s of a 20 s run (5% of which is 1 s):
    a trust lost at 0.10 s is not the crossing at 0.72 s's doing (it is nearer the run's
    start than halfway), one lost 0.05 s before a crossing is."""
    from types import SimpleNamespace

    from analytic.free_motion.trajectory import Event
    events = [Event(t, "singular", "G0", "40 dyads meet")
              for t in (0.7215810248, 1.2440209039, 2.6871829535)]
    lost = SimpleNamespace(quantity="L22.force")

    def named(t_lost):
        v = SimpleNamespace(horizon=t_lost, duration=20.0, lost_by=lost)
        return free_advice.near_free_event(v, events)
    assert named(0.10) is None                      # 0.62 s before, 0.72 s from the start
    assert named(0.30) is None                      # 0.42 s before, 0.30 s from the start
    msg = named(1.244 - 0.05)
    assert msg is not None and "before" in msg and "1.24402" in msg
    assert "after" in named(0.7215810248 + 0.2) and "0.721581" in named(0.92)
    assert named(2.6871829535 + 1.1) is None        # past the last: 5% of 20 s is the bar
