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
    assert flat["motion.motors"] == [{"joint": "pivot", "effort": 0.5, "times": [],
                                      "efforts": []}]
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
