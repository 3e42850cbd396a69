"""Baselines (issue 13): record, check, drift, disappearance, bad files, JUnit and Markdown.

Independent expectations: the drift verdicts follow from numbers this file writes into
the baseline (an error divided by 100 must read as a 100x growth; a tolerance set below
the recorded error must be exceeded); the JUnit documents are validated against a schema
written from the format's own description (``junit.xsd`` beside this file) and their
counts against the cases run.  Runs go through the session cache of the pytest plugin
(:func:`reports.regression.run_cache.cached_runner`), shared with the engine tests and the
committed-baseline check, so most cost nothing extra; the command-line checks re-run.
"""

from __future__ import annotations

import json
import math
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from analytic.cases import case_names, case_path
from reports.cli.xval import main
from reports.regression import baseline as bl
from reports.regression import baseline_check as bc
from reports.regression import baseline_record as br
from reports.regression import baseline_settings as bset
from reports.regression import baseline_store as bs
from reports.regression.pytest_plugin import baseline_params
from reports.regression.run_cache import cached_runner

ROOT = Path(__file__).resolve().parents[2]
BUILTIN = ROOT / "tests" / "baselines" / "builtin.json"
XSD = Path(__file__).with_name("junit.xsd")
RE_RECORD = ("xval baseline record all --engine exudyn --engine mujoco --engine pybullet "
             "--samples 24 --out tests/baselines/builtin.json")


# ============================================================== the committed baseline
@pytest.mark.parametrize("case, engine", baseline_params(BUILTIN))
def test_builtin_baseline(xval, case, engine):
    """The built-in cases at the recommended settings have not drifted tenfold, exceeded
    their tolerance, or lost a quantity since tests/baselines/builtin.json was recorded.
    An intended change (a new engine version, a better model) is re-recorded with the
    command the failure message ends with (RE_RECORD)."""
    xval.assert_baseline(BUILTIN, case=case, engine=engine)


def test_builtin_baseline_names_its_re_record_command():
    assert br.record_command(bs.load(BUILTIN), ROOT) == RE_RECORD


def test_builtin_baseline_covers_every_case_and_engine():
    from sim_models.engines.registry import engine_names
    base = bs.load(BUILTIN)
    assert {(r.case, r.engine) for r in base.runs} >= \
        {(c, e) for c in case_names() for e in ("mujoco", "pybullet")}
    assert {r.engine for r in base.runs} <= set(engine_names())
    from sim_models.engines.registry import get_engine
    for r in base.runs:
        # recorded at the recommended settings: every recorded field is still the engine's
        # default (a field added since is run at its default, and the check notes it)
        now = bset.settings_json(r.engine, get_engine(r.engine).settings())["fields"]
        changed = {k: (v, now[k]) for k, v in r.settings["fields"].items()
                   if k in now and now[k] != v}
        assert not changed, f"{r.label}: recommended settings changed since the baseline " \
                            f"(recorded, now): {changed}; re-record: {RE_RECORD}"


# ============================================================== record, then check
@pytest.fixture(scope="module")
def mujoco_baseline(tmp_path_factory):
    """Every built-in case in MuJoCo, recorded through the session cache (the runs of
    the committed-baseline check and the engine tests: same request and settings)."""
    out = tmp_path_factory.mktemp("baseline") / "mujoco.json"
    base = br.record(case_names(), ["mujoco"], out, request=br.request_dict(samples=24),
                     runner=cached_runner)
    assert not br.record_problems(base)
    bs.save(base)
    return out


def _edited(src: Path, dst: Path, edit) -> Path:
    doc = json.loads(src.read_text())
    edit(doc)
    dst.write_text(json.dumps(doc, indent=2, sort_keys=True))
    return dst


def _run(doc, case, engine="mujoco"):
    return next(r for r in doc["runs"] if r["case"] == case and r["engine"] == engine)


def _worst(run):
    return max(run["quantities"], key=lambda q: q["error"])


def test_record_then_check_passes_on_rerun(mujoco_baseline, tmp_path, capsys):
    """Recorded on every built-in case, then checked by the command line (real re-runs):
    status 0, every run 'pass', nothing grown."""
    doc = json.loads(mujoco_baseline.read_text())
    assert doc["schema"] == bl.SCHEMA and doc["schema_version"] == bl.SCHEMA_VERSION
    assert {r["case"] for r in doc["runs"]} == set(case_names())
    junit, summary = tmp_path / "j.xml", tmp_path / "s.md"
    code = main(["baseline", "check", str(mujoco_baseline), "--junit", str(junit),
                 "--summary", str(summary)])
    out = capsys.readouterr().out
    assert code == 0, out
    assert out.count("pass  ") == len(case_names()) and "result: PASS" in out
    assert "FAIL" not in out
    _validate_junit(junit, tests=len(case_names()), failures=0)
    assert "PASS (10 of 10 passed)" in summary.read_text()


def test_an_error_divided_by_100_fails_naming_quantity_and_factor(mujoco_baseline, tmp_path,
                                                                   capsys):
    """The must-show: one recorded error divided by 100 reads as a 100x growth, above the
    factor 10: status 1, the message names the quantity, the growth and the factor."""
    picked = {}

    def edit(doc):
        run = _run(doc, "quick-return")
        q = _worst(run)
        assert q["error"] > bl.DEFAULT_FACTOR * bl.DRIFT_FLOOR  # drift is measurable
        picked.update(q)
        q["error"] /= 100
    edited = _edited(mujoco_baseline, tmp_path / "edited.json", edit)
    junit, summary = tmp_path / "j.xml", tmp_path / "s.md"
    code = main(["baseline", "check", str(edited), "--case", "quick-return", "--case",
                 "seed-four-bar", "--junit", str(junit), "--summary", str(summary)])
    out = capsys.readouterr().out
    assert code == 1, out
    line = next(ln for ln in out.splitlines() if ln.startswith("FAIL"))
    assert line.startswith(f"FAIL  quick-return / mujoco: {picked['quantity']}: drifted ")
    assert "(100x)" in line and "more than the factor 10" in line, line
    assert "pass  seed-four-bar / mujoco" in out and "1 of 2 runs failed" in out
    _validate_junit(junit, tests=2, failures=1)
    failure = ET.parse(junit).getroot().find(".//failure")
    assert failure.get("type") == "drift" and picked["quantity"] in failure.get("message")
    md = summary.read_text()
    assert "**FAIL**" in md and f"`{picked['quantity']}`" in md and "100x" in md


def test_a_large_improvement_says_the_baseline_is_loose(mujoco_baseline, tmp_path, capsys):
    """A recorded error 100x the current one (the baseline no longer guards it): a
    warning line and status 0 by default; status 1 with --fail-loose."""
    picked = {}

    def edit(doc):
        q = _worst(_run(doc, "quick-return"))
        assert q["error"] > bl.DEFAULT_FACTOR * bl.DRIFT_FLOOR and q["error"] * 100 < 1e-3
        picked.update(q)
        q["error"] *= 100
    edited = _edited(mujoco_baseline, tmp_path / "loose.json", edit)
    args = ["baseline", "check", str(edited), "--case", "quick-return"]
    assert main(args) == 0
    out = capsys.readouterr().out
    [warn] = [ln for ln in out.splitlines() if ln.startswith("warning: ")]
    assert warn.startswith(f"warning: quick-return / mujoco: {picked['quantity']}: improved ")
    assert "(0.01x), more than the factor 10: the baseline is loose; re-record" in warn, warn
    assert main([*args, "--fail-loose"]) == 1
    out = capsys.readouterr().out
    assert f"FAIL  quick-return / mujoco: {picked['quantity']}: improved " in out
    # an improvement within the factor, or one below the floor, is not loose
    rec = bl.QuantityRecord("x.alpha", 9e-7, 0.0, "deg", 1e-3, 0.0, 1.0)
    assert bc.judge(rec, 1e-9, 0.0, bl.DEFAULT_FACTOR).status == "ok"
    rec = bl.QuantityRecord("x.alpha", 2e-5, 0.0, "deg", 1e-3, 0.0, 1.0)
    assert bc.judge(rec, 3e-6, 0.0, bl.DEFAULT_FACTOR).status == "ok"
    assert bc.judge(rec, 1.9e-6, 0.0, bl.DEFAULT_FACTOR).status == "improved"
    assert bc.judge(rec, 1.9e-6, 0.0, bl.DEFAULT_FACTOR, fail_loose=True).failed


def test_check_under_other_settings_names_them(mujoco_baseline, tmp_path, capsys):
    """``--set`` runs the recorded runs with another setting; the output says which, and
    the run's settings line shows it; an unknown key is one line, status 2."""
    junit = tmp_path / "s.xml"
    code = main(["baseline", "check", str(mujoco_baseline), "--case", "seed-four-bar",
                 "--set", "mujoco.timestep=0.0002", "--junit", str(junit)])
    out = capsys.readouterr().out
    assert code in (0, 1), out
    assert "settings changed for this check (--set): mujoco.timestep=0.0002" in \
        out.splitlines()[2], out
    props = {p.get("name"): p.get("value") for p in ET.parse(junit).getroot().iter("property")}
    assert props["set.mujoco.timestep"] == "0.0002"
    assert "timestep=0.0002" in ET.parse(junit).getroot().find(".//system-out").text
    assert main(["baseline", "check", str(mujoco_baseline), "--set", "no_such=1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("xval: error: ") and "no_such" in err and "\n" not in err


def test_the_floor_keeps_round_off_from_tripping(mujoco_baseline):
    """An error below the floor divided by 100 is not drift (1e-8 -> 1e-10 is round-off
    territory: the limit is factor x floor); the same error set to 0 is not either."""
    base = bs.load(mujoco_baseline)
    run = next(r for r in base.runs if r.case == "seed-four-bar")
    small = [q for q in run.quantities if 0 < q.error < bl.DRIFT_FLOOR]
    assert small
    for q in small:
        for recorded in (q.error / 100, 0.0):
            rec = bl.QuantityRecord(q.quantity, recorded, q.at, q.at_unit, q.tolerance,
                                    q.max_abs, q.peak)
            assert bc.judge(rec, q.error, q.at, bl.DEFAULT_FACTOR).status == "ok"
    # just above the limit it is drift, and the message states the floor
    rec = bl.QuantityRecord("x.alpha", 1e-12, 0.0, "deg", 1e-3, 0.0, 1.0)
    v = bc.judge(rec, 1.01 * bl.DEFAULT_FACTOR * bl.DRIFT_FLOOR, 30.0, bl.DEFAULT_FACTOR)
    assert v.status == "drift" and "below the floor 1e-07" in v.message()


def test_over_tolerance_missing_quantity_and_missing_case_fail(mujoco_baseline, tmp_path):
    def edit(doc):
        q = _worst(_run(doc, "seed-four-bar"))
        q["tolerance"] = q["error"] / 2           # now above its tolerance
        _run(doc, "six-bar")["quantities"].append(
            {"quantity": "ghost.alpha", "error": 1e-8, "tolerance": 1e-3, "at": 0.0,
             "at_unit": "deg", "max_abs": 0.0, "peak": 1.0})
        gone = _run(doc, "quick-return")
        gone["model"] = {"builtin": "no-such-case", "sha256": "0" * 64}
    base = bs.load(_edited(mujoco_baseline, tmp_path / "e.json", edit))
    checks = {c.record.case: c for c in bc.check(base, runner=cached_runner)}
    four = checks["seed-four-bar"]
    assert not four.passed and four.failures()[0].status == "over-tolerance"
    assert "exceeds its tolerance" in four.failures()[0].message()
    six = checks["six-bar"]
    assert [q.quantity for q in six.failures()] == ["ghost.alpha"]
    assert "no longer compared" in six.failures()[0].message()
    assert not checks["quick-return"].passed
    assert "'no-such-case' no longer exists" in checks["quick-return"].problems[0]
    assert sum(not c.passed for c in checks.values()) == 3
    # in JUnit: two failures (tolerance, missing quantity) and one error (case gone)
    from reports.regression.ci_formats import from_baseline, junit_xml
    junit = tmp_path / "j.xml"
    junit.write_text(junit_xml("check", from_baseline(list(checks.values()))))
    _validate_junit(junit, tests=len(checks), failures=2, errors=1)
    kinds = {c.get("name"): (c[0].tag, c[0].get("type")) for c in
             ET.parse(junit).getroot().iter("testcase") if len(c) and c[0].tag != "system-out"}
    assert kinds == {"seed-four-bar": ("failure", "tolerance"),
                     "six-bar": ("failure", "missing"), "quick-return": ("error", "gone")}


def test_a_model_file_is_stored_relative_and_a_change_is_detected(tmp_path):
    """A TOML model is stored by its path relative to the baseline file (the folder can
    move) with its SHA-256; editing the file fails the check and says so."""
    proj = tmp_path / "proj"
    (proj / "linkages").mkdir(parents=True)
    model = proj / "linkages" / "four.toml"
    shutil.copy(case_path("seed-four-bar"), model)
    out = proj / "ci" / "baseline.json"
    out.parent.mkdir()
    base = br.record([str(model)], ["mujoco"], out, request=br.request_dict(samples=12),
                     runner=cached_runner)
    bs.save(base)
    doc = json.loads(out.read_text())
    assert doc["runs"][0]["model"]["file"] == "../linkages/four.toml"
    moved = tmp_path / "moved"
    shutil.copytree(proj, moved)
    assert all(c.passed for c in bc.check(bs.load(moved / "ci" / "baseline.json"),
                                          runner=cached_runner))
    text = model.read_text()
    model.write_text(text.replace("mass = 0.6", "mass = 0.61", 1))
    assert text != model.read_text()
    (chk,) = bc.check(bs.load(out), runner=cached_runner)
    assert not chk.passed and "changed since the baseline" in chk.problems[0]
    model.unlink()
    (chk,) = bc.check(bs.load(out), runner=cached_runner)
    assert not chk.passed and "is gone" in chk.problems[0]


def test_model_identity_is_the_parsed_mechanism_not_the_bytes(tmp_path):
    """A comment line or CRLF line endings are no change (the parsed mechanism is the
    same, though the bytes differ: the old byte hash failed here); a changed mass is,
    and the problem names the body, the field and both values."""
    model = tmp_path / "four.toml"
    text = Path(case_path("seed-four-bar")).read_text()
    model.write_text(text)
    out = tmp_path / "b.json"
    bs.save(br.record([str(model)], ["mujoco"], out, request=br.request_dict(samples=12),
                      runner=cached_runner))
    recorded = json.loads(out.read_text())["runs"][0]["model"]
    assert recorded["content"]["bodies.coupler.mass"] == 0.6
    for same in ("# a comment the user added\n" + text, text.replace("\n", "\r\n")):
        model.write_bytes(same.encode())
        assert bl.file_sha256(model) != bl.file_sha256(case_path("seed-four-bar"))
        (chk,) = bc.check(bs.load(out), runner=cached_runner)
        assert chk.passed, chk.problems
    model.write_text(text.replace("mass = 0.6", "mass = 0.61", 1))
    (chk,) = bc.check(bs.load(out), runner=cached_runner)
    assert not chk.passed
    assert "changed since the baseline (parsed mechanism): bodies.coupler.mass 0.6 -> " \
           "0.61" in chk.problems[0], chk.problems


def test_model_identity_names_removed_and_added_items():
    from dataclasses import replace

    from analytic import load_case
    from reports.regression import model_identity as mid
    mech = load_case("seed-four-bar")
    before = mid.content(mech)
    after = mid.content(replace(mech, gravity=(0.0, -9.81)))
    assert mid.changes(before, after).startswith("gravity [0.0, 0.0] -> [0.0, -9.81]")
    assert mid.digest(mech) == mid.digest(load_case("seed-four-bar"))
    assert mid.digest(mech) != mid.digest(replace(mech, gravity=(0.0, -9.81)))
    gone = {k: v for k, v in before.items() if not k.startswith("bodies.rocker.")}
    assert "bodies.rocker.mass removed (was " in mid.changes(before, gone, limit=10)


def test_recording_a_subset_merges_and_replace_replaces(tmp_path, capsys):
    """Issue 22: recording one case into a file of two kept the other run (it was
    silently replaced by the one); counts are printed; --replace writes only the new."""
    out = tmp_path / "b.json"
    common = ["--engine", "mujoco", "--samples", "12", "--out", str(out)]

    def runs():
        return sorted(r["case"] for r in json.loads(out.read_text())["runs"])
    assert main(["baseline", "record", "seed-four-bar", "quick-return", *common]) == 0
    assert runs() == ["quick-return", "seed-four-bar"]
    before = _run(json.loads(out.read_text()), "quick-return")
    assert main(["baseline", "record", "seed-four-bar", *common]) == 0
    assert "wrote 2 runs" in capsys.readouterr().out.split("\n")[-2]
    assert runs() == ["quick-return", "seed-four-bar"]
    assert _run(json.loads(out.read_text()), "quick-return") == before  # kept as it was
    assert main(["baseline", "record", "seed-four-bar", "six-bar", *common]) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last.endswith("1 updated, 1 kept, 1 added (--replace writes only the runs "
                         "recorded now)"), last
    assert main(["baseline", "record", "six-bar", "--replace", *common]) == 0
    assert capsys.readouterr().out.strip().endswith("(replaced)")
    assert runs() == ["six-bar"]


def test_changed_versions_are_named(mujoco_baseline, tmp_path, capsys):
    def edit(doc):
        for r in doc["runs"]:
            r["versions"]["engine"] = "mujoco 0.0.1"
    edited = _edited(mujoco_baseline, tmp_path / "v.json", edit)
    assert main(["baseline", "check", str(edited), "--case", "seed-four-bar"]) == 0
    out = capsys.readouterr().out
    assert "versions changed since the baseline: engine mujoco 0.0.1 -> mujoco " in out


# ============================================================== the file format
def test_file_is_sorted_and_one_line_per_quantity(mujoco_baseline):
    text = mujoco_baseline.read_text()
    doc = json.loads(text)
    assert text == bs.dumps(bs.load(mujoco_baseline)).replace(
        bs.load(mujoco_baseline).recorded, doc["recorded"])
    lines = [ln.strip() for ln in text.splitlines()]
    for run in doc["runs"]:
        names = [q["quantity"] for q in run["quantities"]]
        assert names == sorted(names)
        for q in run["quantities"]:
            assert json.dumps(q, sort_keys=True) + "," in lines or \
                json.dumps(q, sort_keys=True) in lines
    keys = [(r["case"], r["engine"]) for r in doc["runs"]]
    assert keys == sorted(keys)


BAD_FILES = {
    "not json": ("{", "not JSON: Expecting property name"),
    "another schema": ('{"schema": "x"}', "not a linkage-xval baseline"),
    "newer schema": ('{"schema": "linkage-xval baseline", "schema_version": 2, "runs": []}',
                     "schema_version 2 is not supported"),
    "no runs": ('{"schema": "linkage-xval baseline", "schema_version": 1}',
                "missing key 'runs'"),
}


@pytest.mark.parametrize("name", list(BAD_FILES))
def test_bad_baseline_files_are_one_line_status_2(name, tmp_path, capsys):
    text, msg = BAD_FILES[name]
    p = tmp_path / "b.json"
    p.write_text(text)
    assert main(["baseline", "check", str(p)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("xval: error: ") and msg in err, err


@pytest.mark.parametrize("edit, msg", [
    (lambda r: r.pop("settings"), "runs[0] (hibbeler-16-121 / mujoco): missing key 'settings'"),
    (lambda r: r["quantities"][0].update(error=-1), "'error' must be a number >= 0"),
    (lambda r: r["quantities"][0].update(error="small"), "'error' must be a number >= 0"),
    (lambda r: r["request"].update(samples="many"), "'samples' must be a whole number"),
    (lambda r: r["model"].update(file="x.toml"), "exactly one of 'builtin' or 'file'"),
    (lambda r: r["settings"]["fields"].update(warp=9), "no setting 'warp'"),
    (lambda r: r["settings"]["fields"].update(timestep="fast"),
     'timestep="fast": must be a number'),
])
def test_bad_entries_name_the_run_and_key(edit, msg, mujoco_baseline, tmp_path, capsys):
    p = _edited(mujoco_baseline, tmp_path / "b.json", lambda d: edit(d["runs"][0]))
    assert main(["baseline", "check", str(p), "--case", "hibbeler-16-121"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and msg in err and str(p) in err, err


def test_missing_file_and_bad_options(tmp_path, capsys):
    assert main(["baseline", "check", str(tmp_path / "none.json")]) == 2
    assert "no such baseline file" in capsys.readouterr().err
    assert main(["baseline", "check", str(BUILTIN), "--factor", "1"]) == 2
    assert "factor must be a finite number above 1" in capsys.readouterr().err
    assert main(["baseline", "record", "no-such-case", "--out", str(tmp_path / "b.json")]) == 2
    assert "no built-in case 'no-such-case'" in capsys.readouterr().err
    assert main(["baseline", "check", str(tmp_path)]) == 2
    assert "is a folder" in capsys.readouterr().err


# ============================================================== JUnit from xval compare
#: The rules of the schema the Jenkins xunit plugin validates JUnit files against:
#: ``junit-10.xsd`` in jenkinsci/xunit-plugin, src/main/resources/org/jenkinsci/plugins/
#: xunit/types/model/xsd/ (MIT; read at commit 031e285e).  Restated here as checks, not
#: copied: which attributes and children each element may have, the required ones, and
#: its time pattern.  Notably ``testcase`` may not carry ``file`` or ``properties``.
JENKINS_TESTCASE_ATTRS = {"name", "time", "classname", "group"}
JENKINS_TESTCASE_CHILDREN = {"skipped", "error", "failure", "rerunFailure", "rerunError",
                             "flakyFailure", "flakyError", "system-out", "system-err"}
JENKINS_SUITE_ATTRS = {"name", "tests", "failures", "errors", "group", "time", "skipped",
                       "timestamp", "hostname", "id", "package", "file", "log", "url"}
JENKINS_SUITES_ATTRS = {"name", "time", "tests", "failures", "errors"}
JENKINS_TIME = r"(([0-9]{0,3},)*[0-9]{3}|[0-9]{0,3})*(\.[0-9]*)?"


def _jenkins_xunit_rules(root: ET.Element) -> None:
    import re
    assert root.tag == "testsuites" and set(root.attrib) <= JENKINS_SUITES_ATTRS
    for el in (root, *root.iter("testsuite")):
        assert re.fullmatch(JENKINS_TIME, el.get("time", "")), el.get("time")
    for ts in root.iter("testsuite"):
        assert set(ts.attrib) <= JENKINS_SUITE_ATTRS, ts.attrib
        assert {"name", "tests", "failures", "errors"} <= set(ts.attrib)
        assert {c.tag for c in ts} <= {"testsuite", "properties", "testcase", "system-out",
                                       "system-err"}
        for p in ts.iter("property"):
            assert set(p.attrib) == {"name", "value"}
    for tc in root.iter("testcase"):
        assert set(tc.attrib) <= JENKINS_TESTCASE_ATTRS and "name" in tc.attrib, tc.attrib
        assert {c.tag for c in tc} <= JENKINS_TESTCASE_CHILDREN, [c.tag for c in tc]


def _validate_junit(path: Path, tests: int, failures: int, errors: int = 0) -> None:
    """Valid against the JUnit schema and the Jenkins xunit plugin's rules, with the
    expected counts on both levels."""
    xmlschema = pytest.importorskip("xmlschema")
    xmlschema.XMLSchema(str(XSD)).validate(str(path))
    root = ET.parse(path).getroot()
    _jenkins_xunit_rules(root)
    suite = root.find("testsuite")
    for el in (root, suite):
        assert (int(el.get("tests")), int(el.get("failures")), int(el.get("errors"))) == \
            (tests, failures, errors)
    cases = suite.findall("testcase")
    assert len(cases) == tests
    assert sum(c.find("failure") is not None for c in cases) == failures


def test_compare_junit_and_summary(tmp_path, capsys):
    """A failed compare (stock MuJoCo loop softness on the quick-return, 3.5e-3 of peak
    measured, README "Engines") carries its worst quantity and error in the JUnit
    failure; the schema validates it."""
    junit, summary = tmp_path / "c.xml", tmp_path / "c.md"
    code = main(["compare", "quick-return", "--engine", "mujoco", "--set",
                 "invweight_scale=1", "--samples", "12", "--junit", str(junit),
                 "--summary", str(summary)])
    capsys.readouterr()
    assert code == 1
    _validate_junit(junit, tests=1, failures=1)
    case = ET.parse(junit).getroot().find(".//testcase")
    assert case.get("classname") == "xval.compare.mujoco" and case.get("name") == "quick-return"
    props = {p.get("name"): p.get("value") for p in ET.parse(junit).getroot().iter("property")}
    assert props["engine.mujoco"].startswith("mujoco ") and props["linkage-xval"]
    msg = case.find("failure").get("message")
    q, err = msg.split(": error ")[0], float(msg.split(": error ")[1].split()[0])
    assert err > 1e-3 and "of peak at" in msg and "exceeds the tolerance 0.001" in msg
    assert q in case.find("failure").text and "invweight_scale=1" in case.find("failure").text
    md = summary.read_text()
    assert "| quick-return | mujoco | **FAIL** |" in md and f"`{q}`" in md
    assert not math.isnan(err)


def test_junit_for_ci_pages(tmp_path, capsys):
    """A model file is the suite's ``file`` attribute (relative, as given); versions are
    properties; a passing case carries its current worst error in ``system-out``;
    ``compare`` and ``baseline check`` results never share a (classname, name)."""
    model = tmp_path / "linkages" / "four.toml"
    model.parent.mkdir()
    shutil.copy(case_path("seed-four-bar"), model)
    base = tmp_path / "b.json"
    bs.save(br.record([str(model)], ["mujoco"], base, request=br.request_dict(samples=12),
                      runner=cached_runner))
    import os
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        assert main(["compare", "linkages/four.toml", "--engine", "mujoco", "--samples",
                     "12", "--junit", "c.xml"]) == 0
        assert main(["baseline", "check", "b.json", "--junit", "b.xml"]) == 0
    finally:
        os.chdir(cwd)
    capsys.readouterr()
    names = []
    for f in ("c.xml", "b.xml"):
        _validate_junit(tmp_path / f, tests=1, failures=0)
        root = ET.parse(tmp_path / f).getroot()
        assert root.find("testsuite").get("file") == "linkages/four.toml"
        props = {p.get("name"): p.get("value") for p in root.iter("property")}
        from importlib.metadata import version
        assert props["engine.mujoco"] == f"mujoco {version('mujoco')}"
        assert props["linkage-xval"] == version("linkage-xval")
        tc = root.find(".//testcase")
        out = tc.find("system-out").text
        assert out.startswith("worst: ") and " of peak at " in out and "tolerance 0.001" in out
        names.append((tc.get("classname"), tc.get("name")))
    assert names == [("xval.compare.mujoco", "seed-four-bar"),
                     ("xval.baseline.mujoco", "seed-four-bar")], names


def test_record_command_names_settings_that_differ_from_the_defaults(mujoco_baseline):
    """The re-record hint repeats the non-default settings as --set ENGINE.KEY=VALUE, in
    the form the command line parses back to the same settings object."""
    from dataclasses import replace

    from sim_models.engines.registry import get_engine, split_overrides
    base = bs.load(mujoco_baseline)
    run = base.runs[0]
    fields = dict(run.settings["fields"], timestep=1e-4, solref=[-20000.0, -300.0])
    edited = replace(base, runs=(replace(run, settings=dict(run.settings, fields=fields)),
                                 *base.runs[1:]))
    cmd = br.record_command(edited, mujoco_baseline.parent)
    sets = [w for w in cmd.split("--set ")[1:]]
    assert [s.split()[0] for s in sets] == ["mujoco.solref=-20000,-300",
                                            "mujoco.timestep=0.0001"], cmd
    over = split_overrides([s.split()[0] for s in sets], ["mujoco"])["mujoco"]
    assert get_engine("mujoco").settings(over) == \
        bset.settings_from_json(edited.runs[0], "test")
