"""``xval simulate MODEL.xml --engine mujoco``: hand-written MJCF models released in
MuJoCo with nothing added, from their own state, judged against the exact free motion of
their imported description."""

from __future__ import annotations

import json
import re

import pytest

from tests.sim_models.own import user_models as um

from .cli_run import run

pytest.importorskip("mujoco")


def _model(tmp_path, text: str) -> str:
    p = tmp_path / "user.xml"
    p.write_text(text)
    return str(p)


def test_stiff_four_bar_released_from_rest_passes(tmp_path):
    path = _model(tmp_path, um.four_bar_xml(stiff=True))
    code, out = run("simulate", path, "--duration", "2", "--engine", "mujoco")
    assert code == 0, out
    assert "released from its own state" in out and ": PASS" in out
    assert "trusted horizon: whole run (2 s)" in out
    drift = float(re.search(r"energy drift: max (\S+) of", out).group(1))
    assert drift < 1e-5  # measured 1.5e-7 (RK4 at the model's 0.5 ms)


def test_default_connect_four_bar_fails_with_its_loop_opening(tmp_path):
    path = _model(tmp_path, um.four_bar_xml())
    code, out = run("simulate", path, "--duration", "2", "--engine", "mujoco", "--json")
    obj = json.loads(out)
    assert code == 1 and obj["file"] == path
    assert any("loops opened by up to 0.6" in x for x in obj["diagnosis"])


def test_major_simulator_four_bar(tmp_path):
    """The simulator example (three 4 m, 20 kg links, ground pins 2 m apart, crank at
    atan(sqrt 15)) released with the crank at 1 rad/s under gravity, MuJoCo's default
    connect: a pass over 5 s with the energy drift and the horizon stated."""
    path = _model(tmp_path, um.major_four_bar_xml())
    code, out = run("simulate", path, "--driver", "crank_pin", "--keyframe", "moving",
                    "--duration", "5", "--engine", "mujoco")
    assert code == 0, out
    assert "trusted horizon: whole run (5 s)" in out
    drift = float(re.search(r"energy drift: max (\S+) of", out).group(1))
    assert drift < 1e-3  # measured 1.0e-4 of 5376 J


def test_without_engine_prints_the_exact_motion(tmp_path):
    path = _model(tmp_path, um.slider_crank_xml())
    code, out = run("simulate", path, "--duration", "0.5")
    assert code == 0 and "free motion, 0.5 s" in out and "work-energy balance" in out


def test_watt_six_bar_released_passes(tmp_path):
    """The two-loop six-bar, near-hard connects, released from rest at qpos0 under
    gravity: a pass over 2 s (measured worst 3.0e-3 of range, O6.xd), both loops' pins
    judged, energy drift 1.7e-6 (RK4 at the model's 0.5 ms)."""
    path = _model(tmp_path, um.six_bar_xml())
    code, out = run("simulate", path, "--duration", "2", "--engine", "mujoco")
    assert code == 0, out
    assert ": PASS" in out and "trusted horizon: whole run (2 s)" in out
    assert re.search(r"B\.force .* pass", out) and re.search(r"D\.force .* pass", out)
    drift = float(re.search(r"energy drift: max (\S+) of", out).group(1))
    assert drift < 1e-5


def test_urdf_released_in_pybullet_error_falls_with_the_step(tmp_path):
    """The XZ-plane URDF four-bar (closed by --close) released from rest under gravity in
    PyBullet, which loads the file itself: at the harness's free step 1e-4 s it fails
    (worst joint coordinate 3.5e-2 of range over 1 s) and the advice names a 4x smaller
    step; at 2.5e-5 s the error is 4x smaller (semi-implicit Euler is first order: the
    engine's step, not the model) and it passes."""
    p = tmp_path / "four_bar.urdf"
    p.write_text(um.four_bar_urdf("xz"))
    args = ["simulate", str(p), "--engine", "pybullet", "--driver", "O2", "--close",
            "coupler:0.3,0,0=rocker:0.25,0,0", "--duration", "1"]
    worst = {}
    for step in ("1e-4", "2.5e-5"):
        code, out = run(*args, "--timestep", step, "--json")
        obj = json.loads(out)
        v = obj["verdicts"][0]
        worst[step] = max(c["normalised"] for c in v["comparisons"]
                          if c["quantity"].endswith(".x"))
        assert code == (1 if step == "1e-4" else 0), out
    assert 3.0 < worst["1e-4"] / worst["2.5e-5"] < 5.0, worst
    code, out = run(*args)  # the advice wraps to the terminal (80 columns in xdist)
    assert code == 1 and "rerun with --timestep 2.5e-05" in " ".join(out.split())
