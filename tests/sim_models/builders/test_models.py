"""The generated MJCF and URDF: every built-in case builds, compiles/loads, and is lean."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from analytic import Linkage, Prismatic, case_names, load_case
from sim_models.builders.mjcf import (
    EngineVersionError,
    MujocoSettings,
    build_mjcf,
    compile_mjcf,
    require_mujoco,
)
from sim_models.builders.tree import MASS_FLOOR, SimTree
from sim_models.builders.urdf import build_urdf

mujoco = pytest.importorskip("mujoco")
CASES = case_names()


@pytest.mark.parametrize("case", CASES)
def test_tree_closes_loops_at_revolute_joints(case):
    mech = load_case(case)
    st = SimTree(mech)
    assert len(st.joints) == len(mech.bodies) - 1
    assert len(st.chords) == len(mech.joints) - len(mech.bodies) + 1
    for k in st.prismatic:  # every prismatic joint is a tree joint
        assert k in st.tree_joint_indices, mech.joints[k].name
    assert st.tree_joint_indices[0] == [j.name for j in mech.joints].index(mech.driver.joint)


@pytest.mark.parametrize("case", CASES)
def test_mjcf_compiles_without_warnings(case):
    mech = load_case(case)
    spec = build_mjcf(mech, MujocoSettings())
    assert isinstance(spec, mujoco.MjSpec)
    model, warnings = compile_mjcf(mech)
    assert warnings == []
    st = SimTree(mech)
    assert model.nbody == len(mech.bodies)          # world body = ground
    assert model.njnt == len(mech.bodies) - 1
    assert model.neq == len(st.chords)
    assert all(model.eq_type == mujoco.mjtEq.mjEQ_CONNECT)
    n_slide = sum(isinstance(j, Prismatic) for j in mech.joints)
    assert int(np.sum(model.jnt_type == mujoco.mjtJoint.mjJNT_SLIDE)) == n_slide


@pytest.mark.parametrize("case", CASES)
def test_mjcf_scene_economy(case):
    """No contacts or collision geometry, no actuators, gravity only when asked."""
    mech = load_case(case)
    model, _ = compile_mjcf(mech)
    assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
    assert model.npair == 0 and model.nexclude == 0 and model.nu == 0
    assert np.all(model.geom_contype == 0) and np.all(model.geom_conaffinity == 0)
    assert model.ngeom > 0  # the viewer shows the linkage
    np.testing.assert_array_equal(model.opt.gravity, [mech.gravity[0], mech.gravity[1], 0.0])
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert data.ncon == 0


@pytest.mark.parametrize("case", CASES)
def test_mjcf_reference_pose_at_qpos0(case):
    """qpos = 0 is the assembled reference configuration of the analytic solution."""
    mech = load_case(case)
    st = SimTree(mech)
    model, _ = compile_mjcf(mech)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    for b, name in enumerate(st.body_names):
        if b == st.ground:
            continue
        bid = model.body(name).id
        np.testing.assert_allclose(data.xpos[bid][:2], st.origin_ref[b], atol=1e-12)
        q = data.xquat[bid]
        ang = 2 * math.atan2(q[3], q[0])
        assert abs(math.remainder(ang - st.theta_ref[b], 2 * math.pi)) < 1e-12
    for ch in st.chords:  # loops closed
        s1 = model.site(f"{ch.name}@{st.body_names[ch.body_b]}").id
        s2 = model.site(f"{ch.name}@{st.body_names[ch.body_a]}").id
        assert np.linalg.norm(data.site_xpos[s1] - data.site_xpos[s2]) < 1e-12


def test_massless_body_gets_the_documented_floor():
    mech = load_case("seed-slider-crank")
    model, _ = compile_mjcf(mech)
    assert model.body("crank").mass[0] == pytest.approx(MASS_FLOOR * 3.0)
    assert model.body("rod").mass[0] == 3.0
    np.testing.assert_allclose(model.body("rod").inertia, [0.06, 0.06, 0.1])


def test_driver_has_the_armature_and_nothing_else_does():
    mech = load_case("seed-four-bar")
    model, _ = compile_mjcf(mech, MujocoSettings(armature=123.0))
    assert model.dof_armature[model.joint("O2").dofadr[0]] == 123.0
    assert np.count_nonzero(model.dof_armature) == 1


def test_old_mujoco_is_refused(monkeypatch):
    monkeypatch.setattr(mujoco, "__version__", "3.6.0")
    with pytest.raises(EngineVersionError, match="3.7"):
        require_mujoco()
    with pytest.raises(EngineVersionError):
        build_mjcf(load_case("seed-four-bar"))


# ------------------------------------------------------------------------------------ URDF
@pytest.mark.parametrize("case", CASES)
def test_urdf_structure(case):
    mech = load_case(case)
    text, closures = build_urdf(mech)
    root = ET.fromstring(text)
    links = [lk.get("name") for lk in root.findall("link")]
    joints = root.findall("joint")
    assert sorted(links) == sorted(b.name for b in mech.bodies)
    children = {j.find("child").get("link") for j in joints}
    assert set(links) - children == {mech.ground}       # the ground is the root
    assert root.find(".//collision") is None
    assert all(lk.find("inertial") is not None for lk in root.findall("link"))
    kinds = sorted(j.get("type") for j in joints)
    assert kinds == sorted("prismatic" if isinstance(mech.joint(j.get("name")), Prismatic)
                           else "continuous" for j in joints)
    assert len(closures) == len(mech.joints) - len(mech.bodies) + 1


@pytest.mark.parametrize("case", CASES)
def test_urdf_loads_in_pybullet_at_the_reference_pose(case):
    p = pytest.importorskip("pybullet")
    from sim_models.engines.pybullet.driven import PybulletSettings, PybulletSim
    mech = load_case(case)
    st = SimTree(mech)
    sim = PybulletSim(st, PybulletSettings())
    try:
        assert p.getNumJoints(sim.body, physicsClientId=sim.cid) == len(mech.bodies) - 1
        g = p.getPhysicsEngineParameters(physicsClientId=sim.cid)
        assert (g["gravityAccelerationX"], g["gravityAccelerationY"],
                g["gravityAccelerationZ"]) == (mech.gravity[0], mech.gravity[1], 0.0)
        for b, name in enumerate(st.body_names):  # centres of mass at q = 0
            if b == st.ground:
                continue
            pos = p.getLinkState(sim.body, sim.link[name], physicsClientId=sim.cid)[0]
            c = st.origin_ref[b] + np.array(
                [[math.cos(st.theta_ref[b]), -math.sin(st.theta_ref[b])],
                 [math.sin(st.theta_ref[b]), math.cos(st.theta_ref[b])]]) @ st.com[b]
            np.testing.assert_allclose(pos[:2], c, atol=1e-9)
            dyn = p.getDynamicsInfo(sim.body, sim.link[name], physicsClientId=sim.cid)
            assert dyn[0] == pytest.approx(st.mass[b])
            assert dyn[2][2] == pytest.approx(st.inertia[b])
    finally:
        sim.close()


def test_kinematics_only_case_gets_placeholder_masses():
    st = SimTree(load_case("hibbeler-16-31"))
    assert not st.has_mass
    assert all(m == 1.0 for i, m in enumerate(st.mass) if i != st.ground)


def test_tree_coordinates_round_trip():
    """Tree coordinates of the analytic solution reproduce its poses, rates, accelerations."""
    for case in ("quick-return", "inverted-slider-crank", "six-bar"):
        st = SimTree(load_case(case))
        kin = Linkage(st.mech).kinematics(st.mech.driver.value + np.linspace(0, 6, 13))
        th, om, al, org, v, a = st.propagate(*st.coords(kin))
        np.testing.assert_allclose(np.cos(th - kin.theta), 1.0, atol=1e-12)
        np.testing.assert_allclose(al, kin.alpha, atol=1e-9 * np.abs(kin.alpha).max())
        np.testing.assert_allclose(a, kin.a_origin, atol=1e-9 * np.abs(kin.a_origin).max())
