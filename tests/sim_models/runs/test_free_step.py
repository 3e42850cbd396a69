"""The free-motion step chosen from the motion (issue 30, "engines on any description"):
where the exact trajectory's fastest body turns further in one recommended step than
:data:`MAX_TURN_PER_STEP`, the step is shortened to meet it; a slow release keeps the
recommended step exactly; a step the user sets always wins."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest

from analytic.free_motion import simulate
from reports.comparison.free_cases import free_case, release_and_judge
from reports.comparison.free_limits import verdict_of_free
from sim_models.runs.free import free_settings
from sim_models.runs.free_step import MAX_TURN_PER_STEP, choose_step
from tests.reports.cli_run import run as xval

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def _spinning(rate: float, duration: float = 1.0):
    """A stand-in reference: one body turning at ``rate`` rad/s throughout."""
    bodies = (SimpleNamespace(name="ground"), SimpleNamespace(name="wheel"))
    return SimpleNamespace(
        duration=duration, mech=SimpleNamespace(bodies=bodies),
        segments=[SimpleNamespace(ts=np.linspace(0, duration, 7))],
        at=lambda t, forces=False: SimpleNamespace(
            omega=np.column_stack([np.zeros(len(t)), np.full(len(t), rate)])))


def test_choose_step_caps_the_turn_per_step_and_counts_the_sample_interval():
    times = np.linspace(0, 1, 11)                       # 0.1 s sample intervals
    c = choose_step(_spinning(100.0), times, 2e-3)      # 0.2 rad a step > the cap
    assert c is not None and c.body == "wheel" and c.recommended == 2e-3
    assert c.chosen == pytest.approx(MAX_TURN_PER_STEP / 100.0, rel=1e-12)
    assert "chosen from the motion" in c.text and "0.2 rad a step" in c.text
    assert choose_step(_spinning(100.0), times, 1e-3) is None       # 0.1 rad: kept
    # samples 1 ms apart: the run steps at most 1 ms (0.1 rad), so nothing to shorten
    assert choose_step(_spinning(100.0), np.linspace(0, 1, 1001), 2e-3) is None


def _fd_peak_rate(traj, t0: float) -> float:
    """The largest body rate near ``t0`` from central differences of the body angles
    (positions only: independent of the solver's rates)."""
    t = np.linspace(max(0.0, t0 - 5e-3), min(traj.duration, t0 + 5e-3), 2001)
    th = traj.at(t, forces=False).theta
    return float(np.max(np.abs(np.diff(th, axis=0) / np.diff(t)[:, None])))


def test_quick_return_in_pinocchio_runs_at_the_step_chosen_from_the_motion():
    """Before: Pinocchio stepped the released quick-return at its recommended 1e-3 s
    (a body turning 0.229 rad a step) and stopped at 0.385 s by its loop gap.  Now the
    step turns the fastest body (229 rad/s, checked by differences of its angle) by
    the cap, the run completes, and its verdict is the listed known limit."""
    pytest.importorskip("pinocchio")  # the optional engine these runs use
    mech = free_case("quick-return", 2.0)
    run, v = release_and_judge(mech, "pinocchio", 2.0, 400)
    c = run.step_choice
    assert c is not None and c.recommended == free_settings("pinocchio").timestep
    assert _fd_peak_rate(simulate(mech, duration=2.0), c.at) == pytest.approx(
        c.peak_rate, rel=2e-3)
    assert c.peak_rate * c.recommended > MAX_TURN_PER_STEP
    assert run.timestep * c.peak_rate <= MAX_TURN_PER_STEP * (1 + 1e-9)
    assert run.ok, run.reason
    assert "chosen from the motion" in v.settings and "MAX_TURN_PER_STEP" in v.settings
    assert verdict_of_free(v)[0] == "known limit"


def test_slow_release_keeps_the_recommended_step_exactly():
    """The seed four-bar released (31.5 rad/s: 0.03 rad a step at 1e-3 s)."""
    pytest.importorskip("pinocchio")  # the optional engine these runs use
    run, v = release_and_judge(free_case("seed-four-bar", 1.0), "pinocchio", 1.0, 100)
    assert run.step_choice is None
    assert run.settings == free_settings("pinocchio") and run.settings.timestep == 1e-3
    assert run.timestep == pytest.approx(1e-3, rel=1e-12)   # 10 steps a 10 ms interval
    assert "chosen from the motion" not in v.settings


def test_a_step_the_user_sets_wins():
    """--timestep (and --set) is run as given: the quick-return at Pinocchio's 1e-3 s
    stops again by its loop gap, the settings line says nothing of the motion."""
    pytest.importorskip("pinocchio")  # the optional engine these runs use
    base = ("simulate", "quick-return", "--engine", "pinocchio", "--samples", "101",
            "--json")
    for extra in (("--timestep", "1e-3"), ("--set", "pinocchio.timestep=1e-3")):
        code, text = xval(*base, *extra)
        v = json.loads(text)["verdicts"][0]
        assert code == 1 and v["timestep"] == pytest.approx(1e-3, rel=1e-12), extra
        assert not v["run_ok"] and "loop gap" in v["reason"], extra
        assert "chosen from the motion" not in v["settings"], extra
    code, text = xval(*base)
    v = json.loads(text)["verdicts"][0]
    assert v["run_ok"] and "chosen from the motion" in v["settings"]
    assert v["timestep"] * 228.0 < MAX_TURN_PER_STEP
