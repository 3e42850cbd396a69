"""The pytest plugin (issue 13): a throwaway user project runs under pytest with it.

Independent expectations: the failing assertion is given a tolerance (1e-9 of peak)
below MuJoCo's measured error on that linkage (~1e-8, README "Engines"), the passing one
the project's 1e-3; the cache is judged by identity of the run objects and by the
plugin's own count of runs printed at the end of the session.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from reports.regression import baseline as bl
from reports.regression import baseline_record as br
from reports.regression import baseline_store as bs
from reports.regression.run_cache import SESSION, cached_runner

#: A user's own crank-rocker (Grashof: 40 + 150 <= 120 + 100), with gravity, in mm.
USER_TOML = """\
name = "my-four-bar"
description = "A user's crank-rocker: crank 40 mm, coupler 120 mm, rocker 100 mm."
gravity = [0.0, -9.81]

[units]
length = "mm"

[bodies.ground]
points = { O2 = [0, 0], O4 = [150, 0] }

[bodies.crank]
points = { O2 = [0, 0], A = [40, 0] }
mass = 0.1
com = [20, 0]
inertia = 1.333e-5

[bodies.coupler]
points = { A = [0, 0], B = [120, 0] }
mass = 0.3
com = [60, 0]
inertia = 3.6e-4

[bodies.rocker]
points = { O4 = [0, 0], B = [100, 0] }
mass = 0.25
com = [50, 0]
inertia = 2.083e-4

[[joints]]
name = "O2"
type = "revolute"
bodies = ["ground", "crank"]
points = ["O2", "O2"]

[[joints]]
name = "A"
type = "revolute"
bodies = ["crank", "coupler"]
points = ["A", "A"]

[[joints]]
name = "B"
type = "revolute"
bodies = ["coupler", "rocker"]
points = ["B", "B"]

[[joints]]
name = "O4"
type = "revolute"
bodies = ["ground", "rocker"]
points = ["O4", "O4"]

[driver]
joint = "O2"
value = 30.0
velocity = 20.0

[assembly]
points = { "coupler.B" = [110, 90] }
"""

USER_TESTS = '''\
def test_four_bar_agrees(xval):
    xval.assert_agrees("linkages/four_bar.toml", engine="mujoco", tolerance=1e-3)


def test_four_bar_to_a_billionth(xval):  # deliberately too tight: MuJoCo sits near 1e-8
    xval.assert_agrees("linkages/four_bar.toml", engine="mujoco", tolerance=1e-9)


def test_no_drift(xval_baseline):  # the baseline named in pytest.ini
    xval_baseline()
'''


@pytest.fixture(scope="module")
def user_project(tmp_path_factory):
    """A temporary user project: one TOML, one test file, a pytest.ini naming a
    baseline recorded here (the same run request the plugin makes by default)."""
    root = tmp_path_factory.mktemp("user-project")
    (root / "linkages").mkdir()
    (root / "tests").mkdir()
    (root / "linkages" / "four_bar.toml").write_text(USER_TOML)
    (root / "tests" / "test_linkages.py").write_text(USER_TESTS)
    (root / "pytest.ini").write_text("[pytest]\nxval_baseline = tests/baseline.json\n")
    base = br.record([str(root / "linkages" / "four_bar.toml")], ["mujoco"],
                     root / "tests" / "baseline.json", runner=cached_runner)
    bs.save(base)
    return root


def _pytest(root: Path, *args: str, **env: str) -> subprocess.CompletedProcess:
    e = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_")}
    e.update(env)
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider",
                           "-p", "no:randomly", *args], cwd=root, env=e,
                          capture_output=True, text=True, timeout=600)


@pytest.mark.slow
def test_user_project_one_pass_one_failure(user_project):
    """Through the installed ``pytest11`` entry point (autoloaded): the passing and the
    baseline assertions pass, the too-tight one fails with a message naming the
    quantity, the error, where in the cycle and the settings; the three assertions on
    one run cost one engine run."""
    p = _pytest(user_project, "-q")
    out = p.stdout
    print(out)  # the failure message, for the record (pytest -s)
    assert p.returncode == 1, out + p.stderr
    assert re.search(r"1 failed, 2 passed", out), out
    msg = out[out.index("AssertionError: "):]
    assert msg.startswith("AssertionError: my-four-bar (linkages/four_bar.toml) / mujoco: ")
    assert "disagree with the analytic solution by more than 1e-09 of peak" in msg
    # a quantity, its error relative to peak, where in the cycle, with units
    assert re.search(r"coupler\.alpha: error \d\.\d+e-0\d of peak at input [\d.]+ deg "
                     r"\(max \|error\| [\d.e-]+ rad/s\^2", msg), msg
    assert re.search(r"O4\.force: error [\d.e-]+ of peak at input [\d.]+ deg", msg)
    assert "settings: mujoco: timestep=0.00025 integrator=RK4" in msg
    assert "armature=1e+08" in msg and "run: 2 revolutions, 36 samples" in msg
    assert "xval: 1 engine runs" in out and "2 served from the session cache" in out


@pytest.mark.slow
def test_user_project_with_autoload_off_and_dash_p(user_project):
    """``-p xval`` (the entry point's name) loads the plugin when autoloading is off."""
    p = _pytest(user_project, "-q", "-p", "xval", "-k", "agrees",
                PYTEST_DISABLE_PLUGIN_AUTOLOAD="1")
    assert p.returncode == 0 and "1 passed" in p.stdout, p.stdout + p.stderr
    p = _pytest(user_project, "-q", "-k", "agrees", PYTEST_DISABLE_PLUGIN_AUTOLOAD="1")
    assert p.returncode != 0 and "fixture 'xval' not found" in p.stdout


def test_user_baseline_drift_fails_with_re_record_hint(user_project, xval, tmp_path):
    """The baseline assertion in-process (the session cache): a recorded error divided by
    100 fails naming the quantity, and the message ends with the command to re-record."""
    import json
    doc = json.loads((user_project / "tests" / "baseline.json").read_text())
    q = max(doc["runs"][0]["quantities"], key=lambda q: q["error"])
    assert q["error"] < bl.DRIFT_FLOOR  # MuJoCo: ~1e-8, under the floor: /100 is no drift
    xval.assert_baseline(user_project / "tests" / "baseline.json")
    q["error"] = q["error"] / 100
    q["tolerance"] = q["error"] * 50     # but over a tolerance it fails
    p = tmp_path / "b.json"
    p.write_text(json.dumps(doc))
    (tmp_path / "linkages").mkdir()
    (tmp_path / "linkages" / "four_bar.toml").write_text(USER_TOML)
    doc["runs"][0]["model"]["file"] = "linkages/four_bar.toml"
    p.write_text(json.dumps(doc))
    with pytest.raises(AssertionError) as e:
        xval.assert_baseline(p)
    text = str(e.value)
    assert f"FAIL  my-four-bar / mujoco: {q['quantity']}: error " in text
    assert "exceeds its tolerance" in text
    assert text.splitlines()[0].startswith(f"my-four-bar / mujoco: {q['quantity']}: error ")
    assert "record again: pytest --xval-update, or" in text
    assert "linkages/four_bar.toml" in text


# ============================================================== in this session
def test_plugin_registered_through_the_entry_point(pytestconfig):
    import xval_pytest_plugin
    plugin = pytestconfig.pluginmanager.get_plugin("xval")
    assert plugin is xval_pytest_plugin, "pip install -e '.[test]' registers the pytest11 entry"


def test_assertions_share_one_cached_run(xval):
    before = dict(SESSION.stats)
    r1 = xval.run("seed-four-bar", "mujoco", samples=24)
    comps = xval.assert_agrees("seed-four-bar", engine="mujoco", samples=24)
    r2, _ = xval.compare("seed-four-bar", "mujoco", tolerance=1e-3, samples=24,
                         quantities=["B.force"])
    assert r1 is r2
    assert SESSION.stats["runs"] - before["runs"] <= 1
    assert {c.quantity for c in comps} >= {"coupler.alpha", "rocker.alpha", "B.force"}
    with pytest.raises(KeyError, match="no quantity 'B.torque'"):
        xval.compare("seed-four-bar", "mujoco", samples=24, quantities=["B.torque"])


def test_the_run_cache_is_an_object(tmp_path):
    """An ``Xval`` given its own :class:`RunCache` runs, counts and serves from that one;
    the session's (:data:`SESSION`) is left as it was."""
    from reports.regression.pytest_plugin import Xval
    from reports.regression.run_cache import RunCache
    cache, before = RunCache(), dict(SESSION.stats)
    x = Xval(tmp_path, bl.DEFAULT_FACTOR, runs=cache)
    r1 = x.run("seed-four-bar", "mujoco", samples=24)
    r2 = x.run("seed-four-bar", "mujoco", samples=24)
    assert r1 is r2
    assert (cache.stats["runs"], cache.stats["hits"], len(cache.entries)) == (1, 1, 1)
    assert SESSION.stats == before


def test_failure_names_quantity_error_where_and_settings(xval):
    with pytest.raises(AssertionError) as e:
        xval.assert_agrees("seed-four-bar", engine="mujoco", tolerance=1e-12, samples=24,
                           settings={"timestep": "0.00025"})
    text = str(e.value)
    lines = text.splitlines()
    assert lines[0].startswith("seed-four-bar / mujoco: ")
    worst = lines[1].strip()
    assert re.match(r"\S+: error \d\.\d+e-\d+ of peak at input [\d.]+ deg \(max \|error\| ",
                    worst), worst
    assert lines[-2].strip().startswith("settings: mujoco: timestep=0.00025 ")


def test_a_refusal_is_cached_and_raised(xval):
    from dataclasses import replace

    from analytic import load_case
    from sim_models.engines.protocol import EngineRefusal
    mech = load_case("seed-four-bar")
    still = replace(mech, driver=replace(mech.driver, velocity=0.0, acceleration=0.0))
    for _ in range(2):
        with pytest.raises(EngineRefusal, match="no motion"):
            xval.assert_agrees(still, engine="mujoco")


def test_plugin_imports_nothing_heavy():
    """Every pytest run in the environment loads the plugin (the entry point's module): it
    must not import numpy, an engine, or any package of the tool until a fixture is used."""
    code = textwrap.dedent("""
        import sys, xval_pytest_plugin
        heavy = {"numpy", "mujoco", "pybullet", "exudyn", "analytic", "sim_models", "reports"}
        print(sorted(heavy & set(sys.modules)))
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"


# ============================================================== a user's own `reports`
def test_a_users_own_reports_package_leaves_pytest_working(tmp_path):
    """A user project with a ``reports`` package of its own (found first: the rootdir is
    on sys.path through ``python -m pytest`` and its conftest): its unrelated tests run
    and pass with the plugin installed; a test that uses the xval fixture fails with one
    line naming the colliding package, not an import error or a traceback."""
    (tmp_path / "reports").mkdir()
    (tmp_path / "reports" / "__init__.py").write_text("TOTAL = 42\n")
    (tmp_path / "conftest.py").write_text("")
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "test_theirs.py").write_text(
        "import reports\n\n\ndef test_their_reports():\n    assert reports.TOTAL == 42\n")
    (tmp_path / "tests" / "test_engine.py").write_text(
        "def test_uses_xval(xval):\n    xval.assert_agrees('seed-four-bar')\n")
    p = _pytest(tmp_path, "-q", "-rE")
    out = p.stdout + p.stderr
    assert p.returncode == 1, out
    assert re.search(r"1 passed, 1 error", out), out
    # the error as the test's own report gives it (pytest's short summary repeats it
    # in full under CI, where it does not truncate to the terminal's width)
    [line] = [ln for ln in out.splitlines() if "package name collision" in ln
              and not ln.startswith(("ERROR ", "FAILED "))]
    assert "'reports' is imported from" in line and str(tmp_path / "reports") in line, line
    assert "Traceback" not in out and "ModuleNotFoundError" not in out, out
    # the unrelated test alone: a clean pass, nothing of the tool imported
    p = _pytest(tmp_path, "-q", "tests/test_theirs.py")
    assert p.returncode == 0 and "1 passed" in p.stdout, p.stdout + p.stderr


# ============================================================== pytest conventions
@pytest.fixture(scope="module")
def drift_project(tmp_path_factory):
    """A user project whose baseline holds the four-bar in three engines; Exudyn's
    O4.force (4.1e-6 of peak measured, above the floor) recorded 10.6x smaller than it
    is, so re-running reads as a 10.6x drift in that one quantity."""
    root = tmp_path_factory.mktemp("drift-project")
    (root / "linkages").mkdir()
    (root / "tests").mkdir()
    (root / "linkages" / "four_bar.toml").write_text(USER_TOML)
    (root / "tests" / "test_drift.py").write_text(
        "def test_no_drift(xval_baseline):\n    xval_baseline()\n\n\n"
        "def test_plain():\n    assert True\n")
    (root / "pytest.ini").write_text("[pytest]\nxval_baseline = tests/baseline.json\n")
    out = root / "tests" / "baseline.json"
    bs.save(br.record([str(root / "linkages" / "four_bar.toml")],
                      ["mujoco", "pybullet", "exudyn"], out, runner=cached_runner))
    import json
    doc = json.loads(out.read_text())
    run = next(r for r in doc["runs"] if r["engine"] == "exudyn")
    q = next(q for q in run["quantities"] if q["quantity"] == "O4.force")
    assert q["error"] > 10.6 * bl.DRIFT_FLOOR  # still above the floor once divided
    q["error"] = q["error"] / 10.6
    out.write_text(json.dumps(doc, indent=2))
    return root


@pytest.mark.slow
def test_a_drift_in_one_quantity_is_one_red_test(drift_project, tmp_path):
    """Must show (issue 22): the 10.6x drift is one red test ``my-four-bar/exudyn`` whose
    first failure line (and JUnit message) names the quantity, the growth, the factor
    and where; the other engines' tests stay green; run from ``tests/`` (paths are
    rootdir-relative)."""
    junit = tmp_path / "p.xml"
    p = _pytest(drift_project / "tests", "-q", f"--junitxml={junit}")
    out = p.stdout
    print(out)
    assert p.returncode == 1, out + p.stderr
    assert re.search(r"1 failed, 3 passed", out), out
    assert "FAILED test_drift.py::test_no_drift[my-four-bar/exudyn]" in out, out
    first = re.search(r"E +AssertionError: (.*)", out).group(1)
    assert re.match(r"my-four-bar / exudyn: O4\.force: drifted \S+ -> \S+ of peak at "
                    r"[\d.]+ deg \(10\.6x\), more than the factor 10$", first), first
    import xml.etree.ElementTree as ET
    cases = {c.get("name"): c for c in ET.parse(junit).getroot().iter("testcase")}
    assert set(cases) >= {f"test_no_drift[my-four-bar/{e}]"
                          for e in ("mujoco", "pybullet", "exudyn")}
    msg = cases["test_no_drift[my-four-bar/exudyn]"].find("failure").get("message")
    assert msg.startswith("AssertionError: my-four-bar / exudyn: O4.force: drifted "), msg
    assert cases["test_no_drift[my-four-bar/mujoco]"].find("failure") is None


@pytest.mark.slow
def test_skip_and_select_engine_tests(drift_project, tmp_path):
    """``--xval-skip-engines`` skips, ``-m "not xval_engine"`` deselects every test that
    uses an xval fixture; ``baseline_params`` takes a rootdir-relative path, so its
    collection works from ``tests/`` too (it was relative to the current folder)."""
    import shutil
    root = tmp_path / "p"
    shutil.copytree(drift_project, root)
    (root / "tests" / "test_params.py").write_text(
        "import pytest\nfrom xval_pytest_plugin import baseline_params\n\n\n"
        "@pytest.mark.parametrize('case, engine', baseline_params('tests/baseline.json'))\n"
        "def test_run(xval, case, engine):\n"
        "    xval.assert_baseline('tests/baseline.json', case=case, engine=engine)\n")
    p = _pytest(root / "tests", "-q", "--xval-skip-engines")
    assert p.returncode == 0 and "1 passed, 6 skipped" in p.stdout, p.stdout + p.stderr
    p = _pytest(root, "-q", "-m", "not xval_engine")
    assert p.returncode == 0 and "1 passed, 6 deselected" in p.stdout, p.stdout


@pytest.mark.slow
def test_unusable_and_missing_baselines_are_one_line(drift_project, tmp_path):
    import shutil
    root = tmp_path / "p"
    shutil.copytree(drift_project, root)
    (root / "tests" / "baseline.json").write_text("{not json")
    p = _pytest(root, "-q", "-k", "no_drift")
    assert p.returncode == 1 and "1 failed" in p.stdout, p.stdout
    [line] = [ln for ln in p.stdout.splitlines() if "xval: error:" in ln and "not JSON" in ln
              and not ln.startswith(("ERROR ", "FAILED "))]
    assert "Traceback" not in p.stdout and "baseline.py" not in p.stdout, p.stdout
    (root / "tests" / "baseline.json").unlink()
    p = _pytest(root, "-q", "-k", "no_drift")
    assert p.returncode == 1, p.stdout
    assert "no baseline file tests/baseline.json" in p.stdout
    assert "create it with: xval baseline record" in p.stdout


@pytest.mark.slow
def test_xval_update_rewrites_what_changed_and_creates_a_missing_file(drift_project,
                                                                      tmp_path):
    import json
    import shutil
    root = tmp_path / "p"
    shutil.copytree(drift_project, root)
    p = _pytest(root, "-q", "--xval-update")
    assert p.returncode == 0 and "4 passed" in p.stdout, p.stdout
    assert "xval --xval-update: my-four-bar / exudyn in tests/baseline.json: rewrote " \
           "(O4.force: drifted" in p.stdout, p.stdout
    doc = json.loads((root / "tests" / "baseline.json").read_text())
    assert len(doc["runs"]) == 3  # the others kept
    p = _pytest(root, "-q")
    assert p.returncode == 0 and "4 passed" in p.stdout, p.stdout
    # a missing file named with its run: failing without the flag, created with it
    (root / "tests" / "test_new.py").write_text(
        "def test_new(xval):\n    xval.assert_baseline('tests/new.json', "
        "case='linkages/four_bar.toml', engine='mujoco')\n")
    p = _pytest(root, "-q", "tests/test_new.py")
    assert p.returncode == 1 and "no baseline file tests/new.json" in p.stdout
    assert "create it with pytest --xval-update, or: xval baseline record " \
           "linkages/four_bar.toml --engine mujoco --out tests/new.json" in p.stdout, p.stdout
    p = _pytest(root, "-q", "tests/test_new.py", "--xval-update")
    assert p.returncode == 0 and "xval --xval-update: my-four-bar / mujoco in " \
        "tests/new.json: created" in p.stdout, p.stdout
    p = _pytest(root, "-q", "tests/test_new.py")
    assert p.returncode == 0, p.stdout


def test_baseline_under_other_settings(user_project, xval):
    """``settings=`` overrides the recorded settings of every run whose engine has the
    key, and the check's settings text says what was changed."""
    _, (chk,) = xval.check_baseline(user_project / "tests" / "baseline.json",
                                    settings={"timestep": 0.0002})
    assert "timestep=0.0002" in chk.settings_text
    assert chk.settings_text.endswith("(changed for this check: timestep=0.0002)")


def test_a_loose_baseline_warns_and_fails_with_the_flag(user_project, xval, tmp_path):
    """A recorded error 1000x the current one (above the floor once multiplied): a
    pytest warning naming it; with ``--xval-fail-loose`` (``fail_loose``) a failure."""
    import json

    from reports.regression.pytest_plugin import Xval, XvalLooseWarning
    doc = json.loads((user_project / "tests" / "baseline.json").read_text())
    q = max(doc["runs"][0]["quantities"], key=lambda q: q["error"])
    q["error"] *= 1000
    assert q["error"] > bl.DEFAULT_FACTOR * bl.DRIFT_FLOOR
    doc["runs"][0]["model"]["file"] = str(user_project / "linkages" / "four_bar.toml")
    p = tmp_path / "loose.json"
    p.write_text(json.dumps(doc))
    with pytest.warns(XvalLooseWarning, match=rf"{q['quantity']}: improved .* the baseline "
                                              "is loose; re-record"):
        xval.assert_baseline(p)
    strict = Xval(xval.root, xval.factor, fail_loose=True)
    with pytest.raises(AssertionError, match=rf"^my-four-bar / mujoco: {q['quantity']}: "
                                             "improved "):
        strict.assert_baseline(p)
