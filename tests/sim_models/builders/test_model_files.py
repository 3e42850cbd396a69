"""The committed model files: up to date with the description, and loadable as files."""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from dataclasses import fields, is_dataclass, replace

import numpy as np
import pytest

from analytic import case_names, load_case
from sim_models.builders.model_files import MODELS_DIR, mechanism_model_texts, model_texts

#: Two model texts whose numbers all agree to this fraction of the mechanism's size (or
#: rad, or relative for a mass) differ in round-off only: far below the 1e-12 the files
#: are written to (:mod:`sim_models.builders.model_numbers`), far above float64 noise.
ROUND_OFF_ONLY = 1e-9

_NUMBER = re.compile(r"-?\d+\.?\d*(?:[eE][-+]?\d+)?")


def _first_difference(committed: str, generated: str) -> str:
    """Where two model texts differ, and whether it is a real change or round-off."""
    for n, (a, b) in enumerate(zip(committed.splitlines(), generated.splitlines(),
                                   strict=False), 1):
        if a == b:
            continue
        na, nb = _NUMBER.findall(a), _NUMBER.findall(b)
        same_shape = _NUMBER.sub("#", a) == _NUMBER.sub("#", b) and len(na) == len(nb)
        if same_shape and all(abs(float(x) - float(y)) <= ROUND_OFF_ONLY * max(1.0, abs(float(x)))
                              for x, y in zip(na, nb, strict=True)):
            return (f"line {n} differs in round-off only ({a.strip()!r} vs {b.strip()!r}): "
                    "the writer is not deterministic on this machine; this is a bug in "
                    "sim_models.builders.model_numbers, do not regenerate")
        return f"line {n}: committed {a.strip()!r}, generated {b.strip()!r}: run `xval models`"
    return "the files differ in length: run `xval models`"


@pytest.mark.parametrize("case", case_names())
def test_committed_models_are_not_stale(case):
    for name, text in model_texts(case).items():
        path = MODELS_DIR / name
        assert path.is_file(), f"{path} missing: run `xval models`"
        committed = path.read_text()
        assert committed == text, f"{path}: {_first_difference(committed, text)}"


def _jitter(obj, rng, rel):
    """``obj`` (a description dataclass, or a value inside one) with every float
    multiplied by ``1 + u rel``, u uniform in [-1, 1]: round-off of another machine."""
    if isinstance(obj, bool) or obj is None or isinstance(obj, str | int):
        return obj
    if isinstance(obj, float):
        return obj * (1.0 + rel * rng.uniform(-1.0, 1.0))
    if isinstance(obj, tuple):
        return tuple(_jitter(x, rng, rel) for x in obj)
    if isinstance(obj, Mapping):
        return {k: _jitter(v, rng, rel) for k, v in obj.items()}
    if is_dataclass(obj):
        return replace(obj, **{f.name: _jitter(getattr(obj, f.name), rng, rel)
                               for f in fields(obj) if f.init})
    return obj


#: The noise injected: a few units of float64 round-off, what another BLAS or CPU leaves.
INPUT_NOISE = 1e-15


@pytest.mark.parametrize("case", case_names())
def test_models_are_the_same_bytes_under_round_off_noise(case):
    """The committed files come out again, byte for byte, from inputs perturbed by
    relative 1e-15 (three seeds): what a machine whose kernels round differently
    computes.  Fails on writers that print every bit (``repr``)."""
    mech = load_case(case)
    for seed in range(3):
        noisy = _jitter(mech, np.random.default_rng(seed), INPUT_NOISE)
        assert noisy != mech
        for name, text in mechanism_model_texts(noisy, case).items():
            committed = (MODELS_DIR / name).read_text()
            assert text == committed, f"{name}, seed {seed}: {_first_difference(committed, text)}"


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


@pytest.mark.parametrize("case", case_names())
def test_pybullet_keeps_every_links_inertia(case):
    """PyBullet replaces an inertia tensor that breaks the triangle inequality
    (izz > ixx + iyy, even by one rounding) with zero, printing only a warning.  Every
    link of every committed URDF must load with the inertia it was written with: the
    lamina's izz = ixx + iyy, from the description (I about the centre of mass)."""
    p = pytest.importorskip("pybullet")
    mech = load_case(case)
    inertia = {b.name: b.inertia for b in mech.bodies if b.inertia}
    cid = p.connect(p.DIRECT)
    try:
        body = p.loadURDF(str(MODELS_DIR / f"{case}.urdf"), useFixedBase=True,
                          flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=cid)
        for j in range(p.getNumJoints(body, physicsClientId=cid)):
            name = p.getJointInfo(body, j, physicsClientId=cid)[12].decode()
            ixx, iyy, izz = p.getDynamicsInfo(body, j, physicsClientId=cid)[2]
            assert izz > 0 and ixx + iyy >= izz, (name, ixx, iyy, izz)
            if name in inertia:
                assert izz == pytest.approx(inertia[name], rel=1e-11), name
    finally:
        p.disconnect(cid)
