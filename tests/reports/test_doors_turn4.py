"""Issue 30, outputs and baselines (../shared/bugs/README.md, "Outputs and baselines";
the reproducers copied to tests/data/bugs/turn4/): every door that writes a file or reads
a baseline, each reproducer as the user ran it.

Independent expectations: a changed model is named by the key this test changes in the
file; a refused output leaves the input's bytes as this test wrote them; a range is the
one the command line states (``xval simulate --help``); the wall-clock limit is a time
this test measures around the run.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from analytic import load_case
from reports.regression import model_identity as mid
from reports.regression.pytest_plugin import Xval

from .test_bad_inputs import assert_one_line_error

TURN4 = Path(__file__).resolve().parents[1] / "data" / "bugs" / "turn4"


@pytest.fixture(autouse=True)
def _headless(monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "disable")


def _copy(tmp_path, name: str) -> Path:
    p = tmp_path / name
    shutil.copyfile(TURN4 / name, p)
    return p


# ============================================================== 1. model identity
def test_identity_holds_every_force_element():
    """springs, dampers and the motor table, each field by name (was: a TypeError)."""
    flat = mid.content(load_case(str(TURN4 / "force_elements.toml")))
    json.dumps(flat, allow_nan=False)  # every value is JSON
    assert flat["motion.dampers.0.type"] == "jointdamper"
    assert flat["motion.dampers.0.coefficient"] == 0.01
    assert flat["motion.dampers.1.type"] == "pointdamper"
    assert flat["motion.dampers.1.coefficient"] == 0.05
    assert flat["motion.springs.0.stiffness"] == 30.0
    assert flat["motion.springs.1.type"] == "jointspring"
    assert flat["motion.motors.0.times"] == [0.0, 0.1, 0.2]
    assert flat["motion.motors.0.efforts"] == [0.0, 0.3, 0.1]
    # without force elements the identity is the one already recorded in the turn-4 files
    old = json.loads((TURN4 / "free_baseline_duration_1e4.json").read_text())
    assert mid.content(load_case(str(TURN4 / "free_fourbar.toml"))) == \
        old["runs"][0]["model"]["content"]


@pytest.mark.parametrize("free", [False, True], ids=["driven", "free"])
def test_baseline_of_force_elements_records_checks_and_names_a_changed_damper(
        tmp_path, capsys, free):
    model = _copy(tmp_path, "force_elements.toml")
    out = tmp_path / "B.json"
    extra = ["--free", "--duration", "0.1", "--samples", "11"] if free else \
        ["--revolutions", "1", "--samples", "12"]
    from reports.cli.xval import main
    assert main(["baseline", "record", str(model), "--engine", "mujoco", "--out", str(out),
                 *extra]) == 0, capsys.readouterr()
    assert main(["baseline", "check", str(out)]) == 0, capsys.readouterr()
    capsys.readouterr()
    model.write_text(model.read_text().replace("coefficient = 0.01", "coefficient = 0.02"))
    assert main(["baseline", "check", str(out)]) == 1
    text = capsys.readouterr().out
    assert "motion.dampers.0.coefficient 0.01 -> 0.02" in text, text


def test_reproducer_baseline_with_damper(tmp_path, capsys):
    from reports.cli.xval import main
    model = _copy(tmp_path, "baseline_with_damper.toml")
    assert main(["baseline", "record", str(model), "--engine", "mujoco", "--free",
                 "--duration", "0.05", "--samples", "6", "--out",
                 str(tmp_path / "B.json")]) == 0, capsys.readouterr()
    doc = json.loads((tmp_path / "B.json").read_text())
    assert doc["runs"][0]["model"]["content"]["motion.dampers.0.joint"] == "O4"


# ============================================================== 2. outputs
def _refused_untouched(capsys, tmp_path, argv, message):
    """``argv`` refused in one line (status 2); every file in ``tmp_path`` unchanged and
    no new one."""
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    assert_one_line_error(capsys, argv, message)
    after = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    assert after == before


def test_simulate_csv_is_its_input_refused(tmp_path, capsys):
    f = _copy(tmp_path, "simulate_csv_is_input.toml")
    (tmp_path / "link.toml").symlink_to(f.name)
    _refused_untouched(capsys, tmp_path, ["simulate", str(f), "--csv", str(f)],
                       r"--csv .* is the case file")
    _refused_untouched(capsys, tmp_path, ["simulate", str(f), "--csv",
                                          str(tmp_path / "link.toml")],
                       r"--csv .* is the case file")


@pytest.mark.parametrize("other", ["--junit", "--summary"])
def test_simulate_two_outputs_one_file_refused(tmp_path, capsys, other):
    f = _copy(tmp_path, "simulate_csv_same_as_junit.toml")
    x = str(tmp_path / "out.x")
    _refused_untouched(capsys, tmp_path, ["simulate", str(f), "--engine", "mujoco",
                                          "--csv", x, other, x],
                       f"--csv and {other} name the same file")


#: Every command that writes a file: an output on its own input, and two outputs on one
#: file ({f}: the case file, {b}: a baseline file, {x}: a new file).
EVERY_WRITER = [
    (["compare", "{f}", "--engine", "mujoco", "--junit", "{f}"], "--junit .* is the case file"),
    (["compare", "{f}", "--engine", "mujoco", "--junit", "{x}", "--summary", "{x}"],
     "--junit and --summary name the same file"),
    (["simulate", "{f}", "--csv", "{f}"], "--csv .* is the case file"),
    (["sweep", "{f}", "--csv", "{f}"], "--csv .* is the case file"),
    (["sweep", "{f}", "--parquet", "{f}"], "--parquet .* is the case file"),
    (["simulate", "{f}", "--engine", "mujoco", "--csv", "{x}", "--junit", "{x}"],
     "--csv and --junit name the same file"),
    (["plot", "{f}", "--out", "{f}"], "--out .* is the case file"),
    (["animate", "{f}", "--out", "{f}"], "--out .* is the case file"),
    (["explain", "{f}", "--out", "{f}"], "--out .* is the case file"),
    (["baseline", "record", "{f}", "--engine", "mujoco", "--out", "{f}"],
     "--out .* is the case file"),
    (["baseline", "check", "{b}", "--junit", "{b}"], "--junit .* is the baseline"),
    (["baseline", "check", "{b}", "--junit", "{x}", "--summary", "{x}"],
     "--junit and --summary name the same file"),
]


@pytest.mark.parametrize("argv, message", EVERY_WRITER,
                         ids=[" ".join(a[:2]) + f"-{i}" for i, (a, _) in
                              enumerate(EVERY_WRITER)])
def test_every_command_refuses_an_output_on_an_input(tmp_path, capsys, argv, message):
    f = _copy(tmp_path, "free_fourbar.toml")
    b = _copy(tmp_path, "free_baseline_samples_1e6.json")
    names = {"{f}": str(f), "{b}": str(b), "{x}": str(tmp_path / "x.out")}
    _refused_untouched(capsys, tmp_path, [names.get(a, a) for a in argv], message)


def test_a_refusal_leaves_no_folder(tmp_path, capsys, monkeypatch):
    """``sweep --parquet never/x.parquet`` refused after the option made its folder."""
    monkeypatch.chdir(tmp_path)
    assert_one_line_error(capsys, ["sweep", "seed-four-bar", "--parquet", "never/x.parquet",
                                   "--range", "10", "5"], "option --range")
    assert_one_line_error(capsys, ["simulate", "seed-four-bar", "--csv", "a/b/x.csv",
                                   "--duration", "0"], "--duration")
    assert not (tmp_path / "never").exists() and not (tmp_path / "a").exists()


# ============================================================== 3. deep nesting
def _deep(path: Path) -> Path:
    path.write_text('{"schema": "linkage-xval baseline", "schema_version": 1, "runs": '
                    + "[" * 100_000 + "]" * 100_000 + "}")
    return path


def test_deeply_nested_baseline_one_line(tmp_path, capsys):
    p = _deep(tmp_path / "deep.json")
    assert_one_line_error(capsys, ["baseline", "check", str(p)],
                          r"deep\.json: not JSON: nested too deeply")


USER_TESTS = '''
def test_mine():
    assert 1 + 1 == 2


def test_no_drift(xval_baseline):
    xval_baseline()
'''


def _user_pytest(root: Path) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_")}
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           "-p", "no:randomly"], cwd=root, env=env, capture_output=True,
                          text=True, timeout=600)


@pytest.mark.slow
def test_plugin_deep_baseline_fails_only_the_xval_test(tmp_path):
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "test_user.py").write_text(USER_TESTS)
    (tmp_path / "pytest.ini").write_text("[pytest]\ntestpaths = tests\nxval_baseline = "
                                         "bl_deep.json\n")
    _deep(tmp_path / "bl_deep.json")
    p = _user_pytest(tmp_path)
    out = p.stdout + p.stderr
    assert "1 failed, 1 passed" in out, out
    assert "RecursionError" not in out and "Traceback" not in out, out
    assert "xval: error: " in out and "nested too deeply" in out, out


# ============================================================== 4. free baselines
def test_free_baseline_samples_1e6_refused(tmp_path, capsys):
    b = _copy(tmp_path, "free_baseline_samples_1e6.json")
    _copy(tmp_path, "free_fourbar.toml")
    t0 = time.perf_counter()
    assert_one_line_error(capsys, ["baseline", "check", str(b)],
                          r"request samples=1000000: .*accepted range is 2 to 10001")
    assert time.perf_counter() - t0 < 30  # refused before any run (was: no end)


def test_simulate_with_engine_same_samples_range(capsys):
    assert_one_line_error(capsys, ["simulate", "iftomm-a01-pendulum", "--engine", "mujoco",
                                   "--samples", "1000000"],
                          r"argument --samples: .*accepted range is 2 to 10001")


def test_baseline_tolerance_1e300_refused(tmp_path, capsys):
    doc = json.loads((TURN4 / "free_baseline_samples_1e6.json").read_text())
    doc["runs"][0]["request"]["samples"] = 51
    doc["runs"][0]["quantities"][0]["tolerance"] = 1e300
    p = tmp_path / "b.json"
    p.write_text(json.dumps(doc))
    assert_one_line_error(capsys, ["baseline", "check", str(p)],
                          r"'tolerance' 1e\+300 is out of range: the accepted range is "
                          r"1e-15 to 1 of the quantity's peak")


def test_renamed_free_run_fails(tmp_path, capsys):
    from reports.cli.xval import main
    model = _copy(tmp_path, "free_fourbar.toml")
    out = tmp_path / "B.json"
    assert main(["baseline", "record", str(model), "--engine", "mujoco", "--free",
                 "--duration", "0.05", "--samples", "6", "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    doc["runs"][0]["case"] = "seed-four-bar"
    out.write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["baseline", "check", str(out)]) == 1
    text = capsys.readouterr().out
    assert "recorded as case 'seed-four-bar', but its model" in text and "runs as 'fb'" \
        in text, text


def test_free_pass_line_says_drift_and_the_failed_verdict(tmp_path, capsys):
    """A free run recorded while it fails (MuJoCo Euler at 0.02 s on A01): the check
    passes (no drift) and its line says the verdict against the exact trajectory fails."""
    from reports.cli.xval import main
    out = tmp_path / "B.json"
    assert main(["baseline", "record", "iftomm-a01-pendulum", "--engine", "mujoco", "--free",
                 "--duration", "2", "--samples", "101", "--set", "integrator=Euler",
                 "--set", "timestep=0.02", "--out", str(out)]) == 0, capsys.readouterr()
    capsys.readouterr()
    assert main(["baseline", "check", str(out)]) == 0
    line = next(ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("pass"))
    assert "no drift from the recorded run" in line, line
    assert "verdict against the exact trajectory: FAIL, as recorded" in line, line


# ============================================================== 5. the Python API
@pytest.mark.parametrize("samples, words", [
    (0, r"samples=0 sample intervals \(1 sample time\): 1 is out of range"),
    (10 ** 7, r"samples=10000000 sample intervals .* is out of range"),
    (2.5, r"samples=2\.5: 2\.5 is not a whole number"),
])
def test_api_free_samples_ranged(samples, words):
    x = Xval(TURN4, 2.0)
    t0 = time.perf_counter()
    with pytest.raises(pytest.fail.Exception) as e:
        x.assert_free_agrees("free_fourbar.toml", "mujoco", duration=0.2, samples=samples)
    assert time.perf_counter() - t0 < 30
    msg = str(e.value)
    assert msg.startswith("xval: error: ") and "\n" not in msg, msg
    import re
    assert re.search(words, msg), msg


def test_api_free_duration_ranged():
    with pytest.raises(pytest.fail.Exception, match=r"duration=0\.0: 0 is out of range"):
        Xval(TURN4, 2.0).assert_free_agrees("free_fourbar.toml", duration=0.0)


def test_api_file_without_motion_refused_as_the_command_line(tmp_path):
    text = (TURN4 / "free_fourbar.toml").read_text()
    (tmp_path / "nomotion.toml").write_text(text[:text.index("[motion]")])
    with pytest.raises(pytest.fail.Exception, match=r"no \[motion\] table"):
        Xval(tmp_path, 2.0).assert_free_agrees("nomotion.toml", duration=0.1, samples=5)


# ============================================================== 6. wall limit
def test_wall_limit_within_one_sample_interval():
    """One sample interval of 5e6 steps (--samples 2 --timestep 1e-6): the limit acts
    within the interval (was: only after it, tens of seconds later)."""
    from analytic.free_motion import simulate
    from reports.comparison.free_cases import command_case
    from sim_models.runs.free import free_settings, run_free
    from sim_models.runs.free_run import FreeRequest
    mech, _ = command_case("iftomm-a01-pendulum", 5.0)
    traj = simulate(mech, 5.0)
    req = FreeRequest(duration=5.0, samples=1, wall_limit=0.5)
    t0 = time.perf_counter()
    run = run_free(mech, "mujoco", free_settings("mujoco", {"timestep": 1e-6}), req, traj)
    took = time.perf_counter() - t0
    assert not run.ok and "wall-clock limit 0.5 s reached" in run.reason
    assert run.wall < 0.5 + 0.5 and run.steps < 5_000_000, (run.wall, run.steps)
    assert took < 0.5 + 5.0  # the model build is outside the limit, not the stepping
    # per simulated second stepped (steps x 1e-6 s), not per the 5 s interval asked for
    assert abs(run.cpu_per_simulated_second / (run.wall / (run.steps * 1e-6)) - 1) < 1e-9


# ============================================================== 7. free figure
def test_plot_free_samples_beyond_a_figure_refused(tmp_path, capsys):
    f = _copy(tmp_path, "plot_free_samples_max_hang.toml")
    t0 = time.perf_counter()
    assert_one_line_error(capsys, ["plot", str(f), "--free", "--samples", "1000000",
                                   "--what", "forces", "--out", str(tmp_path / "p.png")],
                          r"--samples 1000000: a figure draws at most 10001 samples")
    assert time.perf_counter() - t0 < 30 and not (tmp_path / "p.png").exists()


def test_prescribed_wall_limit_within_the_first_stop():
    """``xval plot seed-four-bar --engine pybullet --revolutions 1000``: 999 revolutions
    before the first sample, one stop (minutes, no end seen): a wall-clock limit acts
    within it."""
    from sim_models.runs.driven import run
    r = run(load_case("seed-four-bar"), "pybullet", revolutions=1000, wall_limit=0.5)
    assert not r.ok and "wall-clock limit 0.5 s reached" in r.reason, r.reason
    assert r.wall < 0.5 + 1.0, r.wall


def test_plot_prescribed_wall_limit(tmp_path, capsys):
    from reports.cli.xval import main
    out = tmp_path / "p.png"
    t0 = time.perf_counter()
    assert main(["plot", "seed-four-bar", "--engine", "pybullet", "--revolutions", "1000",
                 "--wall-limit", "1", "--out", str(out)]) == 0
    assert time.perf_counter() - t0 < 60 and out.is_file()
    assert "pybullet: run failed: wall-clock limit 1 s reached" in capsys.readouterr().out
    assert_one_line_error(capsys, ["plot", "seed-four-bar", "--wall-limit", "1"],
                          "--wall-limit bounds an engine's run; it needs --engine")


@pytest.mark.parametrize("tolerance", [1e300, 0.0, float("nan"), 2.0])
def test_api_tolerance_ranged(tolerance):
    """The plugin's ``tolerance=``: the range of ``--tolerance`` (1e-15 to 1 of peak)."""
    with pytest.raises(pytest.fail.Exception, match=r"tolerance=.*out of range: the "
                       r"accepted range is 1e-15 to 1 of the quantity's peak"):
        Xval(TURN4, 2.0).assert_agrees("seed-four-bar", "mujoco", tolerance=tolerance)
