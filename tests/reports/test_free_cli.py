"""``xval simulate --engine``: status 0 on a passing verdict, 1 on a failing one, 2 with one
line on bad input; --json, --junit and --summary carry the verdict.

The failing run is MuJoCo's semi-implicit Euler at 0.02 s on IFToMM A01 (the pendulum
from the horizontal, 2 s): a first-order method at 0.089 rad per step is off by more
than 1 % of the swing (the test expects the failure, not a number)."""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET

import pytest

from tests.reports.cli_run import run

A01 = ("simulate", "iftomm-a01-pendulum", "--duration", "1", "--samples", "51")


@pytest.fixture(autouse=True)
def _headless(monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "disable")


def test_passing_verdict_status_0_and_json():
    code, out = run(*A01, "--engine", "mujoco", "--json")
    assert code == 0
    doc = json.loads(out)
    (v,) = doc["verdicts"]
    assert v["engine"] == "mujoco" and v["verdict"] == "pass"
    assert v["trusted_horizon_s"] is None  # never exceeded: JSON has no infinity
    assert v["iftomm"]["level"] == "1e-3"
    assert {c["quantity"] for c in v["comparisons"]} >= {"O.x", "link.theta", "energy"}


def test_failing_verdict_status_1_with_junit_and_summary(tmp_path):
    junit, summary = tmp_path / "j.xml", tmp_path / "s.md"
    code, out = run("simulate", "iftomm-a01-pendulum", "--duration", "2", "--samples", "101",
                    "--engine", "mujoco", "--integrator", "Euler", "--timestep", "0.02",
                    "--junit", str(junit), "--summary", str(summary))
    assert code == 1
    assert "FAIL" in out and "trusted horizon:" in out and "--timestep 0.005" in out
    root = ET.parse(junit).getroot()
    assert root.get("failures") == "1"
    tc = root.find(".//testcase")
    assert tc.get("classname") == "xval.simulate.mujoco"
    assert tc.find("failure") is not None
    assert "FAIL" in summary.read_text() and "error / scale" in summary.read_text()
    from tests.reports.test_baseline import _validate_junit  # the Jenkins xunit schema
    _validate_junit(junit, tests=1, failures=1)


@pytest.mark.parametrize(("args", "words"), [
    (("--set", "integrator=RK4"), "--engine"),
    (("--engine", "mujoco", "--set", "nope=1"), "'nope'"),
    (("--engine", "mujoco", "--set", "mujoco.timestep=-1"), "timestep"),
    (("--engine", "mujoco", "--timestep", "5"), "--timestep"),
    (("--engine", "mujoco", "--integrator", "RK4", "--set", "mujoco.integrator=Euler"),
     "give one"),
    (("--engine", "nosuch"), "--engine"),
])
def test_bad_input_one_line_status_2(capsys, args, words):
    code, out = run(*A01, *args)
    err = capsys.readouterr().err
    assert code == 2, out
    assert err.startswith("xval: error:") and err.count("\n") == 1
    assert words in err


def test_text_verdict_fits_80_columns_and_a_pendulum_has_no_loop_row(monkeypatch):
    """The pendulum has no loop: its text verdict says so, with no ``loop.gap`` row of 0
    (a gap that was never measured); every line fits an 80-column terminal."""
    monkeypatch.setenv("COLUMNS", "80")
    code, out = run(*A01, "--engine", "mujoco")
    assert code == 0
    assert "loop-closure drift: none, the mechanism has no loop" in out
    assert "loop.gap" not in out
    assert max(len(line) for line in out.splitlines()) <= 80


def test_the_wall_limit_reaches_the_run(monkeypatch):
    """``--wall-limit``: an engine run past it ends as a result that says so (a failed
    verdict, status 1), not an error.  (The limit bounds the exact integration too, see
    below; here the exact side runs unbounded so that the engine's path is tested.)"""
    import reports.cli.simulate as sim
    real = sim.simulate
    monkeypatch.setattr(sim, "simulate", lambda mech, duration, wall_limit=None, **kw:
                        real(mech, duration))
    code, out = run("simulate", "iftomm-a01-pendulum", "--engine", "mujoco", "--duration",
                    "0.5", "--wall-limit", "1e-9", "--json")
    assert code == 1, out
    data = json.loads(out)
    text = json.dumps(data)
    assert "wall-clock limit 1e-09 s reached" in text, text[:2000]


def test_the_wall_limit_bounds_the_exact_integration(capsys):
    """Before: ``--wall-limit`` needed ``--engine`` and the exact integration of 10,000 s
    ran for hours; now one line naming the limit and how far it got, status 2."""
    code, out = run("simulate", "iftomm-a01-pendulum", "--duration", "10000",
                    "--wall-limit", "0.5")
    err = capsys.readouterr().err
    assert code == 2, out
    assert re.search(r"the exact integration reached the wall-clock limit of 0\.5 s at "
                     r"t = \S+ s of 10000 s", err), err


def test_simulate_json_reports_the_switch_self_check():
    code, out = run("simulate", "tests/data/bugs/turn4/F7b_rate_50_limit_overshoot.toml",
                    "--json", "--samples", "3")
    assert code == 0
    chk = json.loads(out)["switch_check"]
    assert chk["switches_checked"] == 3 and chk["defect"] < 1e-10
