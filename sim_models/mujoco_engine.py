"""MuJoCo behind the engine protocol (:class:`MujocoSession`, :class:`MujocoSettings`).

Model: :func:`sim_models.mjcf.build_mjcf` (typed ``MjSpec`` calls), the scene variant of
``settings.scene`` (:mod:`sim_models.mujoco_scene`), compiled with the inverse weights
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

from .engine_base import HUGE, EngineRefusal, Recorder, Session
from .mjcf import SCENES, MujocoSettings, build_mjcf, compile_spec, require_mujoco
from .mujoco_scene import apply_scene
from .tree import SimTree


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
        mujoco, st, s = self.mj, self.tree, self.settings
        spec = build_mjcf(st.mech, s, tree=st)
        apply_scene(spec, st, s.scene)
        try:
            self.model, warnings = compile_spec(spec, s)
        except ValueError as e:  # MuJoCo's compiler refuses the model: one line, typed
            reason = str(e).replace("Error:", "").split("\n")[0].strip()
            size = max((math.dist(p, q) for b in st.mech.bodies for p in b.points.values()
                        for q in b.points.values()), default=0.0)
            # measured: the seed four-bar compiles scaled to a 1e-6 m crank, not to 1e-7 m
            raise EngineRefusal(f"mechanism {st.mech.name!r} (size {size:.3g} m): MuJoCo cannot "
                                f"compile its model ({reason}); its compiler rejects the "
                                "geometry of links shorter than about 1e-6 m") from None
        self.notes.extend(warnings)
        m = self.model
        self.data = mujoco.MjData(m)
        self.qadr = np.array([m.joint(tj.name).qposadr[0] for tj in st.joints])
        self.dadr = np.array([m.joint(tj.name).dofadr[0] for tj in st.joints])
        self.bid = {b: (0 if b == st.ground else m.body(name).id)
                    for b, name in enumerate(st.body_names)}
        self.eq = [m.equality(ch.name).id for ch in st.chords]
        self.drive_dof = int(self.dadr[st.driver_tree])
        self.A = float(s.armature)
        self.loads = [(self.bid[st.body_names.index(ld.body)], ld) for ld in st.mech.loads]
        self.moving_loads = self._loads_move()
        self.max_contacts = 0  # most contacts seen at a sample (scene-economy study)

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

    def apply_loads(self) -> None:
        d = self.data
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

    def sample(self, t: float, rows, rec: Recorder) -> float:
        _, _, acc = self.tree.driver_path(t)
        self.set_drive(float(acc))
        self.apply_loads()
        self.mj.mj_forward(self.model, self.data)
        self.max_contacts = max(self.max_contacts, int(self.data.ncon))
        if len(rows):
            self._readout(rows, t, float(acc), rec)
        return 0.0

    def divergence(self, t: float) -> str | None:
        if self.data.warning[self.mj.mjtWarning.mjWARN_BADQACC].number:
            return "MuJoCo reported bad qacc (simulation diverged)"
        return super().divergence(t)

    def forward_at(self, q, qd, acceleration: float, rows, rec: Recorder) -> None:
        mj, m, d = self.mj, self.model, self.data
        self.set_state(q, qd)
        self.set_drive(acceleration)
        mj.mj_kinematics(m, d)
        self.apply_loads()
        mj.mj_forward(m, d)
        self._readout(rows, 0.0, acceleration, rec)

    # -- readout ------------------------------------------------------------------
    def _readout(self, rows, t: float, a_prescribed: float, rec: Recorder) -> None:
        """Fill ``rows`` from the current ``data`` (after ``mj_forward``)."""
        mj, st, m, d = self.mj, self.tree, self.model, self.data
        mj.mj_rnePostConstraint(m, d)
        q = d.qpos[self.qadr].copy()
        qd = d.qvel[self.dadr].copy()
        qdd = d.qacc[self.dadr].copy()
        th, _, _, org, _, _ = rec.put_motion(rows, t, q, qd, qdd)
        tau = self.A * (st.driver_sigma * a_prescribed - qdd[st.driver_tree])
        mech = st.mech
        J, P = len(mech.joints), len(st.prismatic)
        force = np.zeros((J, 2))
        normal, moment = np.zeros(P), np.zeros(P)
        # tree joints: cfrc_int of the child = wrench by the parent on the child's subtree
        for tj in st.joints:
            bc = self.bid[tj.child]
            c = d.subtree_com[m.body_rootid[bc]]
            torque, f = d.cfrc_int[bc, :3], d.cfrc_int[bc, 3:]
            k = tj.joint
            jt = mech.joints[k]
            if tj.kind == "hinge":
                force[k] = tj.sigma * f[:2]
            else:
                sb = st.body_names.index(jt.slider)
                Pw = st.point_world(th, org, sb, st.mech.bodies[sb].points[jt.point])[0]
                mz = torque[2] - _cross(Pw - c[:2], f[:2])
                F = tj.sigma * f[:2]
                gb = st.body_names.index(jt.guide)
                ang = th[0, gb] + jt.direction
                n = np.array([-math.sin(ang), math.cos(ang)])
                p = st.prismatic.index(k)
                force[k] = F
                normal[p] = F @ n
                moment[p] = tj.sigma * mz
        for e, ch in zip(self.eq, st.chords, strict=True):
            efc = np.flatnonzero((d.efc_type == mj.mjtConstraint.mjCNSTR_EQUALITY)
                                 & (d.efc_id == e))
            force[ch.joint] = d.efc_force[efc[:2]]
        rec.put_forces(rows, force, st.driver_sigma * tau, normal, moment)


__all__ = ["SCENES", "MujocoSession", "MujocoSettings"]
