"""The run loop's deferred readout (issue 11, item 3): raw engine state recorded at each
stop and converted once after the run must give exactly what converting each sample at
its stop gives, verdicts and failure points included."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analytic import load_case
from sim_models.engines import protocol
from sim_models.engines.protocol import (
    check_motion,
    compile_linkage,
    drive,
    first_divergence,
    plan_samples,
)
from sim_models.engines.registry import get_engine
from sim_models.runs.engine_run import RunRequest

#: Arrays of a run compared between the deferred and the per-sample readout.
FIELDS = ("theta", "omega", "alpha", "slider_acc", "drive_effort", "joint_force", "normal",
          "moment", "loop_violation", "speed_deviation", "measured_values", "q", "qd", "qdd",
          "drive_effort_engine", "joint_force_engine")

#: Conversion of one record at a time and of all at once are the same element-wise
#: arithmetic; allow a few ulps for a reduction that numpy may order differently.
ROUND_OFF = 1e-13


def per_sample(cls):
    """``cls`` with the readout done at each stop: :meth:`convert` of that one record,
    then the divergence check of its loop gap and driver rate there (the way the run
    loop worked before the conversion was deferred)."""

    class PerSample(cls):
        @property
        def deferred(self) -> bool:
            return False

        def sample(self, t, rows, rec):
            raw, ahead, self._why = self.record(t)
            if self._why is None:
                gap, rate = self.convert(np.array([t]), [raw], [list(rows)], rec)
                self._why = check_motion(self.tree, float(gap[0]), float(rate[0]), t,
                                         self.max_violation, self.max_speed_error)
            return ahead

        def divergence(self, t):
            return self._why

    return PerSample


def both_runs(engine, case, settings=None, revolutions=2, samples=36, max_violation=1e-3):
    pytest.importorskip(engine)
    cls = get_engine(engine).session_class
    tree = compile_linkage(load_case(case))
    plan = plan_samples(tree, revolutions, samples)
    request = RunRequest(revolutions, samples, max_violation)
    out = []
    for c in (cls, per_sample(cls)):
        s = c(tree, settings)
        try:
            assert s.deferred is (c is cls)
            out.append(drive(s, plan, request))
        finally:
            s.close()
    return out


def assert_same(a, b):
    assert (a.ok, a.reason, a.steps, a.fail_value) == (b.ok, b.reason, b.steps, b.fail_value)
    for f in FIELDS:
        x, y = getattr(a, f), getattr(b, f)
        if x is None or y is None:
            assert x is None and y is None, f
            continue
        assert np.array_equal(np.isnan(x), np.isnan(y)), f"{f}: NaN pattern differs"
        scale = max(float(np.nanmax(np.abs(x), initial=0.0)), 1e-300)
        assert np.nanmax(np.abs(x - y), initial=0.0) <= ROUND_OFF * scale, f


@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])
@pytest.mark.parametrize("case", ["six-bar", "seed-slider-crank", "quick-return"])
def test_deferred_readout_equals_per_sample(engine, case, monkeypatch):
    """Every sample array, verdict and step count; the seed slider-crank has a slider
    and a load, the quick-return a slider on a moving guide (converted in blocks of 7
    records there)."""
    if case == "quick-return":
        monkeypatch.setattr(protocol, "RAW_BLOCK", 7)
    deferred, each = both_runs(engine, case)
    assert deferred.ok and np.isfinite(deferred.alpha).all()
    assert_same(deferred, each)


@pytest.mark.parametrize("block", [None, 4])
def test_failure_mid_run_ends_where_the_per_sample_check_ends_it(block, monkeypatch):
    """PyBullet at 5 ms on the seed four-bar, with the loop-gap limit set between the
    gaps it shows, so that the run fails in mid-revolution: the same reason, driver
    value, step count, and every later sample NaN, the measured driver value included;
    also when the records are converted in blocks of 4 (the failure in a later block)."""
    pb = pytest.importorskip("sim_models.engines.pybullet.driven")
    if block:
        monkeypatch.setattr(protocol, "RAW_BLOCK", block)
    s = pb.PybulletSettings(timestep=5e-3)
    ok, _ = both_runs("pybullet", "seed-four-bar", s)
    assert ok.ok
    by_time = np.argsort(ok.times)
    gaps = ok.loop_violation[by_time]
    k = len(gaps) // 2 + int(np.argmax(gaps[len(gaps) // 2:]))  # the largest gap late on
    assert gaps[:k].max() < gaps[k]
    size = compile_linkage(load_case("seed-four-bar")).size
    limit = 0.5 * (gaps[:k].max() + gaps[k]) / size
    deferred, each = both_runs("pybullet", "seed-four-bar", s, max_violation=limit)
    assert not deferred.ok and "loop violation" in deferred.reason
    assert_same(deferred, each)
    reached = np.isfinite(deferred.alpha[by_time]).all(axis=1)
    assert reached[:k].all() and not reached[k:].any()
    assert np.isfinite(deferred.measured_values[by_time][:k + 1]).all()
    assert np.isnan(deferred.measured_values[by_time][k + 1:]).all()
    assert deferred.steps < ok.steps


@pytest.mark.parametrize("engine, settings", [
    ("mujoco", {"integrator": "Euler", "timestep": 5e-3, "solref": "-1e8,-2e4"}),
    ("mujoco", {"armature": 1e-3}),
    ("pybullet", {"timestep": 2e-3}),
    ("pybullet", {"motor_force": 1.0}),
])
def test_divergences_match_per_sample(engine, settings):
    pytest.importorskip(engine)
    s = get_engine(engine).settings(settings)
    deferred, each = both_runs(engine, "seed-slider-crank", s)
    assert not deferred.ok
    assert_same(deferred, each)


def test_first_divergence_is_the_per_stop_check():
    """The vectorised check returns the first stop :func:`check_motion` fails at, with
    its message; a gap exactly at the limit passes (the limit is inclusive)."""
    tree = compile_linkage(load_case("seed-four-bar"))
    plan = plan_samples(tree, 2, 36)
    t = plan.times
    rate = np.asarray(tree.driver_path(t)[1], float).copy()
    vmax = 1e-3 * tree.size
    gap = np.full(len(t), 0.5 * vmax)
    assert first_divergence(tree, gap, rate, t, 1e-3, 1e-2) == (None, None)
    gap[3] = vmax                       # at the limit: passes
    gap[9] = vmax * (1 + 1e-12)         # just over: fails
    rate[12] *= 1.02                    # 2% off the prescribed rate
    k, why = first_divergence(tree, gap, rate, t, 1e-3, 1e-2)
    assert k == 9 and why.startswith("loop violation")
    assert why == check_motion(tree, gap[9], rate[9], t[9], 1e-3, 1e-2)
    gap[9] = 0.0
    k, why = first_divergence(tree, gap, rate, t, 1e-3, 1e-2)
    assert k == 12 and why.startswith("driver rate off by")
    gap[5] = math.nan
    assert first_divergence(tree, gap, rate, t, 1e-3, 1e-2)[0] == 5
