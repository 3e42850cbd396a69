"""PyBullet on the user's own URDF file, judged against its imported description.

PyBullet loads the user's URDF itself (``pybullet.loadURDF``, fixed base,
``URDF_USE_INERTIA_FROM_FILE``): its links, inertias, joint origins and axes, limits and
joint damping as written.  Added only what the harness adds to its own URDF models
(:class:`sim_models.engines.pybullet.driven.PybulletSim`): the loop closures a URDF cannot hold
(the ``--close`` points, as ``JOINT_POINT2POINT`` constraints between the two links,
pivots in each link's centre-of-mass frame, ``maxForce`` large), the world's gravity of
the imported model (MuJoCo's reading of the file: a URDF has none of its own), PyBullet's
default joint motors off and ``maxJointVelocity`` raised (PyBullet's own artefacts, not the
user's model), and the drive: a ``VELOCITY_CONTROL`` motor on the driver joint.  Its
joint damping is switched off as in the harness's models: the description carries it
(``[[dampers]]``, read by MuJoCo's URDF reader) and a free run applies it each step, as
the harness's released PyBullet runs apply their elements.

Coordinates are the model's joint coordinates, mapped onto the description's tree as for
MuJoCo (:class:`sim_models.own.mujoco_own.Mapping`); readout as the harness's PyBullet
session does it (finite-difference accelerations, mid-step velocities, tree-joint forces
and drive effort by Newton-Euler from the loop forces, projected on the plane).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..builders.tree import SimTree
from ..engines.free_elements import ElementLoads
from ..engines.free_protocol import FreeSession, drive_free
from ..engines.protocol import RunRequest, compile_linkage, drive, plan_samples
from ..engines.pybullet.driven import (
    PybulletSession,
    PybulletSettings,
    PybulletSim,
    _quiet_fd,
    _require_pybullet,
)
from ..engines.pybullet.free import PybulletFreeSession, PybulletFreeSettings
from ..runs.engine_run import Recorder
from ..runs.newton_euler import joint_readout
from .describe import Imported
from .mujoco_own import Mapping


class OwnPybulletSim(PybulletSim):
    """The user's URDF loaded by PyBullet (see the module); ``jidx`` in the model's joint
    order (the importer's), states in the model's coordinates."""

    def __init__(self, st: SimTree, imp: Imported, settings: PybulletSettings):
        self.imp = imp
        self.map = Mapping(st, imp)
        super().__init__(st, settings)

    def _load(self):
        p, s, cid, imp = self.p, self.settings, self.cid, self.imp
        c = imp.compiled
        p.setGravity(*(float(g) for g in c.model.opt.gravity), physicsClientId=cid)
        p.setPhysicsEngineParameter(fixedTimeStep=s.timestep, numSubSteps=0,
                                    numSolverIterations=int(s.solver_iterations),
                                    solverResidualThreshold=float(s.residual_threshold),
                                    erp=float(s.erp), physicsClientId=cid)
        with _quiet_fd(1), _quiet_fd(2):  # its importer prints (b3Warning: a link without inertia)
            self.body = b = p.loadURDF(str(c.path), useFixedBase=True,
                                       flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=cid)
        by_joint, by_link = {}, {p.getBodyInfo(b, physicsClientId=cid)[0].decode(): -1}
        for j in range(p.getNumJoints(b, physicsClientId=cid)):
            info = p.getJointInfo(b, j, physicsClientId=cid)
            by_joint[info[1].decode()] = j
            by_link[info[12].decode()] = j
            p.setJointMotorControl2(b, j, p.VELOCITY_CONTROL, targetVelocity=0, force=0,
                                    physicsClientId=cid)
            p.changeDynamics(b, j, linearDamping=0, angularDamping=0, jointDamping=0,
                             maxJointVelocity=float(s.max_joint_velocity), physicsClientId=cid)
        self.jidx = [by_joint[j.name] for j in c.joints]
        self.link = by_link | {"world": -1}
        self.cons = []
        for cl in c.closes:
            ends = [(by_link[lk], self._com_frame(by_link[lk], pt))
                    for lk, pt in ((cl.a, cl.pa), (cl.b, cl.pb))]
            k = p.createConstraint(b, ends[0][0], b, ends[1][0], p.JOINT_POINT2POINT,
                                   [0, 0, 0], ends[0][1], ends[1][1], physicsClientId=cid)
            p.changeConstraint(k, maxForce=1e30, physicsClientId=cid)
            self.cons.append(k)
        self.drive = by_joint[imp.driver.name]
        self.loads = []

    def _com_frame(self, link: int, point) -> list[float]:
        """A point given in the link's URDF frame, in its centre-of-mass frame (where
        PyBullet's constraint pivots are)."""
        p = self.p
        pos, orn = p.getDynamicsInfo(self.body, link, physicsClientId=self.cid)[3:5]
        inv_pos, inv_orn = p.invertTransform(pos, orn)
        return list(p.multiplyTransforms(inv_pos, inv_orn, list(point), (0, 0, 0, 1))[0])

    def set_state(self, q, qd):
        pos, vel = self.map.model_state(np.asarray(q, float), np.asarray(qd, float))
        for j, qi, vi in zip(self.jidx, pos, vel, strict=True):
            self.p.resetJointState(self.body, j, float(qi), float(vi), physicsClientId=self.cid)

    def set_drive(self, rate: float):
        # the importer made the driver's coordinate the model's own (sign +1)
        self.p.setJointMotorControl2(self.body, self.drive, self.p.VELOCITY_CONTROL,
                                     targetVelocity=float(rate),
                                     force=float(self.settings.motor_force),
                                     physicsClientId=self.cid)

    def states(self):
        """Model joint positions and velocities (the model's order), no readings."""
        st = self.p.getJointStates(self.body, self.jidx, physicsClientId=self.cid)
        return np.array([s[0] for s in st]), np.array([s[1] for s in st]), None, 0.0

    def constraint_forces(self):
        """Force by body_a on body_b at each closure, on the plane's axes, (n, 2)."""
        pl = self.imp.plane
        out = np.zeros((len(self.cons), 2))
        for i, k in enumerate(self.cons):
            f = np.array(self.p.getConstraintState(k, physicsClientId=self.cid)[:3])
            out[i] = (f @ pl.e1, f @ pl.e2)
        return out


class OwnPybulletSession(PybulletSession):
    """PyBullet on the user's URDF (module doc)."""

    engine_readings = False

    def __init__(self, tree: SimTree, imp: Imported, settings: PybulletSettings | None = None):
        _require_pybullet()
        self.imp = imp
        super(PybulletSession, self).__init__(tree, settings)
        self.sim = OwnPybulletSim(tree, imp, self.settings)
        self.h = self.settings.timestep
        self.accel = tree.mech.driver.acceleration != 0.0
        self.jnames = [j.name for j in tree.mech.joints]
        self.notes.append(
            f"PyBullet loaded the user's URDF {imp.compiled.path} itself (its inertias, "
            "limits); loops closed by JOINT_POINT2POINT at the --close points; "
            "tree-joint forces and drive effort reconstructed by Newton-Euler")

    def _tree(self, q, v):
        mp = self.map
        full = np.zeros((len(q), self.imp.compiled.model.nq))
        full[:, mp.qadr] = q
        return mp.tree_q(full), np.asarray(v) @ mp.T.T

    @property
    def map(self) -> Mapping:
        return self.sim.map

    def state(self):
        q, v, _, _ = self.sim.states()
        tq, tv = self._tree(q[None], v[None])
        return tq[0], tv[0]

    def record(self, t: float):
        """The model's joint states at ``t`` and after one more step (finite
        differences), and the loop forces of that step."""
        sim = self.sim
        q, v, _, _ = sim.states()
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            return None, 0.0, "non-finite state (simulation diverged)"
        h = self.h
        self._one_step(h, t)
        q1, v1, _, _ = sim.states()
        if not (np.all(np.isfinite(q1)) and np.all(np.isfinite(v1))):
            return None, h, "non-finite state (simulation diverged)"
        return (q, v, v1, sim.constraint_forces(), h), h, None

    def convert(self, times, raws, rows, rec: Recorder):
        st, s = self.tree, self.settings
        q, v, v1, cf, h = (np.array(x) for x in zip(*raws, strict=True))
        tq, tv = self._tree(q, v)
        _, tv1 = self._tree(q, v1)
        qdd = (tv1 - tv) / h[:, None]
        vm = 0.5 * (tv + tv1) if s.midpoint_velocity else tv
        prop, gap, rate = rec.put_motions(rows, times, tq, vm, qdd)
        jr = joint_readout(st, prop, cf, self.jnames)
        rec.put_forces_many(rows, jr.force, jr.effort, jr.normal, jr.moment)
        return gap, rate


class OwnPybulletTreeSim(OwnPybulletSim):
    """:class:`OwnPybulletSim` read in the description's tree coordinates (what the
    harness's released PyBullet session reads)."""

    def states(self):
        q, v, rf, tau = super().states()
        mp = self.map
        full = np.zeros((1, self.imp.compiled.model.nq))
        full[:, mp.qadr] = q
        return mp.tree_q(full)[0], v @ mp.T.T, rf, tau


class OwnPybulletFreeSession(PybulletFreeSession):
    """PyBullet on the user's URDF released from the description's exact start (its
    ``qpos0`` or keyframe state), under the model's gravity; the description's springs,
    dampers and motors applied by the harness each step as for its own models (PyBullet's
    own joint damping off, as there)."""

    def __init__(self, tree: SimTree, imp: Imported,
                 settings: PybulletFreeSettings | None = None):
        _require_pybullet()
        FreeSession.__init__(self, tree, settings)
        self.imp = imp
        self.sim = OwnPybulletTreeSim(tree, imp, self.settings.prescribed())
        self.elements = ElementLoads(tree)
        self.h = None
        self.v_hist = []
        self.link = [self.sim.link[n] for n in tree.body_names]
        fm = tree.mech.motion
        self.motors = list(fm.motors) if fm else []


def run_free_pybullet(imp: Imported, request, reference, timestep: float | None = None):
    """The user's URDF released in PyBullet: a :class:`sim_models.runs.free_run.FreeEngineRun`
    against the exact free motion ``reference`` of ``imp.mechanism``."""
    settings = PybulletFreeSettings(**({"timestep": timestep} if timestep else {}))
    session = OwnPybulletFreeSession(compile_linkage(imp.mechanism, chords="analytic"), imp,
                                     settings)
    try:
        return drive_free(session, request, reference)
    finally:
        session.close()


def run_prescribed_pybullet(imp: Imported, request=None,
                            settings: PybulletSettings | None = None):
    """The user's URDF in PyBullet driven along the description's prescribed motion."""
    request = dataclasses.replace(request or RunRequest(), chords="analytic")
    tree = compile_linkage(imp.mechanism, chords="analytic")
    plan = plan_samples(tree, request.revolutions, request.samples)
    with OwnPybulletSession(tree, imp, settings) as session:
        return tree, drive(session, plan, request)


__all__ = ["OwnPybulletFreeSession", "OwnPybulletSession", "run_free_pybullet",
           "run_prescribed_pybullet"]
