"""Exudyn backend: the linkage as an index-3 DAE, joint reactions from its multipliers.

Model (built from the compiled linkage, :class:`sim_models.builders.tree.SimTree`)
-------------------------------------------------------------------------
* one ``NodeRigidBody2D`` + ``ObjectRigidBody2D`` per moving body, the node at the
  body's centre of mass and turned with the body frame (coordinates ``[x_G, y_G,
  theta]``, reference = the analytic assembled pose, so the initial displacements
  are zero);
* **massless links are exact**: a body with ``mass = 0`` gets mass and inertia 0.
  The mass matrix is then singular, but the Newton matrix of the index-3 system
  stays regular because the constraint Jacobian (``2 J`` joint rows plus the
  drive row) is square and regular for a one-degree-of-freedom linkage away from
  singular positions; no floor mass is added (the MuJoCo/PyBullet trees need one).
  Kinematics-only descriptions get the tree's placeholder masses (their forces are
  not compared);
* every joint is a constraint (no spanning tree, no cut joints): ``RevoluteJoint2D``
  between ``MarkerBodyRigid`` markers at the two joint points (marker 0 on
  ``body_a``), ``PrismaticJoint2D`` with marker 0 on the guide at the line's origin
  point (``axisMarker0`` = line direction in the guide frame) and marker 1 on the
  slider at the slider point (``normalMarker1`` = line normal in the slider frame,
  rotation constrained), so a guide that itself moves needs nothing special;
* the drive is a ``CoordinateConstraint``: revolute, between the rotation
  coordinates of ``body_a`` (ground: a ground node) and ``body_b``; prismatic,
  between the ground and an auxiliary massless coordinate ``sigma`` that an
  ``ObjectConnectorCoordinateVector`` ties to the slider's displacement along the
  line (``u . dx_G - sigma = 0``; the guide must be the ground).  A constant-speed
  drive is a velocity-level constraint with the constant offset ``omega``; an
  accelerating one has the offset ``w0 + a t`` as an ``offsetUserFunction_t``,
  turned into Exudyn's symbolic (compiled expression) form, so no Python runs per
  Newton iteration; it is exact at every step end;
* gravity as ``LoadMassProportional``; loads as ``LoadForceVector`` /
  ``LoadTorqueVector`` at the load point's marker (world axes).

Solver: ``MainSolverImplicitSecondOrder`` (generalized-alpha, index 3), full Newton
with a 1e-10 tolerance, dense linear solver, stepped interval by interval with
``SolveSteps`` (the step schedule of :func:`sim_models.engines.protocol.drive`).
The initial state (reset, and the instantaneous mode's ``forward_at``) takes positions
and velocities from the analytic solution and the accelerations and multipliers from
Exudyn's own initial-value solve of its equations.  That solve omits the second
derivative of a user-function offset (documented for ``CoordinateConstraint``), so an
accelerating input would start with the wrong accelerations; the missing part is
solved with Exudyn's own mass matrix and constraint Jacobian at that state (see
``_with_drive_acceleration``).  At the exact state this agrees with the analytic
solution to 1e-8..1.2e-6 of peak for every built-in case (the instantaneous mode).

Readout (conventions of :mod:`sim_models.engines.protocol`), from the multipliers
``lambda`` (``GetAECoordinates``) with the signs measured against the analytic
solution (``/work/notes/exudyn_scratch``; an error of the wrong sign would be of
the order of the peak, the measured ones are 1e-5):

* revolute joint: the force by body_a (marker 0) on body_b (marker 1) is
  ``-lambda`` (Exudyn's ``M q'' + C_q^T lambda = f``);
* prismatic joint, ``lambda = [l0, l1]`` for ``(p1 - p0) . n1 = 0`` and
  ``t0 . n1 = 0``: the normal force by the guide on the slider is ``-l0``, its
  moment about the slider point ``l1 + l0 s'`` with ``s' = u . (P_slider -
  P_origin)``; for the driven prismatic joint the drive force acts at the slider's
  centre of mass in the model and at the slider point in the analytic convention,
  so ``(G - P) x u * effort`` is added to the moment; the joint force reported is
  ``normal * n`` (the analytic joint force of a prismatic joint);
* drive effort: minus the ``CoordinateConstraint``'s multiplier (torque on body_b,
  or force on the slider along the line);
* accelerations are ``Coordinates_tt``; ``s''`` of a slider on a moving guide
  includes the guide's rotation and Coriolis terms.

Which accelerations and multipliers: by default (``sample_by="state"``) the ones
consistent with the integrated positions and velocities of the sample (as MuJoCo
samples by ``mj_forward``): one linear solve per sample, ``[M C^T; C 0] [q'';
lambda] = [f; gamma]``, with Exudyn's mass matrix ``M`` (constant), and its constraint
Jacobian ``C`` and applied forces ``f`` at the sample's state (read through a solver
initialised once, whose structures are reused; no re-initialisation per sample), and
``gamma = -(C q')_q q'`` plus the prescribed drive acceleration written out per joint
(:meth:`ExudynSession._gamma`; the row signs checked against Exudyn's Jacobian when the
session is built).  This is the equation system of Exudyn's own initial-value solve,
whose ``gamma`` is a finite difference: at the exact state it is off by 1e-8..1.2e-6
of peak, the exact ``gamma`` by 1e-15..3e-11.  With ``sample_by="integrator"`` the
generalized-alpha step's own at the step end (which carry the disturbance of every
step change; see :class:`ExudynSettings`).

The readout is deferred (:meth:`ExudynSession.record` copies the raw state at each stop
of the run, :meth:`ExudynSession.convert` solves and converts every record at once,
vectorised) and the divergence check (loop gap, driver rate) runs on the converted
records, once per sample interval.
"""

from __future__ import annotations

import math

import numpy as np

from analytic import Prismatic

from ...builders.tree import SimTree
from ..protocol import (
    EngineRefusal,
    Recorder,
    Session,
    fmt_value,
)
from .model import ExudynModel
from .planar import _perp, _rot
from .readout import ExudynReadout
from .settings import ExudynSettings, require_exudyn


class ExudynSession(ExudynModel, ExudynReadout, Session):
    """A linkage in Exudyn (see the module docstring for the model and the readout)."""

    name = "exudyn"
    settings_class = ExudynSettings
    engine_readings = False

    def __init__(self, tree: SimTree, settings: ExudynSettings | None = None):
        super().__init__(tree, settings)
        self.exu = require_exudyn()
        mech = tree.mech
        djt = mech.driver_joint
        if isinstance(djt, Prismatic) and djt.guide != mech.ground:
            raise EngineRefusal(
                f"mechanism {mech.name!r}: the exudyn engine drives a prismatic joint only "
                f"on a ground guide; driver {djt.name!r} slides on the moving body "
                f"{djt.guide!r}")
        self._build()
        self.solver = None
        self.sim = None
        self.t = 0.0
        self._probe_setup()
        sch = tree.linkage.positions.schedule
        # closed-form branches meeting a change point (the Newton path lists none)
        self._may_cross = sch is not None and not sch.constant

    def _probe_setup(self):
        """A solver initialised once at the reference state whose structures the
        readout reuses (Jacobian, forces: :meth:`_jacobian_and_forces`), the constant
        mass matrix, and the joints' geometry and row signs for :meth:`_gamma`."""
        self.n_ae = self.mbs.systemData.AEsize()
        size = self.n_ode2 + self.n_ae
        self._zero_jacobian = np.zeros((size, size))
        self.probe = self._initialise(0.0, compute=False)
        self._probe_sim = self.sim  # the solver keeps a reference to its settings
        self.probe.ComputeMassMatrix(self.mbs)   # rigid bodies in 2D: constant
        self.M = np.array(self.probe.GetSystemMassMatrix())
        self._joints = self._geometry()
        self._signs = self._row_signs()


    # ------------------------------------------------------------------ stepping
    def _simulation_settings(self, t0: float):
        exu = self.exu
        s = exu.SimulationSettings()
        ti = s.timeIntegration
        ti.startTime = t0
        ti.endTime = 1e30            # SolveSteps is given each interval's end
        ti.numberOfSteps = 1
        ti.verboseMode = 0
        ga = ti.generalizedAlpha
        ga.spectralRadius = float(self.settings.spectral_radius)
        nt = ti.newton
        nt.useModifiedNewton = False
        nt.relativeTolerance = nt.absoluteTolerance = float(self.settings.newton_tolerance)
        s.solution.file.write = False       # no solution/ directory
        s.solution.sensors.active = False
        s.linearSolver.solverType = exu.LinearSolverType.EXUdense
        s.show.statistics = False
        s.show.computationTime = False
        s.show.globalTimers = False
        return s

    def reset(self, t: float, h: float) -> None:
        st = self.tree
        mech = st.mech
        val, vel, acc = (float(x) for x in st.driver_path(t))
        same = t == 0.0 and vel == mech.driver.velocity and acc == mech.driver.acceleration
        kin = st.kin_ref if same else st.linkage.kinematics(val, vel, acc)
        th, om = kin.theta[0], kin.omega[0]
        self._start(t, th, om, kin.origin[0], kin.v_origin[0], val, vel, acc)

    def forward_at(self, q, qd, acceleration: float, rows, rec: Recorder) -> None:
        """Exudyn's own accelerations and multipliers at a given state (tree
        coordinates), without stepping: its initial-value solve of the equations of
        motion and constraints, plus the drive acceleration it leaves out."""
        st = self.tree
        q, qd = np.asarray(q, float), np.asarray(qd, float)
        th, om, _, org, vo, _ = st.propagate(q[None], qd[None], np.zeros_like(q)[None])
        value = float(st.driver_value(q[st.driver_tree]))
        rate = float(st.driver_sigma * qd[st.driver_tree])
        self._start(0.0, th[0], om[0], org[0], vo[0], value, rate, float(acceleration))
        sd = self.mbs.systemData
        self._readout(np.zeros(1), [list(np.atleast_1d(rows))], rec,
                      *(np.array(x)[None] for x in (
                          sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t(),
                          sd.GetODE2Coordinates_tt(), sd.GetAECoordinates())))

    def _start(self, t, theta, omega, origin, v_origin, value, rate, acc) -> None:
        """Initial state from absolute body angles/rates and frame-origin positions and
        velocities (description order), the driver's value, rate and acceleration; then a
        solver started with Exudyn's own consistent accelerations and multipliers."""
        st, exu = self.tree, self.exu
        mech = st.mech
        q = np.zeros(self.n_ode2)
        qd = np.zeros(self.n_ode2)
        for b, ltg in self.ltg.items():
            r = _rot(theta[b], self.com[b])
            rG, vG = origin[b] + r, v_origin[b] + omega[b] * _perp(r)
            q[ltg] = [rG[0] - self.ref[b][0], rG[1] - self.ref[b][1],
                      theta[b] - self.ref[b][2]]
            qd[ltg] = [vG[0], vG[1], omega[b]]
        if self.sigma is not None:
            ls = self.mbs.systemData.GetNodeLTGODE2(self.sigma)[0]
            q[ls], qd[ls] = value - mech.driver.value, rate
        else:
            # the rotation coordinates must carry the turns the input has made
            a, b = self._drive_a, self._drive_b
            qa = q[self.ltg[a][2]] if a != self.g else 0.0
            qb = q[self.ltg[b][2]] if b != self.g else 0.0
            turns = 2 * math.pi * round(((value - mech.driver.value) - (qb - qa)) / (2 * math.pi))
            if b != self.g:
                q[self.ltg[b][2]] += turns
            else:
                q[self.ltg[a][2]] -= turns
        sd = self.mbs.systemData
        initial = exu.ConfigurationType.Initial
        sd.SetODE2Coordinates(q, configuration=initial)
        sd.SetODE2Coordinates_t(qd, configuration=initial)
        # accelerations and multipliers from Exudyn's own equations at this state
        sol = self._initialise(t, compute=True)
        if acc != 0.0:
            qdd, lam = self._with_drive_acceleration(sol, acc)
            sd.SetODE2Coordinates_tt(qdd, configuration=initial)
            sol = self._initialise(t, compute=False)
            # a restart zeroes the multipliers; they are only the Newton start of the
            # first step, and the reading of a sample at time t
            sd.SetAECoordinates(lam)
        self.solver = sol
        self.t = t

    def _initialise(self, t: float, compute: bool):
        """A new solver started from the initial state; ``compute``: Exudyn solves its
        equations of motion and constraints for the initial accelerations and
        multipliers, else it keeps the ones set."""
        self.sim = self._simulation_settings(t)
        self.sim.timeIntegration.generalizedAlpha.computeInitialAccelerations = compute
        sol = self.exu.MainSolverImplicitSecondOrder()
        if not sol.InitializeSolver(self.mbs, self.sim):
            raise EngineRefusal(f"mechanism {self.tree.mech.name!r}: Exudyn could not "
                                f"initialise its solver: {sol.GetErrorString()}")
        return sol

    def _with_drive_acceleration(self, sol, acc: float):
        """Initial accelerations and multipliers including the drive's prescribed
        acceleration, which Exudyn's initial solve leaves out (it has no second
        derivative of the offset).  The missing part solves Exudyn's own system
        ``[M C^T; C 0] [dq''; dlambda] = [0; acc e_drive]`` with its mass matrix and
        constraint Jacobian at this state (``C`` is square: ``2 J`` joint rows, the
        drive row, and the prismatic drive's tie row with its massless coordinate)."""
        mbs, n = self.mbs, self.n_ode2
        size = n + self.mbs.systemData.AEsize()
        # ComputeJacobianAE adds into the solver's Jacobian (measured: the drive row came
        # out doubled after the initial solve): clear it before each call
        sol.ComputeMassMatrix(mbs)
        M = np.array(sol.GetSystemMassMatrix())
        sol.SetSystemJacobian(np.zeros((size, size)))
        sol.ComputeJacobianAE(mbs, 1.0, 0.0, 0.0, False)     # position-level rows
        C = np.array(sol.GetSystemJacobian())[n:, :n]
        sol.SetSystemJacobian(np.zeros((size, size)))
        sol.ComputeJacobianAE(mbs, 0.0, 1.0, 0.0, False)     # the velocity-level drive row
        C[self.drive_ae] = np.array(sol.GetSystemJacobian())[n:, :n][self.drive_ae]
        e = np.zeros(C.shape[0])
        e[self.drive_ae] = 1.0
        r = np.linalg.solve(C, e)                            # q'' per unit drive acceleration
        mu = -np.linalg.solve(C.T, M @ r)
        sd = mbs.systemData
        return (np.asarray(sd.GetODE2Coordinates_tt()) + acc * r,
                np.asarray(sd.GetAECoordinates()) + acc * mu)

    def advance(self, t: float, h: float, n: int) -> str | None:
        if n <= 0:
            return None
        why = self._change_point_between(t, t + n * h)
        if why is not None:
            return why
        sol = self.solver
        sol.it.endTime = t + n * h
        sol.it.currentStepSize = h
        sol.it.maxStepSize = h
        try:
            ok = sol.SolveSteps(self.mbs, self.sim)
        except Exception as e:  # noqa: BLE001 - a failed Newton iteration is a divergence
            return f"Exudyn solver failed ({str(e).strip().splitlines()[0][:120]})"
        self.t = t + n * h
        if not ok:
            return f"Exudyn solver failed ({sol.GetErrorString().strip()[:120]})"
        q = self.mbs.systemData.GetODE2Coordinates()
        if not np.all(np.isfinite(q)):
            return "non-finite state (simulation diverged)"
        return None

    def _change_point_between(self, t0: float, t1: float) -> str | None:
        """The reason to stop when the prescribed motion meets a change point of the
        analytic branch schedule between times ``t0`` (excluded) and ``t1`` (s), else
        None.  At a change point the constraint Jacobian is singular and the index-3
        Newton cannot be trusted to pass it (see :class:`ExudynSettings`)."""
        if not self._may_cross:
            return None
        st = self.tree
        d = st.mech.driver
        ts = [t0, t1]
        if d.acceleration and t0 < -d.velocity / d.acceleration < t1:  # a reversal
            ts.append(-d.velocity / d.acceleration)
        vals = [float(st.driver_path(x)[0]) for x in ts]
        lo, hi = min(vals), max(vals)
        met = sorted((c.value for c in st.linkage.branch_crossings(lo, hi)
                      if lo <= c.value <= hi and c.value != vals[0]),
                     key=lambda v: abs(v - vals[0]))
        if not met:
            return None
        return (f"change point of driver {d.joint!r} at {fmt_value(st, met[0])}: Exudyn's "
                "index-3 Newton cannot pass it (singular constraint Jacobian; measured: "
                "the Newton fails, the run goes on along the other branch, or the "
                "velocities come out disturbed, forces 0.13 of peak off at the defaults; "
                "which one depends on the step and the spectral radius)")


    def extra(self) -> dict:
        return {"massless_exact": True}

    def close(self) -> None:
        if getattr(self, "SC", None) is not None:
            self.SC.Reset()
            self.SC = None
