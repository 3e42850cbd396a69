"""Pinocchio behind the engine protocol: rigid loop constraints, reactions from multipliers.

Model (built through Pinocchio's API from :class:`sim_models.builders.tree.SimTree`)
--------------------------------------------------------------------------
* one Pinocchio joint per tree joint, added **depth first** (every subtree's joints
  contiguous, which ``crba`` and the Cholesky of ``constraintDynamics`` assume; see
  :meth:`PinocchioSession._depth_first`): a hinge is a
  ``JointModelRZ`` whose frame sits at the joint point, turned like the child body's
  frame at the reference pose; a slide is a ``JointModelPrismaticUnaligned`` along the
  line (the child frame's ``axis_child``), its frame at the child body's origin.  Every
  joint coordinate is the tree coordinate of :class:`SimTree` (0 at the reference pose),
  so ``q, v, a`` are read out with :meth:`Recorder.put_motions` unchanged;
* each moving body's mass, centre of mass and inertia (``SimTree.mass/com/inertia``,
  floors included) appended to its joint (``Ixx = Iyy = Izz``: the out-of-plane
  inertias never act, every joint keeps the motion planar);
* each loop-closing revolute joint (``SimTree.chords``) is a ``RigidConstraintModel``
  of type ``CONTACT_3D`` between the joint point on its two bodies, in
  ``LOCAL_WORLD_ALIGNED`` axes, the moving body as joint 1 (a ground body is joint 0);
* gravity is ``model.gravity`` in the plane; loads enter as generalised forces
  ``J^T f`` (``constraintDynamics`` takes no external forces) and as ``fext`` of the
  readout's RNEA.

The redundant direction
-----------------------
A planar loop closed by a 3D point constraint has three rows per loop; every joint
turns about z or slides in the plane, so the z row of the constraint Jacobian is
identically zero (measured: exactly 0.0) and the Delassus matrix ``J M^-1 J^T`` is
singular in that direction (rank ``2 * loops``).  ``CONTACT_6D`` would be worse: it
would lock the hinge.  ``constraintDynamics`` with :class:`pinocchio.ProximalSettings`
solves the proximal (regularised) problem ``lambda_{k+1} = argmin ... + mu/2 |lambda -
lambda_k|^2``, which leaves the zero row's multiplier at its start, 0: the whole
reaction is carried by the two in-plane rows, and the z multiplier is reported as
``extra["max_lambda_z"]`` (measured 0.0).  Only the in-plane components (x, y) are
judged; the z component is not read into any judged quantity.

The drive (prescribed motion)
-----------------------------
The driver is a tree joint whose acceleration is imposed: the constrained dynamics
is affine in the driver's generalised force ``tau_d``, so the session solves it twice
per evaluation (``tau_d = 0`` and ``tau_d = 1``) and takes the ``tau_d`` that gives the
driver's tree acceleration ``sigma_d a_prescribed``; accelerations and multipliers are
the same combination.  ``sigma_d tau_d`` is the drive effort (torque on body_b, or
force on the slider along its line).

Integration
-----------
``integrator="rk4"``: classical Runge-Kutta on ``(q, v)`` (positions exactly additive:
every joint is 1-dof, so ``pinocchio.integrate`` is ``q + dq``); ``"euler"``:
semi-implicit Euler (``v += h a; q += h v``).  Drift of the loop closures is held by
Pinocchio's Baumgarte corrector on each constraint (``Kp = omega^2``, ``Kd = 2 omega``,
``omega = baumgarte / h``: critically damped, a fixed fraction of the step).

Readout (conventions of :mod:`sim_models.engines.protocol`), sampled by state: at each
stop the accelerations and multipliers of ``constraintDynamics`` at the integrated
``q, v``, with the Baumgarte corrector off (the dynamics at the state, as MuJoCo
samples by ``mj_forward`` and Exudyn by state; with it on the seed four-bar's samples
had a floor of 2.4e-7 of peak, without 6.8e-8 at the same steps):

* loop-closing joint: the constraint force of the 3D contact (``contact_force`` of its
  data, stacked in ``data.lambda_c``; world axes), signed so it is the force by body_a
  on body_b;
* tree joint: Pinocchio's RNEA with the constraint forces and loads as ``fext`` gives
  ``data.f[i]``, the wrench by the parent on the child's subtree in joint i's frame;
  a hinge's force is its linear part (world axes, ``sigma`` for body_a on body_b); a
  slide's normal force and couple about the slider point from the same wrench;
* drive effort: ``sigma_d tau_d`` (above); the RNEA's own joint torque at the driver is
  the same number to round-off (its largest difference from every applied joint force
  is ``extra["rnea_residual"]``: 1e-15..1e-10 measured).
"""

from __future__ import annotations

import math

import numpy as np

from ...builders.tree import SimTree
from ..protocol import Recorder, Session, check_raw_state
from .model import PinocchioModel, _couple, _v3
from .settings import PinocchioSettings, require_pinocchio


class PinocchioSession(PinocchioModel, Session):
    """A Pinocchio model of one linkage, driven through its prescribed motion."""

    name = "pinocchio"
    settings_class = PinocchioSettings
    engine_readings = False

    def __init__(self, tree: SimTree, settings: PinocchioSettings | None = None):
        super().__init__(tree, settings)
        self.pin = require_pinocchio()
        self._build()
        self.acc = float(tree.mech.driver.acceleration)
        self.max_lambda_z = 0.0    # largest |z multiplier| read (the redundant row)
        self.rnea_residual = 0.0   # largest |RNEA joint force - applied|, N m or N
        self._h = 0.0              # the step the corrector's gains are set for (s)
        #: a free run's hook adding its force elements to the readout's ``fext``
        self.element_fext = None


    # ------------------------------------------------------------------ dynamics
    def _load_fext(self, fext) -> None:
        """Add the mechanism's loads to ``fext`` (joint-local wrenches; needs
        ``data.oMi`` of the current ``q``)."""
        pin, st = self.pin, self.tree
        for b, ld in self.loads:
            j = self.jid[b]
            if j == 0:
                continue
            oMi = self.data.oMi[j]
            R = oMi.rotation
            pt = st.com[b] if ld.point is None else st.mech.bodies[b].points[ld.point]
            r = _v3(np.asarray(pt, float) - self.offset[b])
            f = R.T @ _v3(ld.force)
            fext[j] = fext[j] + pin.Force(f, _couple(r, f, ld.torque))

    def _tau_loads(self, q, v) -> np.ndarray:
        """The loads as generalised forces ``J^T f`` (``constraintDynamics`` takes none)."""
        pin, m, d = self.pin, self.model, self.data
        if not self.loads:
            return np.zeros(self.nv)
        pin.forwardKinematics(m, d, q)
        fext = pin.StdVec_Force()
        for _ in range(m.njoints):
            fext.append(pin.Force.Zero())
        self._load_fext(fext)
        z = np.zeros(self.nv)
        return pin.rnea(m, d, q, v, z) - pin.rnea(m, d, q, v, z, fext)

    def _solve(self, q, v, tau):
        """``constraintDynamics`` at ``q, v`` with joint forces ``tau``: accelerations and
        the constraint forces (3 per loop, world axes, on joint 1)."""
        pin = self.pin
        a = pin.constraintDynamics(self.model, self.data, q, v, tau, self.cmodels,
                                   self.cdatas, self.prox).copy()
        # data.lambda_c: every constraint's contact_force stacked (reading them one by one
        # through the StdVec costs 30 us a constraint, the solve itself 40 us)
        return a, self.data.lambda_c.copy()

    def dynamics(self, q, v, acc: float):
        """Accelerations, constraint forces and the driver's generalised force with the
        driver's tree acceleration imposed (``sigma_d acc``): the dynamics is affine in
        the driver's force, solved at 0 and 1 and combined (module docstring)."""
        tau = self._tau_loads(q, v)
        a0, l0 = self._solve(q, v, tau)
        tau[self.drive_v] += 1.0
        a1, l1 = self._solve(q, v, tau)
        du = a1[self.drive_v] - a0[self.drive_v]
        td = (self.tree.driver_sigma * acc - a0[self.drive_v]) / du
        return a0 + td * (a1 - a0), l0 + td * (l1 - l0), td

    def _step(self, q, v, h: float):
        f = self.dynamics
        acc = self.acc
        if self.settings.integrator == "euler":
            a = f(q, v, acc)[0]
            v = v + h * a
            return q + h * v, v
        a1 = f(q, v, acc)[0]
        a2 = f(q + 0.5 * h * v, v + 0.5 * h * a1, acc)[0]
        v2 = v + 0.5 * h * a1
        a3 = f(q + 0.5 * h * v2, v + 0.5 * h * a2, acc)[0]
        v3 = v + 0.5 * h * a2
        a4 = f(q + h * v3, v + h * a3, acc)[0]
        v4 = v + h * a3
        return (q + h / 6.0 * (v + 2 * v2 + 2 * v3 + v4),
                v + h / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4))

    # ------------------------------------------------------------------ protocol
    def state(self):
        return self.q[self.vidx].copy(), self.v[self.vidx].copy()

    def reset(self, t: float, h: float) -> None:
        q, qd, (_, _, acc) = self.analytic_state(t)
        self.q = np.zeros(self.model.nq)
        self.v = np.zeros(self.nv)
        self.q[self.vidx], self.v[self.vidx] = q, qd
        self.acc = float(acc)
        self.set_baumgarte(h)
        self._h = h

    def advance(self, t: float, h: float, n: int) -> str | None:
        if h != self._h:
            self.set_baumgarte(h)
            self._h = h
        q, v = self.q, self.v
        try:
            for _ in range(n):
                q, v = self._step(q, v, h)
        except (RuntimeError, ValueError) as e:  # a failed factorisation: a divergence
            return f"Pinocchio failed ({str(e).strip().splitlines()[0][:120]})"
        self.q, self.v = q, v
        return check_raw_state(q, v)

    def record(self, t: float):
        why = check_raw_state(self.q, self.v)
        if why is not None:
            return None, 0.0, why
        return (self.q.copy(), self.v.copy(), self.acc), 0.0, None

    def forward_at(self, q, qd, acceleration: float, rows, rec: Recorder) -> None:
        Q, V = np.zeros(self.model.nq), np.zeros(self.nv)
        Q[self.vidx], V[self.vidx] = q, qd
        self.convert(np.zeros(1), [(Q, V, float(acceleration))], [list(np.atleast_1d(rows))],
                     rec)

    # ------------------------------------------------------------------ readout
    def convert(self, times, raws, rows, rec: Recorder):
        """The analytic conventions of K records (module docstring): the dynamics at
        each record's state, then the RNEA with the constraint forces for the tree
        joints' wrenches."""
        st, mech = self.tree, self.tree.mech
        K, J, P = len(raws), len(mech.joints), len(st.prismatic)
        nt = len(st.joints)
        q, qd, qdd = np.zeros((K, nt)), np.zeros((K, nt)), np.zeros((K, nt))
        force = np.zeros((K, J, 2))
        normal, moment, effort = np.zeros((K, P)), np.zeros((K, P)), np.zeros(K)
        self._gains(0.0)   # the dynamics at the state: no corrector (module docstring)
        try:
            for k, (Q, V, acc) in enumerate(raws):
                self._convert_one(k, Q, V, acc, q, qd, qdd, force, normal, moment, effort)
        finally:
            if self._h:
                self.set_baumgarte(self._h)
        _, gap, rate = rec.put_motions(rows, times, q, qd, qdd)
        rec.put_forces_many(rows, force, effort, normal, moment)
        return gap, rate

    def _convert_one(self, k, Q, V, acc, q, qd, qdd, force, normal, moment, effort):
        """Record ``k`` (state ``Q, V``, driver acceleration ``acc``) into row ``k`` of
        the arrays of :meth:`convert`."""
        try:
            a, lam, td = self.dynamics(Q, V, acc)
        except (RuntimeError, ValueError):
            a, lam, td = np.full(self.nv, np.nan), np.full(self.ncon, np.nan), np.nan
        q[k], qd[k], qdd[k] = Q[self.vidx], V[self.vidx], a[self.vidx]
        effort[k] = self.tree.driver_sigma * td
        if np.all(np.isfinite(a)):
            self._forces(Q, V, a, lam, td, force[k], normal[k], moment[k])
        else:
            force[k], normal[k], moment[k] = np.nan, np.nan, np.nan

    def _forces(self, Q, V, a, lam, td, force, normal, moment) -> None:
        """One record's joint forces (analytic conventions) into ``force (J, 2)``,
        ``normal, moment (P,)``: loops from the multipliers, tree joints from the RNEA
        with the constraint forces and loads as external forces."""
        pin, st, m, d = self.pin, self.tree, self.model, self.data
        mech = st.mech
        pin.forwardKinematics(m, d, Q)
        fext = pin.StdVec_Force()
        for _ in range(m.njoints):
            fext.append(pin.Force.Zero())
        self._load_fext(fext)
        if self.element_fext is not None:   # a free run's springs, dampers, motors
            self.element_fext(fext)
        L = lam.reshape(-1, 3)
        self.max_lambda_z = max(self.max_lambda_z, float(np.abs(L[:, 2]).max(initial=0.0)))
        for c, (ch, cm) in enumerate(zip(st.chords, self.cmodels, strict=True)):
            force[ch.joint] = self.chord_sign[c] * L[c, :2]
            for jnt, plc, s in ((cm.joint1_id, cm.joint1_placement, 1.0),
                                (cm.joint2_id, cm.joint2_placement, -1.0)):
                if jnt == 0:
                    continue
                R = d.oMi[jnt].rotation
                f = R.T @ (s * L[c])
                fext[jnt] = fext[jnt] + pin.Force(f, _couple(plc.translation, f))
        tau = pin.rnea(m, d, Q, V, a, fext)
        tau[self.drive_v] -= td   # what is left: the RNEA against constraintDynamics
        self.rnea_residual = max(self.rnea_residual, float(np.abs(tau).max()))
        for tj in st.joints:
            j = self.jid[tj.child]
            R, O = d.oMi[j].rotation, d.oMi[j].translation
            F, Mz = R @ d.f[j].linear, (R @ d.f[j].angular)[2]
            k = tj.joint
            if tj.kind == "hinge":
                force[k] = tj.sigma * F[:2]
                continue
            jt = mech.joints[k]
            sb = st.body_names.index(jt.slider)
            Pw = d.oMi[self.jid[sb]].act(_v3(np.asarray(mech.bodies[sb].points[jt.point])
                                             - self.offset[sb])) \
                if sb != st.ground else _v3(mech.bodies[sb].points[jt.point])
            MP = Mz + (O[0] - Pw[0]) * F[1] - (O[1] - Pw[1]) * F[0]
            gb = st.body_names.index(jt.guide)
            th_g = st.theta_ref[gb] + (Q[self.vidx] @ st.path[gb])
            ang = th_g + jt.direction
            n = np.array([-math.sin(ang), math.cos(ang)])
            p = st.prismatic.index(k)
            normal[p] = tj.sigma * (F[:2] @ n)
            moment[p] = tj.sigma * MP
            force[k] = normal[p] * n

    def extra(self) -> dict:
        return {"max_lambda_z": self.max_lambda_z, "constraint_rows": self.ncon,
                "rnea_residual": self.rnea_residual}


__all__ = ["PinocchioSession", "PinocchioSettings", "require_pinocchio"]
