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
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from analytic import Prismatic, Revolute

from ...builders.tree import SimModelError, SimTree
from .. import ranges
from ..protocol import (
    EngineRefusal,
    EngineSettings,
    Plan,
    Recorder,
    Session,
    fmt_value,
)


def require_exudyn():
    """The ``exudyn`` module, or a :class:`SimModelError` saying how to install it."""
    try:
        import exudyn
    except ImportError as e:  # pragma: no cover - exudyn is a dependency
        raise SimModelError(f"the exudyn engine needs the exudyn package "
                            f"(pip install exudyn): {e}") from None
    return exudyn


@dataclass(frozen=True)
class ExudynSettings(EngineSettings):
    """Exudyn settings (generalized-alpha, index 3, full Newton).

    Parameters
    ----------
    timestep
        Largest step, s.
    steps_per_rev
        Steps per revolution of the input (per run for a limited-range input).  The
        step is the smaller of ``timestep`` and the one these give; the run shortens
        it so that every sample falls on one.
    spectral_radius
        Generalized-alpha's spectral radius at infinity, rho_inf (1: no numerical
        damping, which lets the algebraic accelerations oscillate).
    newton_tolerance
        Relative and absolute tolerance of the Newton iteration (1e-12 cannot be met
        next to hibbeler-two-inclines' limit position; 1e-10 changes no other result).
    sample_by
        ``"integrator"``: accelerations and multipliers are the generalized-alpha
        step's own (``Coordinates_tt`` and the Lagrange multipliers at the step end).
        ``"state"``: they are the ones consistent with the integrated positions and
        velocities (one linear solve with Exudyn's mass matrix, constraint Jacobian and
        forces there; see the module docstring), as MuJoCo samples by ``mj_forward``;
        the integration itself is unchanged.  Measured 4-5x smaller errors at the same
        steps (25-60x for accelerating inputs), see the README "Exudyn" section.

    Evidence: speed-against-error grids over every built-in case; the worst error is
    taken relative to peak over every judged quantity, prismatic normal force and
    couple included, 36 samples of the 2nd revolution, no step cap
    (``/work/notes/exudyn_scratch/state_grid.csv``, ``final_grid_nocap.csv``):

    =========  ==============================  ==============================
    steps/rev  sample_by="state", rho 0.7/0.8  "integrator", rho 0.7/0.8/0.9
    =========  ==============================  ==============================
    360        3.3e-4 / 3.2e-4                 1.8e-3 / 4.0e-3 / 9.3e-3
    720        8.3e-5 / 7.9e-5                 4.1e-4 / 7.9e-4 / 2.7e-3
    1008       4.3e-5 / 4.0e-5                 2.1e-4 / 4.6e-4 / 2.8e-3
    1440       2.1e-5 / 2.0e-5                 1.0e-4 / 9.6e-5 / 5.7e-4
    2016       -                               5.3e-5 / 4.9e-5 / 2.5e-4
    =========  ==============================  ==============================

    Notes on the grid:

    * hibbeler-two-inclines is not in it: its worst sample sits next to a limit position,
      so it needs the step in seconds, hence the 5e-4 s cap;
    * the errors fall as dt^2;
    * sampling by state is 4-5x more accurate at the same steps, and 25-60x on
      accelerating inputs, because the integrator's own accelerations carry the
      disturbance of the step change the shared schedule makes at every sample of
      such an input (rho 0.8 leaves 2x more of it than 0.7, and 0.9 10x more);
    * sampling by state is insensitive to rho, and 0.8, the issue's value, is the best
      there;
    * rho 1 leaves the integrator's accelerations oscillating (7x peak on the
      four-bar).

    Change points: the session ends the run (a failed run, its reason naming the
    change point) when the prescribed motion meets one of the analytic branch
    schedule, because Exudyn cannot pass one reliably.  There the loop Jacobian loses
    rank while the input turns on, the index-3 Newton matrix is singular, the position
    along the singular direction is fixed only to about the square root of the Newton
    tolerance, and the integrator turns that into a velocity error.  Measured on
    ``analytic/cases/hard/parallelogram-four-bar.toml`` (2 revolutions, 36 samples):

    * defaults: forces 0.13 of peak off 10 deg past the change point (it decays over
      about 20 deg);
    * 1009 or 1440 steps/rev, or newton_tolerance 1e-12: the Newton fails there;
    * rho 0.1, 0.4, or 0.2 at 360 or 720 steps/rev: the run goes on along the
      anti-parallelogram branch (error 2 of peak); rho 0.5: 8e19;
    * rho 0, 0.2 or 0.3 at 1008 steps: 1e-10, but rho 0.2 doubles every other case's
      error (rho 0: 4x), so no setting passes reliably;
    * ``linearSolverSettings.ignoreSingularJacobian`` and ``pivotThreshold`` change
      nothing (the matrix is singular only to round-off).

    Only closed-form linkages list their change points (a Newton-path one is not
    checked).  MuJoCo and PyBullet pass the parallelogram.

    At the defaults every built-in case is within 3.7e-5 of peak (worst:
    hibbeler-16-30 linkCB.alpha; quick-return 2.6e-5, hibbeler-two-inclines 1.0e-5).
    The integrator's own readout needs 2016 steps for 5.7e-5.  A step costs about
    25-55 us on a 2-core AMD EPYC (README "Exudyn").
    """

    timestep: float = 5e-4
    steps_per_rev: int = 1008
    spectral_radius: float = 0.8
    newton_tolerance: float = 1e-10
    sample_by: str = "state"

    engine_name: ClassVar[str] = "exudyn"
    RANGES: ClassVar[Mapping[str, object]] = {
        "timestep": ranges.TIMESTEP,
        "steps_per_rev": ranges.STEPS_PER_REV,
        "spectral_radius": ranges.Range(0, 1, why="generalized-alpha's rho_inf: 0 damps "
                                        "the highest frequencies fully, 1 not at all"),
        # measured: the seed four-bar's Newton meets 1e-14, fails at 1e-15 (120 deg)
        "newton_tolerance": ranges.Range(1e-15, 1, why="relative and absolute; below "
                                         "1e-15 (5 x double round-off) no Newton can "
                                         "meet it"),
        "sample_by": ranges.Choice(("integrator", "state")),
    }

    def max_step(self, plan: Plan) -> float:
        return min(float(self.timestep), plan.rev_time / int(self.steps_per_rev))

    def describe(self) -> str:
        by = "" if self.sample_by == "integrator" else f" sampled by {self.sample_by}"
        return (f"gen-alpha rho={self.spectral_radius:g} steps/rev={self.steps_per_rev} "
                f"dt<={self.timestep:g} newton tol={self.newton_tolerance:g}{by}")


def _rot(a: float, v) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def _perp(v) -> np.ndarray:
    return np.array([-v[1], v[0]])


def _cross(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def _world(theta, r) -> np.ndarray:
    """(K, 2): body offset ``r`` (2,) turned by each angle of ``theta`` (K,)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([c * r[0] - s * r[1], s * r[0] + c * r[1]], axis=1)


def _world_many(theta, r) -> np.ndarray:
    """(K, B, 2): offsets ``r`` (B, 2) turned by angles ``theta`` (K, B)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([c * r[:, 0] - s * r[:, 1], s * r[:, 0] + c * r[:, 1]], axis=2)


def _perp_rows(v) -> np.ndarray:
    return np.stack([-v[:, 1], v[:, 0]], axis=1)


def _dot(a, b) -> np.ndarray:
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1]


def _cross_rows(a, b) -> np.ndarray:
    return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]


class ExudynSession(Session):
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

    def _ref_point(self, b: int, r) -> np.ndarray:
        """World position (m) of offset ``r`` of body ``b`` in the reference pose."""
        if b == self.g:
            return _rot(float(self.tree.kin_ref.theta[0, self.g]), r)
        return self.ref[b][:2] + _rot(self.ref[b][2], r)

    # ------------------------------------------------------------------ model
    def _build(self):
        self._add_drive(self._new_system())
        self._add_loads()
        self._assemble()
        self.drive_ae = int(self.mbs.systemData.GetObjectLTGAE(self.drive_obj)[0])

    def _new_system(self):
        """A new Exudyn system holding the ground, the bodies in the reference pose and the
        joints: what the driven and the released sessions share.  Returns the ground
        node (the drive's, or the released run's rotation markers')."""
        exu, st = self.exu, self.tree
        from exudyn import itemInterface as ii
        self.SC = exu.SystemContainer()
        mbs = self.mbs = self.SC.AddSystem()
        self.g = st.ground
        self.ground_obj = mbs.AddObject(ii.ObjectGround())
        ground_node = mbs.AddNode(ii.NodePointGround())
        self._add_bodies(mbs, st.kin_ref)
        self.joint_obj = [self._add_joint(jt) for jt in st.mech.joints]
        return ground_node

    def _assemble(self) -> None:
        """Assemble the system and index it: each body's ODE2 coordinates and reference
        coordinates, each joint's multipliers, the ODE2 size."""
        mbs = self.mbs
        mbs.Assemble()
        sd = mbs.systemData
        self.ltg = {b: np.array(sd.GetNodeLTGODE2(n)) for b, n in self.node.items()}
        self.ref = {b: np.array(mbs.GetNodeParameter(n, "referenceCoordinates"), float)
                    for b, n in self.node.items()}
        self.joint_ae = [np.array(sd.GetObjectLTGAE(o)) for o in self.joint_obj]
        self.n_ode2 = sd.ODE2Size()

    def _body_mass(self, b: int, body) -> tuple[float, float]:
        """Mass (kg) and inertia about the centre of mass (kg m^2) built for body ``b``."""
        st = self.tree
        if st.has_mass:  # exact: a massless link stays massless (module docstring)
            return float(body.mass), float(body.inertia)
        return float(st.mass[b]), float(st.inertia[b])

    def _add_bodies(self, mbs, kin) -> None:
        """One ``NodeRigidBody2D`` and ``ObjectRigidBody2D`` per moving body, in the
        reference pose ``kin`` (its first sample): fills ``node``, ``obj``, ``com``."""
        from exudyn import itemInterface as ii
        st = self.tree
        self.node, self.obj, self.com = {}, {}, {}
        for b, body in enumerate(st.mech.bodies):
            if b == self.g:
                continue
            m, inertia = self._body_mass(b, body)
            c = np.asarray(st.com[b], float)
            th = float(kin.theta[0, b])
            rG = kin.origin[0, b] + _rot(th, c)
            n = mbs.AddNode(ii.NodeRigidBody2D(referenceCoordinates=[rG[0], rG[1], th],
                                               initialCoordinates=[0.0, 0.0, 0.0],
                                               initialVelocities=[0.0, 0.0, 0.0]))
            self.obj[b] = mbs.AddObject(ii.ObjectRigidBody2D(mass=m, inertia=inertia,
                                                             nodeNumber=n))
            self.node[b], self.com[b] = n, c

    def _marker(self, b: int, p):
        """A rigid marker at body-frame point ``p`` (m) of body ``b``."""
        from exudyn import itemInterface as ii
        p = np.asarray(p, float)
        if b == self.g:
            return self.mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=self.ground_obj,
                                                         localPosition=[p[0], p[1], 0.0]))
        r = p - self.com[b]
        return self.mbs.AddMarker(ii.MarkerBodyRigid(bodyNumber=self.obj[b],
                                                     localPosition=[r[0], r[1], 0.0]))

    def _add_joint(self, jt):
        from exudyn import itemInterface as ii
        st = self.tree
        idx = {n: i for i, n in enumerate(st.body_names)}
        a, b = idx[jt.body_a], idx[jt.body_b]
        ma = self._marker(a, st.mech.bodies[a].points[jt.point_a])
        mb = self._marker(b, st.mech.bodies[b].points[jt.point_b])
        if isinstance(jt, Revolute):
            return self.mbs.AddObject(ii.RevoluteJoint2D(markerNumbers=[ma, mb]))
        d = jt.direction
        nn = d + math.pi / 2 - jt.angle  # the line normal in the slider frame
        return self.mbs.AddObject(ii.PrismaticJoint2D(
            markerNumbers=[ma, mb], axisMarker0=[math.cos(d), math.sin(d), 0.0],
            normalMarker1=[math.cos(nn), math.sin(nn), 0.0], constrainRotation=True))

    def _add_drive(self, ground_node):
        from exudyn import itemInterface as ii
        st, mbs = self.tree, self.mbs
        mech = st.mech
        d, djt = mech.driver, mech.driver_joint
        idx = {n: i for i, n in enumerate(st.body_names)}
        m_ground = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=ground_node, coordinate=0))
        self.sigma = None
        self._drive_a = self._drive_b = None
        if isinstance(djt, Revolute):
            a, b = idx[djt.body_a], idx[djt.body_b]
            self._drive_a, self._drive_b = a, b
            m0, m1 = (m_ground if x == self.g else mbs.AddMarker(
                ii.MarkerNodeCoordinate(nodeNumber=self.node[x], coordinate=2)) for x in (a, b))
        else:
            # sigma (displacement s - s_ref) is a massless coordinate tied to the slider's
            # displacement along the (ground) line; the drive constrains sigma
            sb = idx[djt.slider]
            u = np.array([math.cos(djt.direction), math.sin(djt.direction)])
            # MarkerNodeCoordinates carries total coordinates (reference + displacement)
            # into the CoordinateVector constraint: sigma's reference is u . x_G,ref
            s_ref = float(u @ mbs.GetNodeParameter(self.node[sb], "referenceCoordinates")[:2])
            self.sigma = mbs.AddNode(ii.NodeGenericODE2(referenceCoordinates=[s_ref],
                                                        initialCoordinates=[0.0],
                                                        initialCoordinates_t=[0.0],
                                                        numberOfODE2Coordinates=1))
            mbs.AddObject(ii.ObjectGenericODE2(nodeNumbers=[self.sigma],
                                               massMatrixUserFunction=0,
                                               massMatrix=np.zeros((1, 1))))
            mx = mbs.AddMarker(ii.MarkerNodeCoordinates(nodeNumber=self.node[sb]))
            ms = mbs.AddMarker(ii.MarkerNodeCoordinates(nodeNumber=self.sigma))
            # measured: the equation is X1 q1 - X0 q0 = 0, i.e. sigma = u . x_G
            mbs.AddObject(ii.ObjectConnectorCoordinateVector(
                markerNumbers=[mx, ms], scalingMarker0=np.array([[u[0], u[1], 0.0]]),
                scalingMarker1=np.array([[1.0]]), offset=[0.0]))
            m0 = m_ground
            m1 = mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=self.sigma, coordinate=0))
            self.drive_u = u
        w0, acc = float(d.velocity), float(d.acceleration)
        if acc == 0.0:
            self.drive_obj = mbs.AddObject(ii.CoordinateConstraint(
                markerNumbers=[m0, m1], offset=w0, velocityLevel=True))
            return

        def rate(mbs, t, item, offset):  # the prescribed driver rate at time t
            return w0 + acc * t

        self.drive_obj = mbs.AddObject(ii.CoordinateConstraint(
            markerNumbers=[m0, m1], velocityLevel=True, offsetUserFunction_t=rate))
        # the same function as a compiled expression tree (no Python call per Newton
        # iteration; measured 10-17 us a step, 15-20% of it); kept alive with the session
        from exudyn.utilities import CreateSymbolicUserFunction
        self._rate_fn = CreateSymbolicUserFunction(mbs, rate, "offsetUserFunction_t",
                                                   self.drive_obj)
        mbs.SetObjectParameter(self.drive_obj, "offsetUserFunction_t", self._rate_fn)

    def _add_loads(self):
        from exudyn import itemInterface as ii
        st, mbs = self.tree, self.mbs
        mech = st.mech
        gx, gy = mech.gravity
        if gx or gy:
            for b, o in self.obj.items():
                if mech.bodies[b].mass or not st.has_mass:
                    mk = mbs.AddMarker(ii.MarkerBodyMass(bodyNumber=o))
                    mbs.AddLoad(ii.LoadMassProportional(markerNumber=mk,
                                                        loadVector=[gx, gy, 0.0]))
        idx = {n: i for i, n in enumerate(st.body_names)}
        for ld in mech.loads:
            b = idx[ld.body]
            if b == self.g:  # a load on the ground moves nothing
                continue
            body = mech.bodies[b]
            p = body.points[ld.point] if ld.point is not None else self.com[b]
            mk = self._marker(b, p)
            if ld.force[0] or ld.force[1]:
                mbs.AddLoad(ii.LoadForceVector(markerNumber=mk,
                                               loadVector=[ld.force[0], ld.force[1], 0.0]))
            if ld.torque:
                mbs.AddLoad(ii.LoadTorqueVector(markerNumber=mk,
                                                loadVector=[0.0, 0.0, ld.torque]))

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

    # ------------------------------------------------------------------ readout
    def record(self, t: float):
        """Copies of the state at ``t``: coordinates, velocities, and either the
        integrator's own accelerations and multipliers (``sample_by="integrator"``) or
        Exudyn's constraint Jacobian and applied forces there (``"state"``: the
        accelerations and multipliers are solved from them in :meth:`convert`).  A
        non-finite state is a reason at once."""
        sd = self.mbs.systemData
        q, qd = np.array(sd.GetODE2Coordinates()), np.array(sd.GetODE2Coordinates_t())
        if not (math.isfinite(q.sum()) and math.isfinite(qd.sum())):
            return None, 0.0, "non-finite state (simulation diverged)"
        if self.settings.sample_by == "integrator":
            return (q, qd, np.array(sd.GetODE2Coordinates_tt()),
                    np.array(sd.GetAECoordinates())), 0.0, None
        C, f = self._jacobian_and_forces()
        return (q, qd, C, f), 0.0, None

    def _jacobian_and_forces(self):
        """Exudyn's constraint Jacobian ``C`` (nAE, nODE2; the drive's velocity-level row
        included) and its generalized applied forces ``f`` (nODE2) at the current state,
        from the probe solver's structures (no re-initialisation)."""
        pr, n = self.probe, self.n_ode2
        pr.SetSystemJacobian(self._zero_jacobian)  # ComputeJacobianAE adds into it
        pr.ComputeJacobianAE(self.mbs, 1.0, 1.0, 0.0, False)
        C = np.array(pr.GetSystemJacobian())[n:, :n]
        pr.ComputeODE2RHS(self.mbs)
        return C, np.array(pr.GetSystemResidual())[:n]

    def convert(self, times, raws, rows, rec: Recorder):
        """The analytic conventions of K records at once.  Sampling by state solves
        ``[M C^T; C 0] [q''; lambda] = [f; gamma]`` per record (one batched solve) with
        Exudyn's mass matrix, constraint Jacobian and forces at the record's state, and
        ``gamma`` the constraints' exact velocity terms (:meth:`_gamma`)."""
        q, qd, a3, a4 = (np.array(x) for x in zip(*raws, strict=True))
        times = np.asarray(times, float)
        if self.settings.sample_by == "integrator":
            qdd, lam = a3, a4
        else:
            qdd, lam = self._solve_state(times, q, qd, a3, a4)
        return self._readout(times, rows, rec, q, qd, qdd, lam)

    def _solve_state(self, times, q, qd, C, f):
        """Accelerations and multipliers consistent with the state (K records)."""
        K, n = q.shape
        m = C.shape[1]
        A = np.zeros((K, n + m, n + m))
        A[:, :n, :n] = self.M
        A[:, :n, n:] = C.transpose(0, 2, 1)
        A[:, n:, :n] = C
        b = np.concatenate([f, self._gamma(times, q, qd)], axis=1)
        try:
            x = np.linalg.solve(A, b[..., None])[..., 0]
        except np.linalg.LinAlgError:  # a singular record (a singular position): NaN there
            x = np.full_like(b, np.nan)
            for k in range(K):
                try:
                    x[k] = np.linalg.solve(A[k], b[k])
                except np.linalg.LinAlgError:
                    pass
        return x[:, :n], x[:, n:]

    def _geometry(self):
        """Per joint, the marker data the velocity terms need (built once)."""
        st = self.tree
        mech = st.mech
        idx = {nm: i for i, nm in enumerate(st.body_names)}
        out = []
        for k, jt in enumerate(mech.joints):
            a, b = idx[jt.body_a], idx[jt.body_b]
            pa = np.asarray(mech.bodies[a].points[jt.point_a], float)
            pb = np.asarray(mech.bodies[b].points[jt.point_b], float)
            ra = pa if a == self.g else pa - self.com[a]
            rb = pb if b == self.g else pb - self.com[b]
            extra = None
            if isinstance(jt, Prismatic):
                nn = jt.direction + math.pi / 2 - jt.angle
                extra = (np.array([math.cos(jt.direction), math.sin(jt.direction)]),
                         np.array([math.cos(nn), math.sin(nn)]))
            out.append((k, a, b, ra, rb, extra))
        return out

    def _bodies(self, q, qd, qdd=None):
        """theta, omega, alpha (K, B) and centre-of-mass position, velocity,
        acceleration (K, B, 2) of every body (the ground: fixed, its reference pose)."""
        K, B = len(q), len(self.tree.body_names)
        th = np.full((K, B), float(self.tree.kin_ref.theta[0, self.g]))
        om, al = np.zeros((K, B)), np.zeros((K, B))
        xG, vG, aG = np.zeros((K, B, 2)), np.zeros((K, B, 2)), np.zeros((K, B, 2))
        for b, ltg in self.ltg.items():
            th[:, b] = self.ref[b][2] + q[:, ltg[2]]
            om[:, b] = qd[:, ltg[2]]
            xG[:, b] = self.ref[b][:2] + q[:, ltg[:2]]
            vG[:, b] = qd[:, ltg[:2]]
            if qdd is not None:
                al[:, b] = qdd[:, ltg[2]]
                aG[:, b] = qdd[:, ltg[:2]]
        return th, om, al, xG, vG, aG

    def _gamma(self, times, q, qd):
        """``gamma = -(C q')_q q'`` per record (K, nAE), exactly, from the joints'
        geometry, in Exudyn's row signs (:meth:`_row_signs`), plus the prescribed driver
        acceleration on the drive row (which Exudyn's own initial solve leaves out)."""
        th, om, _, xG, vG, _ = self._bodies(q, qd)
        g = np.zeros((len(q), self.n_ae))
        for k, a, b, ra, rb, line in self._joints:
            Ra, va_, wa = _world(th[:, a], ra), vG[:, a], om[:, a]
            Rb, vb_, wb = _world(th[:, b], rb), vG[:, b], om[:, b]
            rows = self.joint_ae[k]
            if line is None:   # p_b - p_a = 0
                g[:, rows] = (wb * wb)[:, None] * Rb - (wa * wa)[:, None] * Ra
                continue
            t0, n1 = _world(th[:, a], line[0]), _world(th[:, b], line[1])
            d = (xG[:, b] + Rb) - (xG[:, a] + Ra if a != self.g else Ra)
            dv = (vb_ + wb[:, None] * _perp_rows(Rb)) - (va_ + wa[:, None] * _perp_rows(Ra))
            g[:, rows[0]] = (_dot(wb[:, None] ** 2 * Rb - wa[:, None] ** 2 * Ra, n1)
                             - 2 * wb * _dot(dv, _perp_rows(n1)) + wb * wb * _dot(d, n1))
            g[:, rows[1]] = (wb - wa) ** 2 * _dot(t0, n1)
        g *= self._signs
        g[:, self.drive_ae] = self._drive_sign * self.tree.driver_path(times)[2]
        return g

    def _row_signs(self):
        """Exudyn's sign of each joint's constraint rows relative to the ones
        :meth:`_gamma` is written for, from its Jacobian at the reference state (checked
        entry by entry: a different constraint form is an error here, not a wrong
        reading later)."""
        C, _ = self._jacobian_and_forces()
        q = np.zeros((1, self.n_ode2))
        th, _, _, _, _, _ = self._bodies(q, q)
        mine = np.zeros_like(C)
        for k, a, b, ra, rb, line in self._joints:
            rows = self.joint_ae[k]
            for body, r, s in ((a, ra, -1.0), (b, rb, 1.0)):
                if body == self.g:
                    continue
                cols = self.ltg[body]
                R = _world(th[:, body], r)[0]
                if line is None:
                    mine[rows[0], cols] = [s, 0.0, -s * R[1]]
                    mine[rows[1], cols] = [0.0, s, s * R[0]]
                    continue
                n1 = _world(th[:, b], line[1])[0]
                t0 = _world(th[:, a], line[0])[0]
                if body == b:   # (p_b - p_a) . n1 and t0 . n1, n1 turning with body b
                    d = self._ref_point(b, rb) - self._ref_point(a, ra)
                    mine[rows[0], cols] = [n1[0], n1[1], _perp(R) @ n1 + d @ _perp(n1)]
                    mine[rows[1], cols[2]] = t0 @ _perp(n1)
                else:
                    mine[rows[0], cols] = [-n1[0], -n1[1], -(_perp(R) @ n1)]
                    mine[rows[1], cols[2]] = _perp(t0) @ n1
        signs = np.ones(self.n_ae)
        for k, *_ in self._joints:
            for r in self.joint_ae[k]:
                s = 1.0 if C[r] @ mine[r] >= 0 else -1.0
                scale = max(np.abs(C[r]).max(), 1e-300)
                if np.abs(C[r] - s * mine[r]).max() > 1e-9 * scale:
                    raise SimModelError(
                        f"mechanism {self.tree.mech.name!r}: Exudyn's constraint row {r} "
                        f"(joint {self.tree.mech.joints[k].name!r}) is not the expected "
                        f"form: {C[r]} vs {s * mine[r]}")
                signs[r] = s
        # the drive row is q_b - q_a (rates): its acceleration equation is
        # row . q'' = +-acc with the sign of body b's (or sigma's) entry
        row = C[self.drive_ae]
        if self.sigma is not None:
            self._drive_sign = float(row[self.mbs.systemData.GetNodeLTGODE2(self.sigma)[0]])
        elif self._drive_b != self.g:
            self._drive_sign = float(row[self.ltg[self._drive_b][2]])
        else:
            self._drive_sign = -float(row[self.ltg[self._drive_a][2]])
        return signs

    def _readout(self, times, rows, rec: Recorder, q, qd, qdd, lam):
        """Fill ``rec`` from K records of coordinates, velocities, accelerations and
        multipliers; returns the loop gap (largest revolute gap, m) and driver rate."""
        st = self.tree
        mech = st.mech
        th, om, al, xG, vG, aG = self._bodies(q, qd, qdd)
        K, B = th.shape
        origin = xG - _world_many(th, np.array([self.com.get(b, np.zeros(2))
                                                for b in range(B)]))
        origin[:, self.g] = st.kin_ref.origin[0, self.g]
        J, P = len(mech.joints), len(st.prismatic)
        force = np.zeros((K, J, 2))
        sacc, normal, moment = np.zeros((K, P)), np.zeros((K, P)), np.zeros((K, P))
        effort = -lam[:, self.drive_ae]
        gap = np.zeros(K)

        def point(b, r):  # world position, velocity, acceleration of offset r of body b
            R = _world(th[:, b], r)
            if b == self.g:
                z = np.zeros_like(R)
                return R, z, z
            pR = _perp_rows(R)
            return (xG[:, b] + R, vG[:, b] + om[:, b, None] * pR,
                    aG[:, b] + al[:, b, None] * pR - (om[:, b] ** 2)[:, None] * R)

        for k, a, b, ra, rb, line in self._joints:
            L = lam[:, self.joint_ae[k]]
            jt = mech.joints[k]
            if line is None:
                force[:, k] = -L
                d = point(a, ra)[0] - point(b, rb)[0]
                gap = np.maximum(gap, np.hypot(d[:, 0], d[:, 1]))
                continue
            p = st.prismatic.index(k)
            ang = th[:, a] + jt.direction
            u = np.stack([np.cos(ang), np.sin(ang)], axis=1)
            n = _perp_rows(u)
            O, Ov, Oa = point(a, ra)
            S, Sv, Sa = point(b, rb)
            dd, dv, da = S - O, Sv - Ov, Sa - Oa
            wg, ag = om[:, a], al[:, a]
            # s = u . (S - O) differentiated twice with u turning with the guide
            sacc[:, p] = (_dot(ag[:, None] * n - (wg * wg)[:, None] * u, dd)
                          + 2 * wg * _dot(n, dv) + _dot(u, da))
            normal[:, p] = -L[:, 0]
            moment[:, p] = L[:, 1] + L[:, 0] * _dot(u, dd)
            if jt.name == mech.driver.joint:
                G = xG[:, b]
                moment[:, p] += _cross_rows(G - S, u) * effort
            force[:, k] = normal[:, p, None] * n
        value, rate = self._drivers(q, qd)
        rec.put_absolutes(rows, times, th, om, al, sacc, origin, value, rate)
        rec.put_forces_many(rows, force, effort, normal, moment)
        return gap, rate

    def _drivers(self, q, qd):
        """The driver's value (rad or m, unwrapped) and rate in the engine (K,)."""
        d = self.tree.mech.driver
        if self.sigma is not None:
            ls = self.mbs.systemData.GetNodeLTGODE2(self.sigma)[0]
            return d.value + q[:, ls], qd[:, ls]

        def rotation(x, v):  # rotation displacement (or rate) of body x (ground: 0)
            return v[:, self.ltg[x][2]] if x != self.g else np.zeros(len(v))

        a, b = self._drive_a, self._drive_b
        return (d.value + rotation(b, q) - rotation(a, q),
                rotation(b, qd) - rotation(a, qd))

    def extra(self) -> dict:
        return {"massless_exact": True}

    def close(self) -> None:
        if getattr(self, "SC", None) is not None:
            self.SC.Reset()
            self.SC = None
