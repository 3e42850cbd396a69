"""PyBullet behind the engine protocol (:class:`PybulletSession`, :class:`PybulletSettings`).

Model: the URDF of :func:`sim_models.builders.urdf.build_urdf` loaded with a fixed base
and ``URDF_USE_INERTIA_FROM_FILE``; loops closed with ``JOINT_POINT2POINT``
constraints (parent = body_a's link, child = body_b's link, pivots in the
centre-of-mass frames), ``maxForce`` large.  Per ENGINE_NOTES.md: default
joint motors off (force 0), linear/angular/joint damping 0,
``maxJointVelocity`` 1e4 (the default 100 rad/s silently clips fast cranks),
``solverResidualThreshold`` 1e-30 (the default 1e-7 stops the solver early),
global ``erp`` (the per-constraint one does nothing for multibody p2p).

Drive: a ``VELOCITY_CONTROL`` motor on the driven joint with a large force;
its target is the prescribed rate at the end of each step.

Quirks kept here: the **pre-roll** (the first step after ``resetJointState`` ignores the
loop, so a run starts ``preroll_steps`` early from the analytic state of that earlier
time), the **mid-step velocity** (semi-implicit Euler leaves ``v_n`` half a step behind
the positions), accelerations as **finite differences over the step after a sample** (so
:meth:`PybulletSession.sample` steps once and says so), and the **Newton-Euler
reconstruction** of the pin forces.

Readout at a sample (the start of step n): joint positions/velocities of
step n, accelerations ``(v_{n+1} - v_n) / dt`` (exact for the semi-implicit
step), loop forces from ``getConstraintState``.  ``getConstraintState`` and
the motor torque are impulses / dt of a step, i.e. averages over it; by
default (``average_impulses``) the mean of the readings of steps n-1 and n
is taken as the value at the start of step n (second order in dt instead of
first).  Tree-joint forces and the drive effort are **reconstructed by
Newton-Euler** (:mod:`sim_models.runs.newton_euler`) from those accelerations and
loop forces, because PyBullet's ``jointReactionForces`` is wrong for joints
whose parent moves (off by up to 0.94 of peak, ENGINE_NOTES.md); the
engine's own readings are kept in ``joint_force_engine`` (jointFeedbackMode
world frame, converted to the analytic convention) and
``drive_effort_engine`` (motor torque) so that defect can be reported.
"""

from __future__ import annotations

import contextlib
import math
import os
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ...builders.tree import SimModelError, SimTree
from ...builders.urdf import build_urdf, link_offsets
from ...runs.newton_euler import joint_readout
from .. import ranges
from ..protocol import (
    EngineRefusal,
    EngineSettings,
    Recorder,
    Session,
)


@dataclass(frozen=True)
class PybulletSettings(EngineSettings):
    """PyBullet settings (recommended defaults; evidence in the README "Engines" section and
    the speed-against-error grid of :mod:`reports.studies.speed_accuracy`).

    Parameters
    ----------
    timestep
        Largest step, s (shortened so samples fall on steps).  Pin forces and
        the drive effort converge with dt^2 once impulses are averaged;
        accelerations also with dt^2.
    solver_iterations
        ``numSolverIterations``.
    residual_threshold
        ``solverResidualThreshold`` (1e-30: never stop early).
    erp
        Global error-reduction parameter (position drift correction of the
        loop constraints).
    motor_force
        Max force of the drive's velocity motor (N m or N).
    max_joint_velocity
        ``maxJointVelocity`` of every joint.
    average_impulses
        Average the impulse-based readings of steps n-1 and n (off by default:
        measured worse; the impulse of step n already belongs to the start of
        step n, like the finite-difference acceleration).
    midpoint_velocity
        Take ``(v_n + v_{n+1}) / 2`` as the velocity at a sample (used for omega,
        the driver rate and the centripetal terms of the Newton-Euler
        reconstruction).  The semi-implicit step leaves ``v_n`` about half a step
        behind the positions; with ``v_n`` the pin forces converge only with dt
        (seed four-bar at dt 1e-4: 3.7e-4 of peak instead of 4.5e-6).
    preroll_steps
        Steps simulated before t = 0, from the analytic state at the driver
        value of that earlier time: PyBullet's first step after
        ``resetJointState`` ignores the loop (rocker alpha 0 instead of 95.5 on
        the seed four-bar) and its second overshoots.
    """

    timestep: float = 3e-5
    solver_iterations: int = 20
    residual_threshold: float = 1e-30
    erp: float = 1.0
    motor_force: float = 1e9
    max_joint_velocity: float = 1e4
    average_impulses: bool = False
    midpoint_velocity: bool = True
    preroll_steps: int = 20

    engine_name: ClassVar[str] = "pybullet"
    RANGES: ClassVar[Mapping[str, object]] = {
        "timestep": ranges.TIMESTEP,
        "solver_iterations": ranges.Range(1, 1000, whole=True,
                                          why="constraint solver sweeps a step; 1000 caps "
                                              "the cost of a step"),
        "residual_threshold": ranges.Range(0, why="a residual norm; 0 or tiny: never stop "
                                           "early"),
        "erp": ranges.Range(0, 1, why="the fraction of the loop error corrected per step; "
                            "above 1 overcorrects"),
        "motor_force": ranges.Range(0, lo_open=True, unit="N m or N",
                                    why="the drive's largest effort; 0 or below drives "
                                        "nothing"),
        "max_joint_velocity": ranges.Range(0, lo_open=True, unit="rad/s or m/s",
                                           why="PyBullet clamps every joint's speed to it"),
        "average_impulses": ranges.FLAG,
        "midpoint_velocity": ranges.FLAG,
        "preroll_steps": ranges.Range(0, 10000, whole=True,
                                      why="steps before t = 0 from the analytic state; "
                                          "0: none"),
    }

    def describe(self) -> str:
        return (f"PyBullet dt<={self.timestep:g} s, iterations={self.solver_iterations}, "
                f"residual threshold={self.residual_threshold:g}, erp={self.erp:g}, "
                f"motor force={self.motor_force:g}, maxJointVelocity="
                f"{self.max_joint_velocity:g}, average_impulses={self.average_impulses}")


class PybulletSim:
    """A loaded PyBullet model (DIRECT client) with index tables (the raw model; the
    protocol session is :class:`PybulletSession`)."""

    def __init__(self, st: SimTree, settings: PybulletSettings):
        p = _require_pybullet()
        self.p, self.st, self.settings = p, st, settings
        self.cid = p.connect(p.DIRECT)
        try:
            self._load()
        except Exception:
            p.disconnect(self.cid)
            raise

    def _load(self):
        p, st, s, cid = self.p, self.st, self.settings, self.cid
        text, closures = build_urdf(st.mech, st)
        self.closures = closures
        gx, gy = st.mech.gravity
        p.setGravity(float(gx), float(gy), 0.0, physicsClientId=cid)
        p.setPhysicsEngineParameter(fixedTimeStep=s.timestep, numSubSteps=0,
                                    numSolverIterations=int(s.solver_iterations),
                                    solverResidualThreshold=float(s.residual_threshold),
                                    erp=float(s.erp), jointFeedbackMode=3, physicsClientId=cid)
        fd, path = tempfile.mkstemp(suffix=".urdf", prefix="linkage_")
        try:
            with os.fdopen(fd, "w") as f:
                f.write(text)
            self.body = p.loadURDF(path, useFixedBase=True,
                                   flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=cid)
        finally:
            os.unlink(path)
        b = self.body
        nj = p.getNumJoints(b, physicsClientId=cid)
        by_joint, by_link = {}, {st.body_names[st.ground]: -1}
        for j in range(nj):
            info = p.getJointInfo(b, j, physicsClientId=cid)
            by_joint[info[1].decode()] = j
            by_link[info[12].decode()] = j
        self.jidx = [by_joint[tj.name] for tj in st.joints]
        self.link = by_link
        p.changeDynamics(b, -1, linearDamping=0, angularDamping=0, physicsClientId=cid)
        for j in range(nj):
            p.setJointMotorControl2(b, j, p.VELOCITY_CONTROL, targetVelocity=0, force=0,
                                    physicsClientId=cid)
            p.changeDynamics(b, j, linearDamping=0, angularDamping=0, jointDamping=0,
                             maxJointVelocity=float(s.max_joint_velocity),
                             physicsClientId=cid)
            p.enableJointForceTorqueSensor(b, j, True, physicsClientId=cid)
        self.cons = []
        for c in closures:
            k = p.createConstraint(b, by_link[c.parent_link], b, by_link[c.child_link],
                                   p.JOINT_POINT2POINT, [0, 0, 0], list(c.parent_pivot),
                                   list(c.child_pivot), physicsClientId=cid)
            p.changeConstraint(k, maxForce=1e30, physicsClientId=cid)
            self.cons.append(k)
        self.drive = self.jidx[st.driver_tree]
        self.loads = [(by_link[ld.body], ld) for ld in st.mech.loads]

    def close(self):
        try:
            self.p.disconnect(self.cid)
        except Exception:  # pragma: no cover
            pass

    # ----------------------------------------------------------------------
    def set_state(self, q, qd):
        for j, qi, vi in zip(self.jidx, q, qd, strict=True):
            self.p.resetJointState(self.body, j, float(qi), float(vi), physicsClientId=self.cid)

    def set_drive(self, rate: float):
        self.p.setJointMotorControl2(self.body, self.drive, self.p.VELOCITY_CONTROL,
                                     targetVelocity=self.st.driver_sigma * float(rate),
                                     force=float(self.settings.motor_force),
                                     physicsClientId=self.cid)

    def apply_loads(self):
        p, st = self.p, self.st
        if not self.loads:
            return
        for link, ld in self.loads:
            b = st.body_names.index(ld.body)
            if ld.point is None:
                pos = p.getLinkState(self.body, link, physicsClientId=self.cid)[0]
            else:
                # link frame = URDF frame (index 4/5); the point in link-frame coordinates
                off = link_offsets(st)[b]
                ls = p.getLinkState(self.body, link, computeForwardKinematics=True,
                                    physicsClientId=self.cid)
                pt = np.asarray(st.mech.bodies[b].points[ld.point], float) - off
                pos = p.multiplyTransforms(ls[4], ls[5], (pt[0], pt[1], 0.0),
                                           (0, 0, 0, 1))[0]
            p.applyExternalForce(self.body, link, (ld.force[0], ld.force[1], 0.0), pos,
                                 p.WORLD_FRAME, physicsClientId=self.cid)
            if ld.torque:
                p.applyExternalTorque(self.body, link, (0.0, 0.0, ld.torque), p.WORLD_FRAME,
                                      physicsClientId=self.cid)

    def states(self):
        st = self.p.getJointStates(self.body, self.jidx, physicsClientId=self.cid)
        q = np.array([s[0] for s in st])
        v = np.array([s[1] for s in st])
        rf = np.array([s[2][:2] for s in st])
        tau = st[self.st.driver_tree][3]
        return q, v, rf, tau

    def constraint_forces(self):
        """Force by body_a on body_b at each closure (world axes), (n_chords, 2)."""
        out = np.zeros((len(self.cons), 2))
        for i, k in enumerate(self.cons):
            f = self.p.getConstraintState(k, physicsClientId=self.cid)
            out[i] = f[:2]
        return out

    def step(self):
        self.p.stepSimulation(physicsClientId=self.cid)


class PybulletModel:
    """What the driven and the released PyBullet sessions share: the loaded model
    :attr:`sim` (a :class:`PybulletSim`), the step ``h`` it is set to, and closing it."""

    sim: PybulletSim | None
    h: float | None

    def close(self) -> None:
        if getattr(self, "sim", None) is not None:
            self.sim.close()
            self.sim = None

    def _set_step(self, h: float) -> None:
        if h != self.h:
            self.sim.p.setPhysicsEngineParameter(fixedTimeStep=h, physicsClientId=self.sim.cid)
            self.h = h


class PybulletSession(PybulletModel, Session):
    """A loaded PyBullet model of one linkage, driven by a velocity motor."""

    name = "pybullet"
    settings_class = PybulletSettings
    engine_readings = True

    def __init__(self, tree: SimTree, settings: PybulletSettings | None = None):
        super().__init__(tree, settings)
        self.sim = PybulletSim(tree, self.settings)
        self.h = self.settings.timestep
        self.accel = tree.mech.driver.acceleration != 0.0
        self.sig = np.array([tj.sigma for tj in tree.joints])
        self.jnames = [j.name for j in tree.mech.joints]
        self.notes.append(
            "tree-joint forces and drive effort reconstructed by Newton-Euler from PyBullet's "
            "accelerations and loop forces; PyBullet's own readings in joint_force_engine "
            "(jointReactionForces) and drive_effort_engine (motor torque)")

    def _one_step(self, h: float, t_now: float) -> None:
        sim = self.sim
        if self.accel:
            d = self.tree.mech.driver
            # the motor sets v_{n+1}, and q_{n+1} = q_n + h v_{n+1}: the rate at mid-step
            # keeps the positions on the prescribed path exactly
            sim.set_drive(d.velocity + d.acceleration * (t_now + 0.5 * h))
        if sim.loads:
            sim.apply_loads()
        sim.step()

    def state(self):
        q, v, _, _ = self.sim.states()
        return q, v

    # -- the protocol -------------------------------------------------------------
    def reset(self, t: float, h: float) -> None:
        """The analytic state ``preroll_steps`` steps of ``h`` before ``t``, stepped to
        ``t`` (no pre-roll when the analytic solution there is not the continuation of the
        reference pose, e.g. past a change point, or cannot close)."""
        st, sim = self.tree, self.sim
        d = st.mech.driver
        n_pre = max(int(self.settings.preroll_steps), 0)
        q0, qd0, _ = self.analytic_state(t)
        if n_pre:
            try:
                qp, qdp, _ = self.analytic_state(t - n_pre * h)
                # the same assembly: each tree coordinate within ~ its rate x the pre-roll
                drift = np.abs(qp - (q0 - qd0 * n_pre * h))
                if np.max(drift, initial=0.0) < math.radians(5.0):
                    q0, qd0 = qp, qdp
                else:
                    n_pre = 0
            except (ValueError, ArithmeticError):  # e.g. an infeasible earlier input
                n_pre = 0
        t0 = t - n_pre * h
        if n_pre == 0 and t == 0.0 and not np.all(np.isfinite(qd0)):
            raise EngineRefusal(f"mechanism {st.mech.name!r}: no finite analytic state at "
                                "the reference input to start PyBullet from")
        sim.set_state(q0, qd0)
        sim.set_drive(d.velocity + d.acceleration * t0)
        self.h = None
        self._set_step(h)
        for k in range(n_pre):
            self._one_step(h, t0 + k * h)

    def advance(self, t: float, h: float, n: int) -> str | None:
        self._set_step(h)
        sim = self.sim
        if not (self.accel or sim.loads):  # nothing to re-target per step: the bare loop
            step, cid = sim.p.stepSimulation, sim.cid
            for _ in range(n):
                step(physicsClientId=cid)
            return None
        step = self._one_step
        for k in range(n):
            step(h, t + k * h)
        return None

    def record(self, t: float):
        """The joint states at ``t``, then one more step for the finite differences
        (``ahead`` = that step): positions, velocities of steps n and n+1, the reaction
        and motor readings and loop forces of step n+1 (and of step n when impulses are
        averaged).  A non-finite state is a reason at once."""
        sim, s = self.sim, self.settings
        q, v, rf, tau = sim.states()
        prev = (sim.constraint_forces(), tau) if s.average_impulses else None
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            return None, 0.0, "non-finite state (simulation diverged)"
        h = self.h
        self._one_step(h, t)
        q1, v1, rf1, tau1 = sim.states()
        if not (np.all(np.isfinite(q1)) and np.all(np.isfinite(v1))):
            return None, h, "non-finite state (simulation diverged)"
        cf1 = sim.constraint_forces()
        if prev is not None:
            cf, tau = 0.5 * (prev[0] + cf1), 0.5 * (prev[1] + tau1)
        else:
            cf, tau = cf1, tau1
        return (q, v, v1, rf1, cf1, cf, tau, h), h, None

    def convert(self, times, raws, rows, rec: Recorder):
        """Motion from the finite differences and (mid-step) velocities, tree-joint
        forces and drive effort by Newton-Euler, of K raw records at once."""
        st, s = self.tree, self.settings
        q, v, v1, rf1, cf1, cf, tau, h = (np.array(x) for x in zip(*raws, strict=True))
        qdd = (v1 - v) / h[:, None]
        # semi-implicit Euler: v_n lags the positions by about half a step, so the
        # velocity at the sample is the mean of v_n and v_{n+1} (second order)
        vm = 0.5 * (v + v1) if s.midpoint_velocity else v
        prop, gap, rate = rec.put_motions(rows, times, q, vm, qdd)
        jr = joint_readout(st, prop, cf, self.jnames)
        engine = np.full_like(jr.force, np.nan)
        for ti, tj in enumerate(st.joints):
            engine[:, tj.joint] = self.sig[ti] * rf1[:, ti]
        for ci, ch in enumerate(st.chords):
            engine[:, ch.joint] = cf1[:, ci]
        rec.put_forces_many(rows, jr.force, jr.effort, jr.normal, jr.moment, force_engine=engine,
                            effort_engine=st.driver_sigma * tau)
        return gap, rate


def _require_pybullet():
    try:
        with _quiet_stderr():  # its C extension prints "pybullet build time: ..." on import
            import pybullet
    except ImportError as e:  # pragma: no cover
        raise SimModelError(f"PyBullet is not installed ({e}); pip install pybullet") from None
    return pybullet


@contextlib.contextmanager
def _quiet_fd(fd: int):
    """File descriptor ``fd`` (1 standard output, 2 standard error) to /dev/null for the
    block: a C library's own prints (PyBullet's importer warnings, its solver notes), so
    that xval's output holds only its own lines (one line for an error)."""
    import sys
    (sys.stdout if fd == 1 else sys.stderr).flush()
    saved, null = os.dup(fd), os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, fd)
        yield
    finally:
        os.dup2(saved, fd)
        os.close(saved)
        os.close(null)


def _quiet_stderr():
    """:func:`_quiet_fd` on standard error."""
    return _quiet_fd(2)


__all__ = ["PybulletSession", "PybulletSettings", "PybulletSim"]
