"""``xval tune --engine mujoco_warp``: the tuned settings of MuJoCo Warp (float32) meet
the tolerance in a fresh verdict run (``xval compare``'s run and comparison, not the
search's), and a tolerance below its float32 floor is no pass whose limit names the
arithmetic.  Skipped when ``mujoco_warp`` is not installed (``.ci/warp`` runs it)."""

from __future__ import annotations

import pytest

pytest.importorskip("mujoco_warp", reason="MuJoCo Warp is not installed: pip install "
                    "'linkage-xval[warp]'")

from analytic import load_case  # noqa: E402
from reports.comparison.quantities import judged  # noqa: E402
from reports.comparison.runs import run_verdict  # noqa: E402
from reports.tune import TuneCase, tune  # noqa: E402
from sim_models import compile_linkage  # noqa: E402

CASE = "seed-four-bar"
#: The verdict tolerance, 1e-3 of peak (Warp's recommended run: 4.0e-4, its tests).
TOL = 1e-3
#: Far below Warp's float32 floor on this case: measured, the worst error stops falling
#: with the step at 2.6e-4 of peak (288 -> 576 steps per revolution: 2.8e-4 -> 2.6e-4),
#: where the harness's float32 floor estimate is 4.4e-4.
BELOW_FLOAT32 = 1e-6


def test_warp_tuned_settings_meet_the_tolerance():
    res = tune(TuneCase(CASE), "mujoco_warp", TOL, budget=15, pool=False, knob_limit=1,
               verify=False)
    assert res.answer is not None, res.limit_text
    v = run_verdict(compile_linkage(load_case(CASE)), "mujoco_warp", res.settings)
    assert v.run.ok, v.run.reason
    assert max(c.normalised for c in judged(v.comparisons)) <= TOL
    assert res.answer.m.unit_steps <= res.recommended.m.unit_steps


def test_warp_below_its_float32_floor_is_no_pass_naming_it():
    res = tune(TuneCase(CASE), "mujoco_warp", BELOW_FLOAT32, budget=3, pool=False,
               knob_limit=0, verify=False)
    assert res.answer is None
    assert "float32" in res.limit_text, res.limit_text
