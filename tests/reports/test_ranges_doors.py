"""Every door of an engine setting or run request goes through the same ranges
(sim_models/engines/ranges.py): ``--set``, the option flags, a baseline file, the pytest
plugin's option.  Each impossible value is one line, status 2, naming what the user
typed (the option, or the file, run and key), and no engine runs.  The table of
impossible values is tests/sim_models/engines/test_settings_ranges.py's; the baseline
reproducers are ../shared/bugs/baseline-*.json, copied to tests/data/bugs/."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from reports.cli.xval import main
from sim_models.engines.registry import get_engine

from ..sim_models.engines.test_settings_ranges import ENGINES, IMPOSSIBLE
from .test_bad_inputs import assert_one_line_error

BUGS = Path(__file__).resolve().parents[1] / "data" / "bugs"
BUILTIN = Path(__file__).resolve().parents[1] / "baselines" / "builtin.json"


@pytest.fixture
def no_run(monkeypatch):
    """Fail the test if any engine run or comparison starts."""
    import reports.comparison.runs as vr
    import reports.regression.baseline_check as bc
    import reports.regression.baseline_record as br
    from sim_models.runs import driven

    def ran(*a, **k):
        pytest.fail("an engine ran for an impossible setting")
    monkeypatch.setattr(vr, "run_comparison", ran)
    monkeypatch.setattr(vr, "run_verdict", ran)
    monkeypatch.setattr(br, "run_and_compare", ran)
    monkeypatch.setattr(bc, "run_and_compare", ran)  # check's default runner
    monkeypatch.setattr(br, "record", ran)
    monkeypatch.setattr(driven, "open_session", ran)


def _rows():
    return [pytest.param(*r, id=f"{r[0]}.{r[1]}={r[2]}") for r in IMPOSSIBLE
            if r[0] in ENGINES]


# ============================================================== --set
@pytest.mark.parametrize("engine, key, value, words", _rows())
def test_set_door(capsys, no_run, engine, key, value, words):
    item = f"{engine}.{key}={value}"
    assert_one_line_error(capsys, ["compare", "seed-four-bar", "--engine", engine,
                                   "--set", item], "^xval: error: " + re.escape(
                                       f"--set {item}: ") + ".*" + re.escape(words))


@pytest.mark.parametrize("engine, key, value, words", [r for r in _rows()
                                                       if r.values[1] == "timestep"])
def test_set_door_of_baseline_record(capsys, no_run, tmp_path, engine, key, value, words):
    item = f"{key}={value}"
    assert_one_line_error(capsys, ["baseline", "record", "seed-four-bar", "--engine", engine,
                                   "--out", str(tmp_path / "b.json"), "--set", item],
                          re.escape(f"--set {item}: ") + ".*" + re.escape(words))
    assert not (tmp_path / "b.json").exists()


@pytest.mark.parametrize("argv, message", [
    (["--set", "timestep=1e-9"], r"--set timestep=1e-9: 1e-09 is out of range: the "
                                 r"accepted range is 1e-06 to 0\.1 s"),
    (["--set", "integrator=Euler", "--integrator", "RK4"],
     r"--integrator RK4 and --set integrator=Euler both set mujoco's integrator; give one"),
    (["--set", "timestep=1e-3", "--timestep", "1e-4"],
     r"--timestep 0\.0001 and --set timestep=1e-3 both set mujoco's timestep"),
    (["--set", "timestep=1e-3", "--set", "timestep=2e-3"],
     r"--set timestep=1e-3 and --set timestep=2e-3 both set mujoco's timestep"),
    (["--timestep", "1e-9"], r"argument --timestep: 1e-09 is out of range: the accepted "
                             r"range is 1e-06 to 0\.1 s"),
    (["--revolutions", "-3"], r"argument --revolutions: -3 is out of range: .*1 to 1000"),
    (["--samples", "1"], r"argument --samples: 1 is out of range: .*2 to 3600"),
], ids=["plain-timestep", "integrator-twice", "timestep-flag-and-set", "set-twice",
        "timestep-flag", "revolutions-flag", "samples-flag"])
def test_flags_and_conflicts(capsys, no_run, argv, message):
    assert_one_line_error(capsys, ["compare", "seed-four-bar", *argv], message)


@pytest.mark.parametrize("cmd", [["plot", "seed-four-bar", "--engine", "mujoco"],
                                 ["baseline", "record", "seed-four-bar", "--out", "{b}"]])
@pytest.mark.parametrize("flag, value, words", [("--revolutions", "1001", "1 to 1000"),
                                                ("--samples", "3601", "2 to 3600")])
def test_flags_of_other_commands(capsys, no_run, tmp_path, cmd, flag, value, words):
    argv = [a.replace("{b}", str(tmp_path / "b.json")) for a in cmd] + [flag, value]
    assert_one_line_error(capsys, argv, f"argument {flag}: {value} is out of range: "
                                        f".*{words}")


# ============================================================== baseline files
def _typed(engine: str, key: str, text: str):
    """``text`` as a JSON value of the field's type (a bool field keeps the string: a
    wrong type, refused as such)."""
    typ = get_engine(engine).settings_class.field_types()[key]
    if typ is float:
        return float(text)
    if typ is int:
        return int(float(text))
    if typ is bool or typ is str:
        return text
    return [float(x) for x in text.split(",")]


def _one_run(engine: str) -> dict:
    doc = json.loads(BUILTIN.read_text())
    doc["runs"] = [next(r for r in doc["runs"] if r["engine"] == engine)]
    return doc


@pytest.mark.parametrize("engine, key, value, words", _rows())
def test_baseline_settings_door(capsys, no_run, tmp_path, engine, key, value, words):
    doc = _one_run(engine)
    run = doc["runs"][0]
    run["settings"]["fields"][key] = _typed(engine, key, value)
    p = tmp_path / "b.json"
    p.write_text(json.dumps(doc))
    typ = get_engine(engine).settings_class.field_types()[key]
    expect = "must be true or false" if typ is bool else re.escape(words)
    assert_one_line_error(capsys, ["baseline", "check", str(p)],
                          re.escape(f"{p}: runs[0] ({run['case']} / {engine}): settings "
                                    f"field {key}=") + ".*" + expect)


#: The issue-22 reproducers: (file, the words of the one-line refusal).
BUG_FILES = {
    "baseline-bad-chords.json": r"runs\[0\] \(seed-four-bar / mujoco\): request "
                                r"chords=\"bogus\": 'bogus' is not accepted: use one of "
                                r"moving, analytic",
    "baseline-no-runs.json": r"'runs' is empty: a baseline with no runs judges nothing",
    "baseline-no-quantities.json": r"runs\[0\] \(seed-four-bar / mujoco\): 'quantities' is "
                                   r"empty",
    "baseline-zero-revolutions.json": r"runs\[0\] \(seed-four-bar / mujoco\): request "
                                      r"revolutions=0: 0 is out of range: the accepted "
                                      r"range is 1 to 1000 .*the range of --revolutions",
    "baseline-nan-violation.json": r"runs\[0\] \(seed-four-bar / mujoco\): request "
                                   r"max_violation=NaN: nan is not a finite number",
    "baseline-huge-revolutions.json": r"runs\[0\] \(seed-four-bar / mujoco\): request "
                                      r"revolutions=100000: 100000 is out of range",
    "baseline-tiny-timestep.json": r"runs\[0\] \(seed-four-bar / mujoco\): settings field "
                                   r"timestep=1e-09: 1e-09 is out of range: the accepted "
                                   r"range is 1e-06 to 0\.1 s",
}


def test_every_bug_baseline_is_covered():
    assert {p.name for p in BUGS.glob("baseline-*.json")} == set(BUG_FILES)


@pytest.mark.parametrize("name", sorted(BUG_FILES))
def test_bug_baseline_files(capsys, no_run, name):
    path = BUGS / name
    assert_one_line_error(capsys, ["baseline", "check", str(path)],
                          re.escape(str(path)) + ": " + BUG_FILES[name])


def _edit_run(doc, fn):
    fn(doc["runs"][0])
    return doc


#: Edits of a valid one-run baseline (the zero-revolutions reproducer with 2
#: revolutions), and the words of the refusal.
EDITS = {
    "revolutions-negative": (lambda d: _edit_run(d, lambda r: r["request"].update(
        revolutions=-3)), r"request revolutions=-3: -3 is out of range"),
    "revolutions-true": (lambda d: _edit_run(d, lambda r: r["request"].update(
        revolutions=True)), r"request revolutions=true: a true/false value is not a number"),
    "samples-1": (lambda d: _edit_run(d, lambda r: r["request"].update(samples=1)),
                  r"request samples=1: 1 is out of range: .*2 to 3600.*the range of --samples"),
    "samples-1e7": (lambda d: _edit_run(d, lambda r: r["request"].update(samples=10 ** 7)),
                    r"request samples=10000000: 10000000 is out of range"),
    "speed-error-text": (lambda d: _edit_run(d, lambda r: r["request"].update(
        max_speed_error="0.01")), r"request: 'max_speed_error' must be a number"),
    "settings-field-missing": (lambda d: _edit_run(d, lambda r: r["settings"]["fields"].pop(
        "armature")), r"settings field 'armature' is missing \(it would run at today's "
                      r"default 100000000\.0\)"),
    "settings-wrong-type": (lambda d: _edit_run(d, lambda r: r["settings"]["fields"].update(
        iterations="100")), r"settings field iterations=\"100\": must be a whole number"),
    "settings-float-for-int": (lambda d: _edit_run(d, lambda r: r["settings"]["fields"]
                                                   .update(iterations=100.5)),
                               r"settings field iterations=100\.5: must be a whole number"),
    "settings-unknown-field": (lambda d: _edit_run(d, lambda r: r["settings"]["fields"]
                                                   .update(warp=9)),
                               r"settings field 'warp': mujoco has no setting 'warp'"),
    "settings-wrong-class": (lambda d: _edit_run(d, lambda r: r["settings"].update(
        **{"class": "PybulletSettings"})), r"settings class 'PybulletSettings' is not "
                                           r"mujoco's \(MujocoSettings\)"),
    "engine-unknown": (lambda d: _edit_run(d, lambda r: r.update(engine="gazebo")),
                       r"\(seed-four-bar / gazebo\): 'engine' 'gazebo' is not a known "
                       r"engine; engines: mujoco"),
    "quantities-empty": (lambda d: _edit_run(d, lambda r: r.update(quantities=[])),
                         r"'quantities' is empty"),
    "schema-version": (lambda d: {**d, "schema_version": 2},
                       r"schema_version 2 is not supported"),
}


@pytest.mark.parametrize("name", sorted(EDITS))
def test_baseline_file_edits(capsys, no_run, tmp_path, name):
    doc = json.loads((BUGS / "baseline-zero-revolutions.json").read_text())
    doc["runs"][0]["request"]["revolutions"] = 2
    edit, words = EDITS[name]
    p = tmp_path / "b.json"
    p.write_text(json.dumps(edit(doc)))
    assert_one_line_error(capsys, ["baseline", "check", str(p)],
                          re.escape(str(p)) + ": " + ("" if name == "schema-version" else
                                                      r"runs\[0\] .*") + words)


def test_the_unedited_base_of_the_edits_loads(tmp_path):
    """The edits above change one thing of a file that is otherwise accepted."""
    import reports.regression.baseline_store as bs
    doc = json.loads((BUGS / "baseline-zero-revolutions.json").read_text())
    doc["runs"][0]["request"]["revolutions"] = 2
    p = tmp_path / "b.json"
    p.write_text(json.dumps(doc))
    assert len(bs.load(p).runs) == 1


# ============================================================== drift factor options
def test_factor_option_of_baseline_check(capsys, no_run):
    assert_one_line_error(capsys, ["baseline", "check", str(BUILTIN), "--factor", "0.5"],
                          r"argument --factor: 0\.5 is out of range: the drift factor must be a "
                          r"finite number above 1")


def _pytest(root: Path, *args: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_")}
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           *args], cwd=root, env=env, capture_output=True, text=True,
                          timeout=300)


@pytest.mark.slow
def test_xval_factor_is_checked_where_pytest_parses_it(tmp_path):
    """``--xval-factor 0`` was silently taken as 10, ``0.5`` failed at test time naming
    ``--factor``: both are now pytest usage errors naming ``--xval-factor``; a valid
    value reaches the fixture."""
    (tmp_path / "test_f.py").write_text("def test_f(xval):\n    assert xval.factor == 3.0\n")
    for bad in ("0", "0.5", "nan"):
        p = _pytest(tmp_path, "--xval-factor", bad)
        assert p.returncode == 4, p.stdout + p.stderr
        assert f"argument --xval-factor: {bad} is out of range: the drift factor must be a " \
               "finite number above 1" in p.stderr, p.stderr
    p = _pytest(tmp_path, "--xval-factor", "3")
    assert p.returncode == 0, p.stdout + p.stderr


# ============================================================== input ranges, models
@pytest.mark.parametrize("argv, message", [
    (["sweep", "seed-four-bar", "--points", "36", "--range", "0", "1e300"],
     r"argument --range: 1e\+300 is out of range: the accepted range is \|x\| <= 360000 deg"),
    (["sweep", "seed-four-bar", "--points", "36", "--range", "0", "360000.001"],
     r"argument --range: 360000\.001 is out of range"),
    (["sweep", "hibbeler-16-30", "--points", "10", "--range", "0", "2e4"],
     r"argument --range: 20000 is out of range: the accepted range is \|x\| <= 10000 m"),
    (["solve", "seed-four-bar", "--angle", "360000.001"],
     r"argument --angle: 360000\.001 is out of range: the accepted range is \|x\| <= 360000"),
], ids=["range-1e300", "range-just-above", "range-prismatic", "angle-just-above"])
def test_input_ranges_are_capped_like_angle(capsys, tmp_path, argv, message):
    argv = argv + (["--csv", str(tmp_path / "o.csv")] if argv[0] == "sweep" else [])
    assert_one_line_error(capsys, argv, message)
    assert not (tmp_path / "o.csv").exists()


def test_the_printed_bound_itself_is_accepted(capsys, tmp_path):
    """'|x| <= 360000 deg' accepts 360000 deg (1 ulp above 2000 pi rad once converted),
    on the command line and in a file."""
    from analytic.cases import case_path
    assert main(["solve", "seed-four-bar", "--angle", "-360000"]) == 0
    assert main(["sweep", "seed-four-bar", "--points", "4", "--range", "-360000",
                 "360000", "--csv", str(tmp_path / "o.csv")]) == 0
    text = re.sub(r"(?m)^value = .*$", "value = 360000.0", case_path("seed-four-bar")
                  .read_text(), count=1)
    assert "value = 360000.0" in text
    (tmp_path / "f.toml").write_text(text)
    assert main(["solve", str(tmp_path / "f.toml")]) == 0
    capsys.readouterr()


def test_models_refuses_what_compare_refuses(capsys, tmp_path):
    """nano-four-bar.toml: models ended in MuJoCo's ValueError traceback where compare
    refused in one line; both now give the same line."""
    bug = str(BUGS / "nano-four-bar.toml")
    errs = []
    for argv in (["models", bug, "--out", str(tmp_path / "D")],
                 ["compare", bug, "--engine", "mujoco"]):
        assert main(argv) == 2
        errs.append(capsys.readouterr().err)
    assert errs[0] == errs[1] and errs[0].count("\n") == 1, errs
    assert re.match(r"xval: error: mechanism 'fb' \(size 4e-10 m\): MuJoCo cannot compile its "
                    r"model", errs[0])
    assert not (tmp_path / "D").exists()  # a refusal leaves no folder (issue 30)
