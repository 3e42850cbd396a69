"""The committed model files: up to date with the description, and loadable as files."""

from __future__ import annotations

import json

import numpy as np
import pytest

from analytic import case_names
from sim_models.models import MODELS_DIR, model_texts


@pytest.mark.parametrize("case", case_names())
def test_committed_models_are_not_stale(case):
    for name, text in model_texts(case).items():
        path = MODELS_DIR / name
        assert path.is_file(), f"{path} missing: run `xval models`"
        assert path.read_text() == text, f"{path} is stale: run `xval models`"


@pytest.mark.parametrize("case", case_names())
def test_mjcf_file_loads_and_steps_without_warnings(case):
    mujoco = pytest.importorskip("mujoco")
    msgs = []
    mujoco.set_mju_user_warning(msgs.append)
    try:
        m = mujoco.MjModel.from_xml_path(str(MODELS_DIR / f"{case}.xml"))
        d = mujoco.MjData(m)
        for _ in range(50):
            mujoco.mj_step(m, d)
    finally:
        mujoco.set_mju_user_warning(None)
    assert not msgs, msgs
    assert all(w.number == 0 for w in d.warning), [w.number for w in d.warning]
    assert np.all(np.isfinite(d.qacc))
    assert m.ngeom > 0 and m.neq >= 1  # a viewer sees the links; loops are closed


@pytest.mark.parametrize("case", case_names())
def test_urdf_file_loads_with_its_closures(case):
    p = pytest.importorskip("pybullet")
    cid = p.connect(p.DIRECT)
    try:
        body = p.loadURDF(str(MODELS_DIR / f"{case}.urdf"), useFixedBase=True,
                          flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=cid)
        links = {p.getJointInfo(body, j, physicsClientId=cid)[12].decode(): j
                 for j in range(p.getNumJoints(body, physicsClientId=cid))}
        closures = json.loads((MODELS_DIR / f"{case}.closures.json").read_text())
        assert closures, "every built-in case has at least one loop"
        for c in closures:
            cons = p.createConstraint(body, links[c["parent_link"]], body,
                                      links[c["child_link"]], p.JOINT_POINT2POINT, [0, 0, 0],
                                      c["parent_pivot"], c["child_pivot"], physicsClientId=cid)
            assert cons >= 0
        # no collision shapes anywhere (scene economy)
        for j in [-1, *links.values()]:
            assert p.getCollisionShapeData(body, j, physicsClientId=cid) == ()
    finally:
        p.disconnect(cid)
