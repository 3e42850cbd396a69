"""Free-motion baselines (``xval baseline record --free``, ``check``, the pytest plugin's
cycle): what a record holds, a check that passes unchanged and fails when a recorded
value is tightened (error, energy drift, loop drift, trusted horizon, tolerance), and
one line with status 2 for every bad field of the file or the command line.

Independent expectations: each failing check follows from a number this file writes
into the record (an error divided by 1000 must read as a 1000x growth beyond the factor
10; a horizon moved 0.1 s later than measured, ten sample intervals, must be lost
earlier than recorded); runs go through the pytest plugin's session cache.
"""

from __future__ import annotations

import copy
import json
import math
import re

import pytest

from reports.cli.xval import main
from reports.regression import baseline_check as bc
from reports.regression import baseline_record as br
from reports.regression import baseline_settings as bset
from reports.regression import baseline_store as bs
from reports.regression.baseline_free import free_request
from reports.regression.run_cache import cached_runner
from tests.reports.test_bad_inputs import assert_one_line_error

#: The recorded runs: A01 in MuJoCo (within every tolerance; no loop) and the released
#: seed four-bar in PyBullet (its first-order step loses the trajectory at ~0.85 s).
DURATION, SAMPLES = 1.0, 51


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    path = tmp_path_factory.mktemp("free-baseline") / "free.json"
    req = free_request(DURATION, SAMPLES)
    a = br.record(["iftomm-a01-pendulum"], ["mujoco"], path, request=req,
                  runner=cached_runner)
    b = br.record(["seed-four-bar"], ["pybullet"], path, request=req, runner=cached_runner)
    assert not br.record_problems(a) and not br.record_problems(b)
    base, _ = br.merge(a, b)
    bs.save(base)
    return path


def _doc(path):
    return json.loads(path.read_text())


def _run(doc, engine):
    return next(r for r in doc["runs"] if r["engine"] == engine)


def _q(run, name):
    return next(q for q in run["quantities"] if q["quantity"] == name)


def _check(tmp_path, doc):
    p = tmp_path / "b.json"
    p.write_text(json.dumps(doc))
    return {c.record.engine: c for c in bc.check(bs.load(p), runner=cached_runner)}


def test_record_holds_errors_horizons_and_drifts(recorded):
    doc = _doc(recorded)
    a01, seed = _run(doc, "mujoco"), _run(doc, "pybullet")
    assert a01["request"] == {"mode": "free", "duration": 1.0, "samples": 51}
    assert a01["settings"]["class"] == "MujocoFreeSettings"
    names = {q["quantity"] for q in a01["quantities"]}
    assert "energy" in names and "loop.gap" not in names      # a pendulum has no loop
    assert {"energy", "loop.gap", "O4.x"} <= {q["quantity"] for q in seed["quantities"]}
    assert all(q["horizon_s"] is None for q in a01["quantities"])   # never exceeded
    assert all(q["at_unit"] == "s" for q in a01["quantities"])
    h = _q(seed, "O4.x")["horizon_s"]
    assert 0.5 < h < 1.0 and _q(seed, "O4.x")["error"] > _q(seed, "O4.x")["tolerance"]
    cmd = br.record_command(bs.load(recorded))
    assert "--free --duration 1 --samples 51" in cmd and "--engine pybullet" in cmd


def test_check_passes_unchanged(tmp_path, recorded):
    checks = _check(tmp_path, _doc(recorded))
    assert all(c.passed for c in checks.values()), [c.failures() for c in checks.values()]


def test_check_fails_when_an_error_is_tightened(tmp_path, recorded):
    doc = _doc(recorded)
    q = _q(_run(doc, "pybullet"), "O4.x")
    q["error"] /= 1000
    bad = _check(tmp_path, doc)["pybullet"]
    assert not bad.passed and bad.failures()[0].quantity == "O4.x"
    assert bad.failures()[0].status == "drift" and "of range" in bad.failures()[0].message()


def test_check_fails_when_the_energy_drift_is_tightened(tmp_path, recorded):
    doc = _doc(recorded)
    q = _q(_run(doc, "pybullet"), "energy")
    assert q["error"] > 1e-5   # 1000x smaller stays above the drift floor's reach
    q["error"] = q["error"] / 1000
    bad = _check(tmp_path, doc)["pybullet"]
    assert [(f.quantity, f.status) for f in bad.failures()] == [("energy", "drift")]


def test_check_fails_when_the_loop_drift_is_tightened(tmp_path, recorded):
    """PyBullet's loop gap (~8e-7 of the size) lies under the drift floor's reach
    (10 x 1e-7), so its tolerance is what a tightened record can fail."""
    doc = _doc(recorded)
    q = _q(_run(doc, "pybullet"), "loop.gap")
    q["tolerance"] = q["error"] / 2
    bad = _check(tmp_path, doc)["pybullet"]
    assert [(f.quantity, f.status) for f in bad.failures()] == [("loop.gap",
                                                                  "over-tolerance")]


def test_check_fails_when_the_horizon_is_tightened(tmp_path, recorded):
    doc = _doc(recorded)
    q = _q(_run(doc, "pybullet"), "O4.x")
    q["horizon_s"] += 0.1     # ten sample intervals later than measured
    bad = _check(tmp_path, doc)["pybullet"]
    f = bad.failures()
    assert [x.quantity for x in f] == ["O4.x"] and f[0].status == "horizon"
    assert re.search(r"trusted horizon 0\.9\d* s -> 0\.8\d* s, earlier by more than one "
                     r"sample interval \(0\.02 s", f[0].message()), f[0].message()
    q["horizon_s"] -= 0.1 - 0.01   # within one interval of what is measured: no change
    assert _check(tmp_path, doc)["pybullet"].passed


def test_check_fails_when_a_tolerance_is_tightened(tmp_path, recorded):
    """A quantity recorded within its tolerance must stay within it."""
    doc = _doc(recorded)
    q = _q(_run(doc, "mujoco"), "energy")
    q["tolerance"] = q["error"] / 2 if q["error"] > 0 else 1e-15
    bad = _check(tmp_path, doc)["mujoco"]
    assert [(x.quantity, x.status) for x in bad.failures()] == [("energy", "over-tolerance")]


def test_command_line_check_passes_then_fails_tightened(tmp_path, recorded, capsys):
    doc = _doc(recorded)
    doc["runs"] = [_run(doc, "mujoco")]
    p = tmp_path / "a01.json"
    p.write_text(json.dumps(doc))
    assert main(["baseline", "check", str(p)]) == 0
    out = capsys.readouterr().out
    assert "pass  iftomm-a01-pendulum / mujoco (free, 1 s)" in out
    assert "trusted horizon whole run (recorded whole run)" in out
    _q(doc["runs"][0], "O.x")["error"] = 1e-12 if _q(doc["runs"][0], "O.x")["error"] > 1e-10 \
        else _q(doc["runs"][0], "O.x")["error"]
    _q(doc["runs"][0], "energy")["tolerance"] = 1e-15  # the least accepted (MIN_TOLERANCE)
    p.write_text(json.dumps(doc))
    assert main(["baseline", "check", str(p)]) == 1
    out = capsys.readouterr().out
    assert "FAIL  iftomm-a01-pendulum / mujoco (free, 1 s): energy: error" in out
    assert "--free --duration 1 --samples 51" in out   # how to record it again


def test_check_set_takes_the_free_settings(tmp_path, recorded, capsys):
    """``check --set`` of a free-only baseline is checked against the free-motion
    settings class (PyBullet's ``first_step`` is a free-motion setting only), with the
    same ranges as ``xval simulate --set``."""
    doc = _doc(recorded)
    doc["runs"] = [_run(doc, "mujoco")]
    p = tmp_path / "a01.json"
    p.write_text(json.dumps(doc))
    assert_one_line_error(capsys, ["baseline", "check", str(p), "--set",
                                   "mujoco.timestep=1"],
                          r"engine 'mujoco' setting timestep=1: 1 is out of range")
    assert_one_line_error(capsys, ["baseline", "check", str(p), "--set",
                                   "mujoco.armature=1"],
                          r"no engine here has a setting 'armature'")
    classes = bset.override_classes(bs.load(recorded))
    assert classes["pybullet"].__name__ == "PybulletFreeSettings"
    assert bset.overrides_for(["pybullet.first_step=1e-5"], ["pybullet"], classes) == {
        "pybullet": {"first_step": "1e-5"}}


def test_pytest_plugin_cycle(tmp_path, recorded, xval):
    """The plugin's assert_baseline judges free runs with the same check."""
    xval.assert_baseline(recorded)
    doc = _doc(recorded)
    _q(_run(doc, "pybullet"), "O4.x")["horizon_s"] += 0.1
    p = tmp_path / "tight.json"
    p.write_text(json.dumps(doc))
    with pytest.raises(AssertionError, match=r"O4\.x: trusted horizon"):
        xval.assert_baseline(p)


# ================================================================= bad input: status 2
def _set(path, value):
    """An edit of the first run: ``path`` a tuple of keys into it."""
    def f(run):
        d = run
        for k in path[:-1]:
            d = d[k]
        if value is _DEL:
            d.pop(path[-1])
        else:
            d[path[-1]] = value
    return f


_DEL = object()
_RUN = r"runs\[0\] \(iftomm-a01-pendulum / mujoco\)"

BAD = {
    "duration-zero": (_set(("request", "duration"), 0.0),
                      r"request duration=0\.0: 0 is out of range: the accepted range is "
                      r"1e-06 to 10000 s \(the range of --duration\)"),
    "duration-huge": (_set(("request", "duration"), 1e5), r"request duration=100000\.0"),
    "duration-text": (_set(("request", "duration"), "1"), r"request duration=\"1\""),
    "duration-true": (_set(("request", "duration"), True), r"request duration=true"),
    "duration-missing": (_set(("request", "duration"), _DEL),
                         r"request duration: missing key"),
    "samples-one": (_set(("request", "samples"), 1),
                    r"request samples=1: 1 is out of range: the accepted range is 2 to "
                    r"10001 \(.*the range of --samples with an engine\)"),
    "samples-float": (_set(("request", "samples"), 50.5), r"request samples=50\.5"),
    "samples-huge": (_set(("request", "samples"), 10 ** 7), r"request samples=10000000"),
    "request-extra-key": (_set(("request", "revolutions"), 2),
                          r"request revolutions=2: is not a free-motion request key"),
    "mode-unknown": (_set(("request", "mode"), "drift"),
                     r"request mode 'drift': only 'run' \(prescribed\) and 'free'"),
    "timestep-out-of-range": (_set(("settings", "fields", "timestep"), 10.0),
                              r"settings field timestep=10\.0: .*out of range"),
    "timestep-text": (_set(("settings", "fields", "timestep"), "5e-4"),
                      r"settings field timestep=\"5e-4\": must be a number"),
    "setting-missing": (_set(("settings", "fields", "solref"), _DEL),
                        r"settings field 'solref' is missing"),
    "setting-unknown": (_set(("settings", "fields", "armature"), 1.0),
                        r"settings field 'armature': mujoco has no setting 'armature'"),
    "settings-prescribed-class": (_set(("settings", "class"), "MujocoSettings"),
                                  r"settings class 'MujocoSettings' is not mujoco's "
                                  r"\(MujocoFreeSettings\)"),
    "integrator-unknown": (_set(("settings", "fields", "integrator"), "Verlet"),
                           r"settings field integrator=\"Verlet\""),
    "quantities-empty": (_set(("quantities",), []), r"'quantities' is empty: a run with no "
                                                    r"recorded quantity judges nothing"),
}


def _horizon_edit(value):
    def f(run):
        if value is _DEL:
            run["quantities"][0].pop("horizon_s")
        else:
            run["quantities"][0]["horizon_s"] = value
    return f


BAD.update({
    "horizon-missing": (_horizon_edit(_DEL), r"quantity '[^']+': missing key 'horizon_s'"),
    "horizon-negative": (_horizon_edit(-1.0),
                         r"quantity '[^']+': 'horizon_s' must be a time >= 0 s or null "
                         r"\(never exceeded\), got -1\.0"),
    "horizon-text": (_horizon_edit("later"), r"'horizon_s' must be a time >= 0 s"),
})


@pytest.fixture
def no_free_run(monkeypatch):
    import reports.regression.baseline_free as bf

    def ran(*a, **k):
        pytest.fail("a free run started for an unusable baseline")
    monkeypatch.setattr(bf, "run_and_compare_free", ran)


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_free_baseline_one_line_status_2(tmp_path, capsys, recorded, no_free_run, name):
    edit, message = BAD[name]
    doc = _doc(recorded)
    doc["runs"] = [copy.deepcopy(_run(doc, "mujoco"))]
    edit(doc["runs"][0])
    p = tmp_path / f"{name}.json"
    p.write_text(json.dumps(doc))
    assert_one_line_error(capsys, ["baseline", "check", str(p)],
                          re.escape(str(p)) + ": " + _RUN + ": .*" + message)


def test_a_baseline_with_no_runs_judges_nothing(tmp_path, capsys, recorded):
    doc = _doc(recorded)
    doc["runs"] = []
    p = tmp_path / "empty.json"
    p.write_text(json.dumps(doc))
    assert_one_line_error(capsys, ["baseline", "check", str(p)], r"'runs' is empty")


@pytest.mark.parametrize("argv, message", [
    (["seed-four-bar", "--free", "--revolutions", "2"], r"--revolutions does not apply to "
                                                        r"--free"),
    (["seed-four-bar", "--free", "--tolerance", "0.1"], r"--tolerance does not apply"),
    (["seed-four-bar", "--duration", "1"], r"--duration needs --free"),
    (["seed-four-bar", "--free", "--duration", "0"], r"argument --duration: 0 is out of "
                                                     r"range"),
    (["seed-four-bar", "--free", "--samples", "1"], r"argument --samples: 1 is out of range"),
    (["seed-four-bar", "--samples", "5000"], r"argument --samples: 5000 is out of range"),
    (["hibbeler-16-121", "--free"], r"case 'hibbeler-16-121' cannot be released under "
                                    r"gravity: no moving body has mass"),
])
def test_bad_free_record_options(tmp_path, capsys, argv, message, no_free_run):
    out = tmp_path / "b.json"
    assert_one_line_error(capsys, ["baseline", "record", *argv, "--engine", "mujoco",
                                   "--out", str(out)], message)
    assert not out.exists()


def test_record_refuses_a_file_without_motion(tmp_path, capsys, no_free_run):
    from tests.reports.free_inputs import seed_under_gravity
    f = tmp_path / "driven.toml"
    f.write_text(seed_under_gravity())
    assert_one_line_error(capsys, ["baseline", "record", str(f), "--free", "--engine",
                                   "mujoco", "--out", str(tmp_path / "b.json")],
                          r"no \[motion\] table")


def test_record_refuses_a_run_that_stopped(tmp_path):
    """A run that stopped judges nothing after it stopped: not recorded."""
    req = free_request(0.5, 11)

    def stopped(mech, engine, settings, request):
        run, comps = cached_runner(mech, engine, settings, request)
        return type("R", (), {"ok": False, "t_fail": 0.25, "reason": "NaN state",
                              "case": run.case})(), comps
    base = br.record(["iftomm-a01-pendulum"], ["mujoco"], tmp_path / "b.json",
                     request=req, runner=stopped)
    assert br.record_problems(base) == ["iftomm-a01-pendulum / mujoco (free, 0.5 s): the "
                                        "run stopped at t = 0.25 s: NaN state"]
    assert math.isfinite(base.runs[0].quantities[0].error)
