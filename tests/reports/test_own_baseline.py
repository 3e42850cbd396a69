"""``xval baseline record MODEL.xml --engine mujoco`` in a separate repository, checked
after reformatting the file (no failure) and after a ``solref`` change (the failure names
the constraint's parameter and the quantities that drifted)."""

from __future__ import annotations

import json

import pytest

from reports.regression import model_identity as mid
from sim_models.own import import_model
from tests.sim_models.own import user_models as um
from tests.sim_models.own.test_import_mjcf import PENDULUM_ELEMENTS

from .cli_run import run

pytest.importorskip("mujoco")


def test_identity_of_a_description_with_motors_is_json(tmp_path):
    """A description with [[dampers]], [[springs]] and [[motors]] has a content
    identity (before the fix: TypeError, a Motor is not JSON serializable)."""
    p = tmp_path / "p.xml"
    p.write_text(PENDULUM_ELEMENTS)
    mech = import_model(str(p), driver="pivot", keyframe="up").mechanism
    flat = mid.content(mech)
    motor = {k: v for k, v in flat.items() if k.startswith("motion.motors.")}
    assert motor == {"motion.motors.0.type": "motor", "motion.motors.0.joint": "pivot",
                     "motion.motors.0.effort": 0.5, "motion.motors.0.times": [],
                     "motion.motors.0.efforts": []}
    assert len(mid.digest(mech)) == 64 and json.dumps(flat)


def test_baseline_of_a_user_model(tmp_path, capsys, monkeypatch):
    repo = tmp_path / "gripper-repo"
    (repo / "ci").mkdir(parents=True)
    model = repo / "gripper.xml"
    text = um.four_bar_xml(stiff=True)
    model.write_text(text)
    monkeypatch.chdir(repo)
    code, out = run("baseline", "record", "gripper.xml", "--engine", "mujoco", "--out",
                    "ci/base.json")
    assert code == 0, out
    base = json.loads((repo / "ci" / "base.json").read_text())
    content = base["runs"][0]["model"]["content"]
    assert content["mjcf.close.solref"] == "(0.002,1)"
    # reformatted, commented: the parsed model is the same, no failure
    model.write_text("<!-- reformatted -->\n" + text.replace("  <", "    <")
                     .replace('<mujoco model="user-four-bar">',
                              '<mujoco  model="user-four-bar" >\n<!-- a comment -->'))
    code, out = run("baseline", "check", "ci/base.json")
    assert code == 0 and "result: PASS" in out, out
    # MuJoCo's default connect instead of the near-hard one
    model.write_text(text.replace('solref="0.002 1" solimp="0.9999 0.9999 0.001" ', ""))
    code, out = run("baseline", "check", "ci/base.json")
    assert code == 1
    assert 'mjcf.close.solref "(0.002,1)" -> "(0.02,1)"' in out
    assert "close.force: error" in out and "exceeds its tolerance" in out


@pytest.mark.slow
def test_free_baselines_of_user_models(tmp_path, capsys, monkeypatch):
    """``baseline record MODEL.xml --free``: the six-bar released from qpos0 and the
    simulator four-bar from its keyframe 'moving' (--driver, --keyframe kept in the
    model's identity); the check passes as recorded, and after a solref change of the
    six-bar names the parameter."""
    (tmp_path / "six.xml").write_text(um.six_bar_xml())
    (tmp_path / "major.xml").write_text(um.major_four_bar_xml())
    monkeypatch.chdir(tmp_path)
    code, out = run("baseline", "record", "six.xml", "--engine", "mujoco", "--free",
                    "--duration", "0.5", "--out", "base.json")
    assert code == 0 and "user-watt-six-bar / mujoco (free, 0.5 s)" in out, out
    code, out = run("baseline", "record", "major.xml", "--engine", "mujoco", "--free",
                    "--duration", "1", "--driver", "crank_pin", "--keyframe", "moving",
                    "--out", "base.json")
    assert code == 0 and "trusted horizon whole run" in out, out
    base = json.loads((tmp_path / "base.json").read_text())
    major = next(r for r in base["runs"] if r["case"] == "major-four-bar")
    assert major["model"]["content"]["own.keyframe"] == "moving"
    assert major["request"] == {"mode": "free", "duration": 1.0, "samples": 201}
    code, out = run("baseline", "check", "base.json")
    assert code == 0 and "result: PASS: 0 of 2 runs failed" in out, out
    six = tmp_path / "six.xml"
    six.write_text(six.read_text().replace('solref="0.002 1"', 'solref="0.02 1"'))
    code, out = run("baseline", "check", "base.json")
    assert code == 1 and 'mjcf.D.solref "(0.002,1)" -> "(0.02,1)"' in out, out
    assert "--driver crank_pin --keyframe moving" in out  # the command to record again


@pytest.mark.parametrize("args, words", [
    (["seed-four-bar", "--engine", "mujoco", "--driver", "O2"],
     "--driver applies to your own MJCF models"),
    (["six.xml", "--engine", "pybullet"], "runs in MuJoCo only"),
    (["six.xml", "--engine", "mujoco", "--free", "--duration", "0"], "--duration"),
])
def test_record_refusals(tmp_path, capsys, monkeypatch, args, words):
    (tmp_path / "six.xml").write_text(um.six_bar_xml())
    monkeypatch.chdir(tmp_path)
    code, _ = run("baseline", "record", *args, "--out", "b.json")
    err = capsys.readouterr().err
    assert code == 2 and words in err and err.count("\n") == 1, err
    assert not (tmp_path / "b.json").exists()
