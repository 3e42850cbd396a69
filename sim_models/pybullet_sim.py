"""PyBullet driver for :func:`sim_models.engines.run` (use that front door).

Model: the URDF of :func:`sim_models.urdf.build_urdf` loaded with a fixed base
and ``URDF_USE_INERTIA_FROM_FILE``; loops closed with ``JOINT_POINT2POINT``
constraints (parent = body_a's link, child = body_b's link, pivots in the
centre-of-mass frames), ``maxForce`` large.  Per ENGINE_NOTES.md: default
joint motors off (force 0), linear/angular/joint damping 0,
``maxJointVelocity`` 1e4 (the default 100 rad/s silently clips fast cranks),
``solverResidualThreshold`` 1e-30 (the default 1e-7 stops the solver early),
global ``erp`` (the per-constraint one does nothing for multibody p2p).

Drive: a ``VELOCITY_CONTROL`` motor on the driven joint with a large force;
its target is the prescribed rate at the end of each step.

Readout at a sample (the start of step n): joint positions/velocities of
step n, accelerations ``(v_{n+1} - v_n) / dt`` (exact for the semi-implicit
step), loop forces from ``getConstraintState``.  ``getConstraintState`` and
the motor torque are impulses / dt of a step, i.e. averages over it; by
default (``average_impulses``) the mean of the readings of steps n-1 and n
is taken as the value at the start of step n (second order in dt instead of
first).  Tree-joint forces and the drive effort are **reconstructed by
Newton-Euler** (:mod:`sim_models.newton_euler`) from those accelerations and
loop forces, because PyBullet's ``jointReactionForces`` is wrong for joints
whose parent moves (off by up to 0.94 of peak, ENGINE_NOTES.md); the
engine's own readings are kept in ``joint_force_engine`` (jointFeedbackMode
world frame, converted to the analytic convention) and
``drive_effort_engine`` (motor torque) so that defect can be reported.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from dataclasses import dataclass

import numpy as np

from .engines import EngineRun, _finish, _Plan, _Recorder, _step_schedule
from .newton_euler import reconstruct
from .tree import SimModelError, SimTree
from .urdf import build_urdf


@dataclass(frozen=True)
class PybulletSettings:
    """PyBullet settings.

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

    def describe(self) -> str:
        return (f"PyBullet dt<={self.timestep:g} s, iterations={self.solver_iterations}, "
                f"residual threshold={self.residual_threshold:g}, erp={self.erp:g}, "
                f"motor force={self.motor_force:g}, maxJointVelocity="
                f"{self.max_joint_velocity:g}, average_impulses={self.average_impulses}")


def _require_pybullet():
    try:
        import pybullet
    except ImportError as e:  # pragma: no cover
        raise SimModelError(f"PyBullet is not installed ({e}); pip install pybullet") from None
    return pybullet


class PybulletSim:
    """A loaded PyBullet model (DIRECT client) with index tables."""

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
                from .urdf import link_offsets
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


def run_pybullet(st: SimTree, settings: PybulletSettings, plan: _Plan, max_violation: float,
                 max_speed_error: float) -> EngineRun:
    sim = PybulletSim(st, settings)
    try:
        return _run(sim, st, settings, plan, max_violation, max_speed_error)
    finally:
        sim.close()


def _run(sim: PybulletSim, st: SimTree, settings: PybulletSettings, plan: _Plan,
         max_violation: float, max_speed_error: float) -> EngineRun:
    p = sim.p
    rec = _Recorder(st, plan)
    dmech = st.mech.driver
    order, stops, steps = _step_schedule(plan.times, settings.timestep)
    sample_at: dict[float, list[int]] = {}
    for i in order:
        if np.isfinite(plan.times[i]):
            sample_at.setdefault(float(plan.times[i]) if plan.times[i] > 1e-15 else 0.0,
                                 []).append(int(i))
    vmax = max_violation * st.size
    accel = dmech.acceleration != 0.0
    moving = bool(sim.loads)
    # the sign factor of each tree joint, to express engine readings as body_a -> body_b
    sig = np.array([tj.sigma for tj in st.joints])
    reason = fail = None
    dt_used = max((s[0] for s in steps), default=settings.timestep)
    prev_cf = prev_tau = None
    stepped = False

    def one_step(h, t_now):
        if accel:
            sim.set_drive(dmech.velocity + dmech.acceleration * (t_now + h))
        if moving:
            sim.apply_loads()
        sim.step()

    # start a few steps early (see PybulletSettings.preroll_steps)
    h0 = next((h for h, n in steps if n > 0), settings.timestep)
    n_pre = max(int(settings.preroll_steps), 0)
    t = -n_pre * h0
    try:
        val, vel0, acc0 = (float(x) for x in st.driver_path(t))
        kin = st.linkage.kinematics(val, vel0, acc0)
        q0, qd0, _ = st.coords(kin)
    except Exception:  # e.g. the reference sits at a limit position: no pre-roll
        n_pre, t = 0, 0.0
        q0, qd0, _ = st.coords(st.kin_ref)
        q0 = np.zeros_like(q0)
    sim.set_state(q0[0], qd0[0])
    sim.set_drive(dmech.velocity + dmech.acceleration * t)
    p.setPhysicsEngineParameter(fixedTimeStep=h0, physicsClientId=sim.cid)
    h_cur = h0
    t0 = time.perf_counter()
    for _ in range(n_pre):
        one_step(h0, t)
        t += h0
    t = 0.0
    carried = 0  # steps of the current interval already taken (the post-sample step)
    for (h, n), t_stop in zip(steps, stops[1:], strict=True):
        if carried:
            # the post-sample step (of the previous interval's size) is already taken
            rem = t_stop - t
            k = rem / h
            if abs(k - round(k)) < 1e-6 * max(k, 1.0):
                n = int(round(k))
            else:
                n = max(1, math.ceil(rem / settings.timestep - 1e-9))
                h = rem / n
            carried = 0
        if h != h_cur and n > 0:
            p.setPhysicsEngineParameter(fixedTimeStep=h, physicsClientId=sim.cid)
            h_cur = h
        for _ in range(n):
            one_step(h, t)
            stepped = True
            t += h
        t = t_stop
        # impulse readings of the step that ends at the sample (for averaging)
        prev_cf = sim.constraint_forces() if stepped else None
        prev_tau = sim.states()[3] if stepped else None
        idx = sample_at.get(t_stop, [])
        # sample: the state at the start of the next step, then that step for the differences
        q, v, _, _ = sim.states()
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            reason = "non-finite state (simulation diverged)"
        else:
            h_next = h_cur  # same step as before the sample: consistent differences
            one_step(h_next, t)
            carried = 1
            q1, v1, rf1, tau1 = sim.states()
            cf1 = sim.constraint_forces()
            qdd = (v1 - v) / h_next
            # semi-implicit Euler: v_n lags the positions by about half a step, so the
            # velocity at the sample is the mean of v_n and v_{n+1} (second order)
            vm = 0.5 * (v + v1) if settings.midpoint_velocity else v
            th, om, al, org, _, a_org = st.propagate(q[None], vm[None], qdd[None])
            stepped = True
            if settings.average_impulses and prev_cf is not None:
                cf = 0.5 * (prev_cf + cf1)
                tau = 0.5 * (prev_tau + tau1)
            else:
                cf, tau = cf1, tau1
            viol = 0.0
            for ch in st.chords:
                pa = st.point_world(th, org, ch.body_a, ch.point_a)[0]
                pb = st.point_world(th, org, ch.body_b, ch.point_b)[0]
                viol = max(viol, float(np.linalg.norm(pa - pb)))
            _, vel_now, acc_now = st.driver_path(t)
            rate = st.driver_sigma * vm[st.driver_tree]
            jnames = [j.name for j in st.mech.joints]
            for i in idx:
                rec.theta[i], rec.omega[i], rec.alpha[i] = th[0], om[0], al[0]
                rec.measured[i] = st.driver_value(q[st.driver_tree])
                rec.viol[i] = viol
                rec.speed[i] = rate - float(vel_now)
                F, Nn, M, eff = reconstruct(st, th, om, al, org, a_org, cf[None])
                for name, val in F.items():
                    rec.force[i, jnames.index(name)] = val[0]
                for pi, k in enumerate(st.prismatic):
                    name = st.mech.joints[k].name
                    rec.normal[i, pi] = Nn[name][0]
                    rec.moment[i, pi] = M[name][0]
                    t_idx = st.tree_joint_indices.index(k)
                    rec.slider_acc[i, pi] = st.joints[t_idx].sigma * qdd[t_idx]
                rec.effort[i] = eff[0]
                rec.effort_engine[i] = st.driver_sigma * tau
                for t_idx, tj in enumerate(st.joints):
                    rec.force_engine[i, tj.joint] = sig[t_idx] * rf1[t_idx]
                for ci, ch in enumerate(st.chords):
                    rec.force_engine[i, ch.joint] = cf1[ci]
            t += h_next
            if not (np.all(np.isfinite(q1)) and np.all(np.isfinite(v1))):
                reason = "non-finite state (simulation diverged)"
            elif viol > vmax:
                reason = f"loop violation {viol:.3g} m > {vmax:.3g} m"
            elif abs(rate - vel_now) > max_speed_error * max(abs(vel_now), abs(dmech.velocity),
                                                             1e-12):
                reason = (f"driver rate off by {abs(rate - vel_now):.3g} "
                          f"(> {max_speed_error:g} relative)")
        if reason is not None:
            reason, fail = rec.fail(st, t_stop, reason)
            break
    wall = time.perf_counter() - t0
    notes = ("tree-joint forces and drive effort reconstructed by Newton-Euler from PyBullet's "
             "accelerations and loop forces; PyBullet's own readings in joint_force_engine "
             "(jointReactionForces) and drive_effort_engine (motor torque)",)
    return _finish(st, plan, rec, "pybullet", settings.describe(), reason, fail, wall, dt_used,
                   notes=notes, engine_readings=True)
