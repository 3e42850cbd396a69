"""MuJoCo behind the engine protocol (:class:`MujocoSession`, :class:`MujocoSettings`).

Model: :func:`sim_models.builders.mjcf.build_mjcf` (typed ``MjSpec`` calls), the scene variant of
``settings.scene`` (:mod:`sim_models.engines.mujoco.scene`), compiled with the inverse weights
scaled by ``settings.invweight_scale``.

Quirks kept here
----------------
* **Drive by armature**: the driven joint carries a huge ``armature`` A and
  ``qfrc_applied = A a_prescribed``; the driver then follows its prescribed acceleration to
  O(1/A), and the effort the driver exerts is ``A (a_prescribed - qacc)``.
* **Samples by ``mj_forward``**: under RK4, ``qacc`` after ``mj_step`` is not the
  acceleration at the state before the step, so every sample is a ``mj_forward`` at the
  state at the sample time (then ``mj_rnePostConstraint`` for ``cfrc_int``).
* **Forces**: a tree joint's force is ``cfrc_int`` of its child (the wrench by the parent
  on the child's subtree, about the subtree's centre of mass); a loop-closing joint's is
  the ``connect`` equality's ``efc_force`` (by body_a on body_b by construction).
* **Warnings** go to :attr:`Session.notes`, never to stderr or ``MUJOCO_LOG.TXT``.
"""

from __future__ import annotations

import math

import numpy as np

from ...builders.mjcf import SCENES, MujocoSettings, build_mjcf, compile_spec, require_mujoco
from ...builders.tree import SimTree
from ..protocol import HUGE, Recorder, Session, check_raw_state
from .scene import apply_scene


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


class MujocoSession(Session):
    """A compiled MuJoCo model of one linkage, driven through its prescribed motion."""

    name = "mujoco"
    settings_class = MujocoSettings
    engine_readings = False

    def __init__(self, tree: SimTree, settings: MujocoSettings | None = None):
        super().__init__(tree, settings)
        mujoco = require_mujoco()
        self.mj = mujoco
        self._old_warning = mujoco.get_mju_user_warning()
        mujoco.set_mju_user_warning(self._warn)  # no stderr noise, no MUJOCO_LOG.TXT
        try:
            self._build()
        except Exception:
            self.close()
            raise

    def _warn(self, msg: str) -> None:
        self.notes.append(f"MuJoCo warning: {msg.strip()}")

    def _build(self) -> None:
        st, s = self.tree, self.mujoco_settings()
        spec = build_mjcf(st.mech, s, tree=st)
        apply_scene(spec, st, s.scene)
        # the prescribed driver acceleration is constant (SimTree.driver_path)
        self._compile(spec, s, acc=float(st.mech.driver.acceleration), armature=float(s.armature))

    def _compile(self, spec, s: MujocoSettings, acc: float, armature: float) -> None:
        """Compile ``spec`` and index the model in the compiled linkage's terms (the tree
        joints' addresses, the bodies, the loop equalities, each tree joint's child and
        its subtree's root, the loads): what the driven and the released sessions share.
        ``acc``: the driver's prescribed acceleration; ``armature``: the drive's (both 0
        when released: :meth:`convert`'s drive effort is then 0)."""
        mujoco, st = self.mj, self.tree
        # a model MuJoCo's compiler rejects: EngineRefusal, one line (mjcf.compile_refusal)
        self.model, warnings = compile_spec(spec, s, st.mech)
        self.notes.extend(warnings)
        m = self.model
        self.data = mujoco.MjData(m)
        self.qadr = np.array([m.joint(tj.name).qposadr[0] for tj in st.joints])
        self.dadr = np.array([m.joint(tj.name).dofadr[0] for tj in st.joints])
        self.bid = {b: (0 if b == st.ground else m.body(name).id)
                    for b, name in enumerate(st.body_names)}
        self.eq = [m.equality(ch.name).id for ch in st.chords]
        self.drive_dof = int(self.dadr[st.driver_tree])
        # each tree joint's child body and the root of its kinematic subtree (readout)
        self.child_bid = np.array([self.bid[tj.child] for tj in st.joints], dtype=int)
        self.child_root = np.array([m.body_rootid[b] for b in self.child_bid], dtype=int)
        self.acc = acc
        # enum values as ints: comparing an array with the enum object costs 35 us
        self._equality = int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)
        self._badqacc = int(mujoco.mjtWarning.mjWARN_BADQACC)
        self.A = armature
        self.loads = [(self.bid[st.body_names.index(ld.body)], ld) for ld in st.mech.loads]
        self.moving_loads = self._loads_move()
        self.max_contacts = 0  # most contacts seen at a sample (scene-economy study)

    def mujoco_settings(self) -> MujocoSettings:
        """The :class:`MujocoSettings` the host model is built with (a session of the same
        model in another runtime, e.g. MuJoCo Warp, maps its own settings to these)."""
        return self.settings

    def close(self) -> None:
        if getattr(self, "_old_warning", False) is not False:
            self.mj.set_mju_user_warning(self._old_warning)
            self._old_warning = False

    def extra(self) -> dict:
        return {"scene": self.settings.scene, "ngeom": int(self.model.ngeom),
                "max_contacts": self.max_contacts}

    # -- state and drive ----------------------------------------------------------
    def set_state(self, q, qd) -> None:
        self.data.qpos[self.qadr] = q
        self.data.qvel[self.dadr] = qd

    def set_drive(self, a_prescribed: float) -> None:
        self.data.qfrc_applied[self.drive_dof] = self.A * self.tree.driver_sigma * a_prescribed

    def apply_loads(self, d=None) -> None:
        """``xfrc_applied`` of the loads from the pose in ``d`` (default ``self.data``;
        any object with MjData's ``xipos, xpos, xmat, xfrc_applied`` arrays)."""
        d = self.data if d is None else d
        if not self.loads:
            return
        d.xfrc_applied[:] = 0.0
        for bid, ld in self.loads:
            F = np.array([ld.force[0], ld.force[1], 0.0])
            c = d.xipos[bid]
            if ld.point is not None:
                b = self.tree.body_names.index(ld.body)
                p = self.tree.mech.bodies[b].points[ld.point]
                P = d.xpos[bid] + d.xmat[bid].reshape(3, 3) @ np.array([p[0], p[1], 0.0])
            else:
                P = c
            d.xfrc_applied[bid, :3] = F
            d.xfrc_applied[bid, 3:] = np.cross(P - c, F) + np.array([0, 0, ld.torque])

    def _loads_move(self) -> bool:
        """True when a load's moment about its body's centre of mass changes with the pose."""
        st = self.tree
        for _, ld in self.loads:
            b = st.body_names.index(ld.body)
            if ld.point is None or np.allclose(st.mech.bodies[b].points[ld.point], st.com[b]):
                continue
            return True
        return False

    def state(self):
        return self.data.qpos[self.qadr].copy(), self.data.qvel[self.dadr].copy()

    # -- the protocol -------------------------------------------------------------
    def reset(self, t: float, h: float) -> None:
        mj, m, d = self.mj, self.model, self.data
        mj.mj_resetData(m, d)
        q, qd, (_, _, acc) = self.analytic_state(t)
        self.set_state(q, qd)
        # the prescribed driver acceleration is constant: qfrc_applied is set once
        self.set_drive(acc)
        mj.mj_kinematics(m, d)
        self.apply_loads()
        m.opt.timestep = h
        mj.mj_forward(m, d)

    def advance(self, t: float, h: float, n: int) -> str | None:
        mj, m, d = self.mj, self.model, self.data
        m.opt.timestep = h
        step = mj.mj_step
        qvel, qacc = d.qvel, d.qacc
        moving = self.moving_loads
        for _ in range(n):
            if moving:
                self.apply_loads()
            step(m, d)
        if not (abs(qvel.sum()) < HUGE and abs(qacc.sum()) < HUGE):  # NaN, inf, huge
            return "non-finite or huge velocities (simulation diverged)"
        return None

    def record(self, t: float):
        """``mj_forward`` at the state at ``t`` (the RK4 quirk), then copies of the arrays
        the readout needs (:meth:`_raw`); MuJoCo's bad-qacc warning and a non-finite or
        huge state are reasons at once."""
        mj, m, d = self.mj, self.model, self.data
        self.set_drive(self.acc)
        self.apply_loads()
        mj.mj_forward(m, d)
        self.max_contacts = max(self.max_contacts, d.ncon)
        if d.warning[self._badqacc].number:
            return None, 0.0, "MuJoCo reported bad qacc (simulation diverged)"
        q, qd = d.qpos[self.qadr], d.qvel[self.dadr]
        # a cheap net (NaN fails both comparisons; |qd_i| > HUGE makes qd.qd > HUGE^2),
        # then the exact check and its message
        if not (math.isfinite(q.sum()) and qd @ qd <= HUGE * HUGE):
            why = check_raw_state(q, qd)
            if why is not None:
                return None, 0.0, why
        return self._raw(self.acc), 0.0, None

    def forward_at(self, q, qd, acceleration: float, rows, rec: Recorder) -> None:
        mj, m, d = self.mj, self.model, self.data
        self.set_state(q, qd)
        self.set_drive(acceleration)
        mj.mj_kinematics(m, d)
        self.apply_loads()
        mj.mj_forward(m, d)
        self.convert(np.zeros(1), [self._raw(acceleration)], [list(np.atleast_1d(rows))], rec)

    # -- readout ------------------------------------------------------------------
    def _raw(self, a_prescribed: float) -> tuple:
        """Copies of ``data``'s arrays the readout needs (after ``mj_forward`` and
        ``mj_rnePostConstraint``), whole (a copy is cheaper than an index): ``qpos,
        qvel, qacc, cfrc_int, subtree_com`` and the constraint rows' type, id and force,
        and the prescribed driver acceleration."""
        mj, m, d = self.mj, self.model, self.data
        mj.mj_rnePostConstraint(m, d)
        n = d.nefc
        return (d.qpos.copy(), d.qvel.copy(), d.qacc.copy(), d.cfrc_int.copy(),
                d.subtree_com.copy(), d.efc_type[:n].copy(), d.efc_id[:n].copy(),
                d.efc_force[:n].copy(), a_prescribed)

    def _loop_forces(self, efc_type, efc_id, efc_force) -> np.ndarray:
        """(K, n_chords, 2): each loop's ``connect`` force (by body_a on body_b by
        construction), from the first two of its equality rows, per record (one row
        lookup when every record has the same constraint rows, as it usually has)."""
        K, C = len(efc_force), len(self.eq)
        out = np.zeros((K, C, 2))
        if len({len(x) for x in efc_type}) == 1 and K:
            T, I = np.array(efc_type), np.array(efc_id)
            if np.all(T == T[0]) and np.all(I == I[0]):
                F = np.array(efc_force)
                eq_rows = np.flatnonzero(T[0] == self._equality)
                for c, e in enumerate(self.eq):
                    out[:, c] = F[:, eq_rows[I[0][eq_rows] == e][:2]]
                return out
        for k in range(K):
            eq_rows = np.flatnonzero(efc_type[k] == self._equality)
            for c, e in enumerate(self.eq):
                out[k, c] = efc_force[k][eq_rows[efc_id[k][eq_rows] == e][:2]]
        return out

    def drive_effort(self, qdd, acc, raws) -> np.ndarray:
        """(K,) the drive's effort on the mechanism along the driven tree dof (N m or N):
        ``A (a_prescribed - qacc)`` of the armature drive (exact in float64: qacc is
        resolved to 1e-16 of A's share)."""
        st = self.tree
        return self.A * (st.driver_sigma * acc - qdd[:, st.driver_tree])

    def convert(self, times, raws, rows, rec: Recorder):
        """The analytic conventions of K raw records (:meth:`_raw`), vectorised."""
        st, mech = self.tree, self.tree.mech
        qpos, qvel, qacc, cfrc, com, efc_type, efc_id, efc_force, acc = \
            zip(*(r[:9] for r in raws), strict=True)
        q, qd, qdd = (np.array(x)[:, a] for x, a in ((qpos, self.qadr), (qvel, self.dadr),
                                                      (qacc, self.dadr)))
        cfrc = np.array(cfrc)[:, self.child_bid]
        com = np.array(com)[:, self.child_root]
        loops = self._loop_forces(efc_type, efc_id, efc_force)
        acc = np.array(acc)
        prop, gap, rate = rec.put_motions(rows, times, q, qd, qdd)
        th, org = prop[0], prop[3]
        tau = self.drive_effort(qdd, acc, raws)
        K, J, P = len(raws), len(mech.joints), len(st.prismatic)
        force = np.zeros((K, J, 2))
        normal, moment = np.zeros((K, P)), np.zeros((K, P))
        # tree joints: cfrc_int of the child = wrench by the parent on the child's subtree
        for ti, tj in enumerate(st.joints):
            torque, f, c = cfrc[:, ti, :3], cfrc[:, ti, 3:], com[:, ti]
            k = tj.joint
            jt = mech.joints[k]
            if tj.kind == "hinge":
                force[:, k] = tj.sigma * f[:, :2]
                continue
            sb = st.body_names.index(jt.slider)
            Pw = st.point_world(th, org, sb, mech.bodies[sb].points[jt.point])
            mz = torque[:, 2] - _cross(Pw - c[:, :2], f[:, :2])
            F = tj.sigma * f[:, :2]
            ang = th[:, st.body_names.index(jt.guide)] + jt.direction
            p = st.prismatic.index(k)
            force[:, k] = F
            normal[:, p] = -F[:, 0] * np.sin(ang) + F[:, 1] * np.cos(ang)
            moment[:, p] = tj.sigma * mz
        for ci, ch in enumerate(st.chords):
            force[:, ch.joint] = loops[:, ci]
        rec.put_forces_many(rows, force, st.driver_sigma * tau, normal, moment)
        return gap, rate


__all__ = ["SCENES", "MujocoSession", "MujocoSettings"]
