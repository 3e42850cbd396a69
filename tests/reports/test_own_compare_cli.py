"""``xval compare MODEL.xml --engine mujoco``: a hand-written MJCF four-bar run by MuJoCo
with its own options, driven along the imported description, judged and diagnosed."""

from __future__ import annotations

import json

import pytest

from tests.sim_models.own import user_models as um

from .cli_run import run

pytest.importorskip("mujoco")


def _model(tmp_path, text: str) -> str:
    p = tmp_path / "user.xml"
    p.write_text(text)
    return str(p)


def test_stiff_connect_passes_with_its_own_settings(tmp_path):
    path = _model(tmp_path, um.four_bar_xml(stiff=True))
    code, out = run("compare", path, "--engine", "mujoco")
    assert code == 0, out
    assert ": PASS" in out
    # the verdict names the file and the settings it ran with
    assert f"model file: {path}" in out and "settings: the user's model" in out
    assert "close.solref=(0.002,1)" in out
    assert "integrator=RK4" in out and "timestep=0.0005" in out
    assert "diagnosis: loop closure at the model's pose (qpos0): connect 'close' 0 mm" in out


def test_default_connect_fails_and_says_why(tmp_path):
    """MuJoCo's default connect (solref 0.02 s, solimp 0.9-0.95) lets the loop open
    by ~0.2 mm under gravity: the pin forces and the coupler's alpha miss by > 1e-3 of
    peak, status 1, and the diagnosis names the loop's opening."""
    path = _model(tmp_path, um.four_bar_xml())
    code, out = run("compare", path, "--engine", "mujoco")
    assert code == 1, out
    assert ": FAIL" in out and "close.solref=(0.02,1)" in out
    assert "diagnosis: engine: the loops opened by up to 0.2" in out


def test_json_names_file_and_diagnosis(tmp_path):
    path = _model(tmp_path, um.slider_crank_xml())
    code, out = run("compare", path, "--engine", "mujoco", "--json")
    obj = json.loads(out)[0]
    assert obj["file"] == path and obj["engine"] == "mujoco"
    # MuJoCo's default connect lets the gudgeon pin open by 0.43 mm at once under the
    # rod's weight: beyond the divergence limit (1e-3 of the size), the run stops there
    assert code == 1 and obj["verdict"] == "fail"
    assert any("the run stopped: loop violation" in x for x in obj["diagnosis"])


@pytest.mark.parametrize("args, words", [
    (["--engine", "pybullet"], "runs in MuJoCo only"),
    (["--engine", "mujoco", "--set", "integrator=Euler"], "its own options"),
])
def test_refusals(tmp_path, capsys, args, words):
    path = _model(tmp_path, um.four_bar_xml())
    code, _ = run("compare", path, *args)
    assert code == 2 and words in capsys.readouterr().err


def test_a_limit_reached_during_the_motion_is_named(tmp_path):
    """A limit of +-5 deg on the rocker's joint, which swings further in a revolution: the
    diagnosis names the limit as a modelling defect acting during the motion (and the
    header of the import lists it as not modelled)."""
    xml = um.four_bar_xml(stiff=True).replace(
        '<joint name="O4"', '<joint name="O4" limited="true" range="-5 5"')
    path = _model(tmp_path, xml)
    code, out = run("compare", path, "--engine", "mujoco", "--revolutions", "1")
    assert code == 1
    assert "diagnosis: modelling: limit of joint 'O4' acted during the motion" in out
    assert "diagnosis: not modelled: limits on joints ['O4']" in out


def test_urdf_with_close_runs_in_mujoco(tmp_path, capsys):
    """A URDF four-bar closed by --close, run by MuJoCo with the options its URDF reader
    gives (0.002 s, Euler, the default connect): a verdict naming the file and those
    settings; released at rest with no in-plane force it is refused (nothing moves)."""
    p = tmp_path / "four_bar.urdf"
    p.write_text(um.four_bar_urdf())
    close = "coupler:0.3,0,0=rocker:0.25,0,0"
    code, out = run("compare", str(p), "--engine", "mujoco", "--driver", "O2",
                    "--close", close)
    assert code in (0, 1) and f"model file: {p}" in out and "the user's model" in out
    assert "integrator=EULER" in out and "close_coupler_rocker.solref=(0.02,1)" in out
    code, _ = run("simulate", str(p), "--engine", "mujoco", "--driver", "O2", "--close",
                  close)
    assert code == 2 and "does not move" in capsys.readouterr().err


@pytest.mark.slow
def test_urdf_with_close_runs_in_pybullet(tmp_path):
    """PyBullet loads the user's URDF itself (the XZ-plane four-bar: gravity in its
    plane), the loop closed at the --close points by a point-to-point constraint, driven
    by a velocity motor as the harness drives its own URDF models: every angular
    acceleration, the drive effort and every pin force within 1e-3 of peak over the
    default run (measured worst 5.8e-6, rocker.alpha, at the harness's PyBullet dt 3e-5 s);
    the verdict names the file, and no importer warning reaches the output."""
    p = tmp_path / "four_bar.urdf"
    p.write_text(um.four_bar_urdf("xz"))
    code, out = run("compare", str(p), "--engine", "pybullet", "--driver", "O2", "--close",
                    "coupler:0.3,0,0=rocker:0.25,0,0", "--json")
    obj = json.loads(out)[0]
    assert code == 0 and obj["engine"] == "pybullet" and obj["file"] == str(p), out
    worst = {c["quantity"]: c["normalised"] for c in obj["comparisons"]}
    assert {"close_coupler_rocker.force", "O4.force", "drive.effort"} <= set(worst)
    assert max(worst.values()) < 1e-3, worst
    assert "b3Warning" not in out
