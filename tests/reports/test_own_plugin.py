"""The pytest plugin on a user's own engine model (issue 32): a throwaway user project
holds hand-written MJCF files (tests/sim_models/own/user_models.py), its tests assert
them with ``xval.assert_agrees("models/six_bar.xml", engine="mujoco")``, the free
assertion, and ``xval_baseline`` on a baseline recorded on the files; run by pytest in a
subprocess.

Independent expectations: the failing assertion is given a tolerance (1e-6 of peak)
below MuJoCo's measured error on the near-hard six-bar (worst 5.0e-4, coupler.alpha,
tests/sim_models/own/test_own_runs.py), the passing one the project's 1e-3; the cache is
judged by the plugin's own count of runs printed at the end of the session; the runs
are the user's file's, told by its own settings in the message (the connects' solref).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from reports.regression import baseline_record as br
from reports.regression import baseline_store as bs
from reports.regression.baseline_free import free_request
from reports.regression.run_cache import cached_runner
from sim_models.engines.protocol import EngineRefusal
from sim_models.engines.settings import SettingsError
from tests.sim_models.own import user_models as um

pytest.importorskip("mujoco")

USER_TESTS = '''\
def test_six_bar_agrees(xval):
    xval.assert_agrees("models/six_bar.xml", engine="mujoco", tolerance=1e-3)


def test_six_bar_to_a_millionth(xval):  # deliberately too tight: MuJoCo sits near 5e-4
    xval.assert_agrees("models/six_bar.xml", engine="mujoco", tolerance=1e-6)


def test_simulator_four_bar_released(xval):
    xval.assert_free_agrees("models/major.xml", engine="mujoco", duration=2,
                            driver="crank_pin", keyframe="moving")


def test_no_drift(xval_baseline):  # one test per run of the baseline in pytest.ini
    xval_baseline()
'''


@pytest.fixture(scope="module")
def own_project(tmp_path_factory):
    """A user project: two MJCF models, a test file, a pytest.ini naming a baseline
    recorded here on the models (the six-bar driven, the simulator four-bar released
    from its keyframe), with the run requests the plugin makes by default."""
    root = tmp_path_factory.mktemp("own-project")
    (root / "models").mkdir()
    (root / "tests").mkdir()
    (root / "models" / "six_bar.xml").write_text(um.six_bar_xml())
    (root / "models" / "major.xml").write_text(um.major_four_bar_xml())
    (root / "tests" / "test_models.py").write_text(USER_TESTS)
    (root / "pytest.ini").write_text("[pytest]\nxval_baseline = tests/baseline.json\n")
    out = root / "tests" / "baseline.json"
    base = br.record([str(root / "models" / "six_bar.xml")], ["mujoco"], out,
                     runner=cached_runner)
    free = br.record([str(root / "models" / "major.xml")], ["mujoco"], out,
                     request=free_request(2.0), runner=cached_runner,
                     own_options={"driver": "crank_pin", "keyframe": "moving"})
    bs.save(br.merge(base, free)[0])
    return root


def _pytest(root: Path, *args: str) -> subprocess.CompletedProcess:
    e = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_")}
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider",
                           "-p", "no:randomly", *args], cwd=root, env=e,
                          capture_output=True, text=True, timeout=600)


@pytest.mark.slow
def test_user_project_on_its_own_models(own_project):
    """The driven and free assertions and the two baseline runs pass, the too-tight one
    fails naming the file, a quantity and the model's own settings; the baseline's runs
    are the assertions' runs (served from the session cache: 2 engine runs in all)."""
    p = _pytest(own_project, "-q")
    out = p.stdout
    print(out)
    assert p.returncode == 1, out + p.stderr
    assert re.search(r"1 failed, 4 passed", out), out
    msg = out[out.index("AssertionError: "):]
    assert msg.startswith("AssertionError: user-watt-six-bar (models/six_bar.xml) / "
                          "mujoco: "), msg
    assert "disagree with the analytic solution by more than 1e-06 of peak" in msg
    assert re.search(r"coupler\.alpha: error [\d.e-]+ of peak at input [\d.]+ deg", msg), msg
    assert "the user's model" in msg and "B.solref=(0.002,1)" in msg
    assert "xval: 2 engine runs" in out and "3 served from the session cache" in out


def test_baseline_on_a_model_fails_on_a_solref_change(own_project, xval, tmp_path):
    """In-process (``xval`` fixture): the baseline passes as recorded; with the six-bar's
    connects at MuJoCo's default solref it fails naming the parameter; the command
    that records the baseline again carries the free run's --driver and --keyframe."""
    (tmp_path / "models").mkdir()
    (tmp_path / "tests").mkdir()
    for name in ("six_bar.xml", "major.xml"):
        (tmp_path / "models" / name).write_text((own_project / "models" / name).read_text())
    base = tmp_path / "tests" / "baseline.json"
    doc = json.loads((own_project / "tests" / "baseline.json").read_text())
    base.write_text(json.dumps(doc))
    xval.assert_baseline(base)
    six = tmp_path / "models" / "six_bar.xml"
    six.write_text(six.read_text().replace('solref="0.002 1"', 'solref="0.02 1"'))
    with pytest.raises(AssertionError) as e:
        xval.assert_baseline(base)
    text = str(e.value)
    assert 'mjcf.B.solref "(0.002,1)" -> "(0.02,1)"' in text, text
    assert "xval baseline record " in text and "models/six_bar.xml --engine mujoco" in text
    again = br.record_command(bs.load(base), tmp_path)
    assert "--free --duration 2 --samples 201" in again
    assert "models/major.xml --engine mujoco --driver crank_pin --keyframe moving" in again


@pytest.mark.parametrize("call, kind, words", [
    (lambda x, m: x.assert_agrees(m, revolutions=0), SettingsError, "revolutions=0"),
    (lambda x, m: x.assert_agrees(m, samples=1), SettingsError, "samples=1"),
    (lambda x, m: x.assert_agrees(m, settings={"timestep": 1e-4}), SettingsError,
     "runs with its own options"),
    (lambda x, m: x.assert_agrees(m, engine="pybullet"), EngineRefusal, "MuJoCo only"),
    # the free door fails the asking test in one line (xval: error: ...), as for a file
    (lambda x, m: x.assert_free_agrees(m, duration=0.0), pytest.fail.Exception,
     "xval: error: free run duration=0.0"),
    (lambda x, m: x.assert_free_agrees(m, samples=10**7), pytest.fail.Exception,
     "xval: error: free run samples="),
])
def test_the_command_lines_ranges(own_project, xval, call, kind, words):
    """The same ranges as the command line, one line each, before any run."""
    before = xval.runs.stats["runs"]
    with pytest.raises(kind, match=re.escape(words)) as e:
        call(xval, str(own_project / "models" / "six_bar.xml"))
    assert "\n" not in str(e.value)
    assert xval.runs.stats["runs"] == before


@pytest.mark.slow
def test_a_urdf_with_its_closure_in_pybullet(tmp_path, xval):
    """``xval.assert_agrees("four_bar.urdf", engine="pybullet", driver=, close=)``: PyBullet
    loads the file, the loop closed at the given link points, within 1e-3 of peak (measured
    worst 5.8e-6 over the default run, tests/reports/test_own_compare_cli.py); its free
    run is refused in one line (not built for PyBullet)."""
    p = tmp_path / "four_bar.urdf"
    p.write_text(um.four_bar_urdf("xz"))
    close = [("coupler", (um.B_LEN, 0.0, 0.0), "rocker", (um.C_LEN, 0.0, 0.0))]
    comps = xval.assert_agrees(p, engine="pybullet", driver="O2", close=close,
                               revolutions=1)
    assert {c.quantity for c in comps} >= {"close_coupler_rocker.force", "rocker.alpha"}
    with pytest.raises(pytest.fail.Exception, match="runs in MuJoCo only"):
        xval.assert_free_agrees(p, engine="pybullet", driver="O2", close=close)


def test_free_assertion_failure_names_the_file_quantities_and_settings(tmp_path, xval):
    """The XZ URDF four-bar released in MuJoCo with its URDF reader's options (Euler at
    2 ms, the default connect; the loop opens): the free assertion fails, naming the
    quantities over their tolerance, the trusted horizon and the model's own settings."""
    p = tmp_path / "four_bar.urdf"
    p.write_text(um.four_bar_urdf("xz"))
    close = [("coupler", (um.B_LEN, 0.0, 0.0), "rocker", (um.C_LEN, 0.0, 0.0))]
    with pytest.raises(AssertionError) as e:
        xval.assert_free_agrees(p, engine="mujoco", driver="O2", close=close)
    text = str(e.value)
    assert text.startswith("urdf-four-bar / mujoco: free motion over 1 s disagrees "
                           "(trusted horizon "), text
    assert re.search(r"rocker\.theta", text) and "integrator=EULER" in text, text
