"""The one compile -> run -> compare (reports.comparison.runs.run_verdict): every door that
runs an engine and compares it goes through it with the request it was given, and its
:class:`Verdict` answers ok / near_event / judged as the comparison module decides them."""

from __future__ import annotations

import pytest

import reports.comparison.runs as vr
from analytic import load_case
from reports.comparison.compare import Comparison, verdict
from sim_models.runs.engine_run import RunRequest


class _Run:
    """The parts of an EngineRun the callers read."""

    ok = True
    reason = ""


def _comps():
    return (Comparison("rocker.alpha", 1e-6, 1.0, 1e-6, 10.0, 1e-3, True),
            Comparison("B.force[engine]", 1.0, 1.0, 1.0, 20.0, 1e-3, False))


@pytest.fixture
def calls(monkeypatch):
    """Replace run_verdict by a recorder: (linkage, engine, settings, request) per call."""
    seen = []

    def fake(linkage, engine, settings=None, request=None):
        seen.append((linkage, engine, settings, request))
        return vr.Verdict(linkage, _Run(), _comps())
    monkeypatch.setattr(vr, "run_verdict", fake)
    return seen


def test_every_caller_runs_through_run_verdict(calls, monkeypatch):
    from reports.regression import baseline_record
    from reports.regression.run_cache import RunCache
    mech = load_case("seed-four-bar")
    req = baseline_record.request_dict(3, 24, 2e-3, 3e-2, "moving")
    run_, comps = baseline_record.run_and_compare(mech, "mujoco", None, req)
    assert [c.quantity for c in comps] == ["rocker.alpha"]  # judged only
    entry = RunCache().make_run(mech, "pybullet", None, req)
    assert [c.quantity for c in entry["comparisons"]] == ["rocker.alpha", "B.force[engine]"]
    r, comps = vr.run_comparison("TREE", "exudyn", None, "instantaneous", 1, 5)
    assert len(comps) == 2
    assert [c[1] for c in calls] == ["mujoco", "pybullet", "exudyn"]
    assert calls[0][3] == calls[1][3] == RunRequest(3, 24, 2e-3, 3e-2, "moving", "run")
    assert calls[2][3] == RunRequest(1, 5, mode="instantaneous")


def test_request_of_takes_the_defaults_of_run_request():
    assert vr.request_of({}) == RunRequest()
    assert vr.request_of({"samples": 12, "unknown": 1}) == RunRequest(samples=12)


def test_verdict_is_the_comparison_verdict():
    comps = _comps()
    v = vr.Verdict(None, _Run(), comps)
    assert v.ok is verdict(list(comps)) is True  # the [engine] row's failure is not judged
    assert v.near_event is None  # a pass has no event to point at
    assert [c.quantity for c in v.judged()] == ["rocker.alpha"]
    failed = type("Failed", (_Run,), {"ok": False, "reason": "diverged"})()
    assert not vr.Verdict(None, failed, comps).ok


def test_near_a_limit_is_one_decision():
    """A condition number above 100, or NaN (a singular sample), is near a limit: where a
    limited-range run stops and what the verdict leaves out (the same predicate)."""
    import numpy as np

    from reports.comparison.reference import MAX_CONDITION
    from sim_models.runs.sampling import LIMITED_RANGE_CONDITION, near_limit
    assert MAX_CONDITION == LIMITED_RANGE_CONDITION == 100.0
    np.testing.assert_array_equal(near_limit([1.0, 99.9, 100.0, 100.1, np.inf, np.nan]),
                                  [False, False, False, True, True, True])


def _crash(*_a, **_k):
    raise IndexError("too many indices for array: array is 1-dimensional, but 2 were "
                     "indexed")


def test_one_engines_crash_is_its_failed_verdict_and_the_others_run(monkeypatch):
    """turn4/warp-rocker-load.toml with ``--engine all``: MuJoCo Warp's IndexError ended
    the whole command in a traceback, no engine's verdict printed.  Now the crashed
    engine is a failed verdict whose run names the exception in one line, and every
    other engine's verdict is printed; the exit status is that of a failed verdict."""
    from sim_models.engines.pybullet.driven import PybulletSession

    from .cli_run import run as xval
    monkeypatch.setattr(PybulletSession, "advance", _crash)
    monkeypatch.setattr("reports.cli.compare.engine_list",
                        lambda *_a: ["pybullet", "mujoco"])
    code, out = xval("compare", "seed-four-bar", "--engine", "all", "--revolutions", "1")
    assert code == 1
    assert "== seed-four-bar / mujoco (run) : PASS" in out
    assert "== seed-four-bar / pybullet (run) : FAIL" in out
    line = next(ln for ln in out.splitlines() if ln.startswith("run failed:"))
    assert "engine crashed: IndexError: too many indices" in line


def test_a_lone_engines_crash_is_one_line_and_status_1(monkeypatch):
    from sim_models.engines.mujoco.driven import MujocoSession

    from .cli_run import run as xval
    monkeypatch.setattr(MujocoSession, "advance", _crash)
    code, out = xval("compare", "seed-four-bar", "--engine", "mujoco", "--json")
    assert code == 1
    import json
    (v,) = json.loads(out)
    assert v["verdict"] == "fail" and not v["run_ok"]
    assert v["reason"].startswith("engine crashed: IndexError: too many indices")
