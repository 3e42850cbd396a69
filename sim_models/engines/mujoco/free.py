"""MuJoCo released (free motion): :class:`MujocoFreeSession`, :class:`MujocoFreeSettings`.

The prescribed model (:func:`sim_models.builders.mjcf.build_mjcf`: the spanning tree, loops
closed by ``connect`` equalities) with the drive taken out (the driven joint's
armature 0, no ``qfrc_applied``), and the description's force elements built as
MuJoCo's own:

* **point springs and dampers**: a spatial tendon between two sites at the points,
  ``stiffness`` = k, ``springlength`` = the free length, ``damping`` = c (MuJoCo's
  tendon force ``-k (L - L0) - c L'``: tension, the description's sign);
* **joint springs and dampers**: a fixed tendon over the tree joints whose length is
  the joint's coordinate up to a constant (a revolute joint's ``theta_b - theta_a``
  is the sum of the hinge coordinates on the path from a to b, so a loop-closing
  joint works too), ``stiffness``/``damping``, its ``springlength`` set at the start
  from the released state;
* **motors**: a ``motor`` actuator on that fixed tendon (gain 1), ``ctrl`` = the
  effort, set before each step at the step's midpoint time (a table is then
  integrated to second order; constant efforts exactly); ``actuator_force`` is the
  engine's motor effort;
* gravity: MuJoCo's; constant loads: ``xfrc_applied`` at the centre of mass, set by
  the harness each step (harness-applied, frozen over an RK4 step).

Joint reactions are read as in the prescribed runs (``cfrc_int`` of the child for a
tree joint, the ``connect`` force for a cut joint).  Measured (MuJoCo 4.0, seed
four-bar released with a spatial-tendon spring and damper): ``cfrc_int`` includes the
tendons' forces on the bodies (the reactions agree with the reference's to 4e-5 of
peak as they are; subtracting the tendon forces again made them 0.3 of peak off).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from analytic import Revolute
from analytic.motion_spec import JointDamper, JointSpring, PointDamper, PointSpring

from ...builders.mjcf import HARD_SOLIMP, MujocoSettings, build_mjcf, direct_solref
from ...builders.tree import SimTree
from ...runs.engine_run import Recorder
from ...runs.sampling import times_plan
from ..free_protocol import (
    FreeRead,
    FreeSession,
    FreeStart,
)
from ..protocol import HUGE, EngineSettings
from .driven import MujocoSession


@dataclass(frozen=True)
class MujocoFreeSettings(EngineSettings):
    """MuJoCo's recommended free-motion settings (the fields of
    :class:`sim_models.builders.mjcf.MujocoSettings` that a released model uses).

    Evidence (``benchmarks/free_engine_grid.py grid``; worst joint-coordinate error
    over the run relative to its range, energy drift relative to the energy scale,
    stepping CPU s per simulated s on this shared 2-core machine, noisy to ~2x):

    ======================  ===========================  ============================
    integrator, timestep    A01, 5 s                     seed four-bar released, 2 s
    ======================  ===========================  ============================
    RK4 2e-3                2.3e-11, 0.03                7.5e-5, drift 2.5e-7, 0.04
    RK4 1e-3                1.9e-12, 0.05-0.10           1.1e-5, drift 3.3e-8, 0.07-0.10
    RK4 5e-4                3.7e-13, 0.14                9.6e-7, drift 2.5e-9, 0.14
    RK4 2.5e-4              2.9e-13, 0.23                1.6e-6, drift 2.2e-9, 0.33
    implicitfast/Euler 1e-3 6.8e-4, drift 1.3e-3         0.68, drift 3.2e-3, gap 1.3e-3
    implicitfast/Euler 2.5e-4 1.8e-4                     0.17, drift 8.0e-4
    ======================  ===========================  ============================

    ``implicitfast`` and ``Euler`` give the same numbers (no velocity-dependent force
    in these models: both are semi-implicit Euler) and are first order.  At RK4 1e-3 s
    the loop's ``solref`` time constant: 3 ms 9.1e-5, 10 ms 1.1e-5, 30 ms 8.5e-6,
    100 ms 2.1e-5; ``invweight_scale`` 1 (stock MuJoCo) 1.6e-3, 1e-3 1.1e-5, 1e-5
    1.2e-5.  RK4 at 5e-4 s: below that the error stops falling (the soft constraint's
    own error), so a smaller step only costs.  A01 has no loop: 1e-12 at any RK4 step.
    ``impratio`` and ``cone`` act on friction only (contacts are off): not settings here.
    """

    timestep: float = 5e-4
    integrator: str = "RK4"
    solref: tuple[float, float] = direct_solref(1e-2)
    solimp: tuple[float, float, float, float, float] = HARD_SOLIMP
    iterations: int = 100
    tolerance: float = 1e-12
    invweight_scale: float = 1e-3

    engine_name: ClassVar[str] = "mujoco"
    RANGES: ClassVar[Mapping[str, object]] = {
        k: MujocoSettings.RANGES[k] for k in ("timestep", "integrator", "solref", "solimp",
                                              "iterations", "tolerance", "invweight_scale")}

    def extra_problem(self):
        return MujocoSettings.extra_problem(self)  # the same solref sign rule

    def prescribed(self) -> MujocoSettings:
        """The prescribed-run settings these map to (the armature is removed after the
        build)."""
        return MujocoSettings(timestep=self.timestep, integrator=self.integrator,
                              solref=self.solref, solimp=self.solimp,
                              iterations=self.iterations, tolerance=self.tolerance,
                              invweight_scale=self.invweight_scale)


class MujocoFreeSession(MujocoSession, FreeSession):
    """A released MuJoCo model (see the module docstring)."""

    name = "mujoco"
    settings_class = MujocoFreeSettings
    motor_effort_source = "engine"
    native = ("gravity, point springs/dampers (spatial tendons), joint springs/dampers "
              "(fixed tendons), motors (motor actuator on a fixed tendon): MuJoCo's own; "
              "constant loads: harness (xfrc_applied each step)")

    def __init__(self, tree: SimTree, settings: MujocoFreeSettings | None = None):
        FreeSession.__init__(self, tree, settings)
        MujocoSession.__init__(self, tree, self.settings)

    def _build(self) -> None:
        st, s = self.tree, self.settings
        spec = build_mjcf(st.mech, s.prescribed(), tree=st)
        spec.joint(st.joints[st.driver_tree].name).armature = 0.0
        self._joint_tendons = self._add_elements(spec)
        self._compile(spec, s.prescribed(), acc=0.0, armature=0.0)  # no drive
        m = self.model
        fm = st.mech.motion
        self.motors = list(fm.motors) if fm else []
        self.motor_act = [m.actuator(f"motor:{i}").id for i in range(len(self.motors))]
        self.tables = any(mo.times for mo in self.motors)

    # -- model ----------------------------------------------------------------------
    def _coefficients(self, k: int) -> np.ndarray:
        """(nt,): joint ``k``'s coordinate per tree coordinate (a fixed tendon's coefs)."""
        st, mech = self.tree, self.tree.mech
        jt = mech.joints[k]
        c = np.zeros(len(st.joints))
        if isinstance(jt, Revolute):
            idx = {n: i for i, n in enumerate(st.body_names)}
            c = st.path[idx[jt.body_b]] - st.path[idx[jt.body_a]]
        else:
            ti = st.tree_joint_indices.index(k)
            c[ti] = st.joints[ti].sigma
        return c

    def _add_elements(self, spec) -> dict[int, tuple[str, np.ndarray]]:
        """Tendons and actuators of the force elements; returns joint index -> (fixed
        tendon name, coefficients) for :meth:`start` (its spring length)."""
        mj, st, mech = self.mj, self.tree, self.tree.mech
        fm = mech.motion
        if fm is None:
            return {}
        idx = {n: i for i, n in enumerate(st.body_names)}
        jidx = {j.name: k for k, j in enumerate(mech.joints)}
        bodies = {b: (spec.worldbody if b == st.ground else spec.body(st.body_names[b]))
                  for b in range(len(st.body_names))}
        joint_tendons: dict[int, tuple[str, np.ndarray]] = {}

        def fixed(k: int):
            if k not in joint_tendons:
                name = f"joint:{mech.joints[k].name}"
                t = spec.add_tendon(name=name)
                c = self._coefficients(k)
                for i in np.flatnonzero(c):
                    t.wrap_joint(st.joints[i].name, float(c[i]))
                joint_tendons[k] = (name, c)
            return spec.tendon(joint_tendons[k][0])

        for i, el in enumerate(fm.springs + fm.dampers):
            if isinstance(el, PointSpring | PointDamper):
                t = spec.add_tendon(name=f"element:{i}")
                for end, (bn, pn) in enumerate(((el.body_a, el.point_a),
                                                (el.body_b, el.point_b))):
                    p = mech.bodies[idx[bn]].points[pn]
                    bodies[idx[bn]].add_site(name=f"element:{i}:{end}",
                                             pos=[p[0], p[1], 0.0])
                    t.wrap_site(f"element:{i}:{end}")
            else:
                t = fixed(jidx[el.joint])
            # MuJoCo 4 takes stiffness and damping as polynomial coefficients (the
            # linear one first); 3.x as one number
            if isinstance(el, PointSpring | JointSpring):
                t.stiffness = _add_linear(t.stiffness, el.stiffness)
            if isinstance(el, PointSpring):
                t.springlength = [float(el.free_length), float(el.free_length)]
            elif isinstance(el, PointDamper | JointDamper):
                t.damping = _add_linear(t.damping, el.coefficient)
        for i, mo in enumerate(fm.motors):
            k = jidx[mo.joint]
            fixed(k)
            a = spec.add_actuator(name=f"motor:{i}", target=joint_tendons[k][0],
                                  trntype=mj.mjtTrn.mjTRN_TENDON)
            a.set_to_motor()
            a.gear = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]
            a.ctrllimited = mj.mjtLimited.mjLIMITED_FALSE
        return joint_tendons

    # -- the free protocol ----------------------------------------------------------
    def start(self, s0: FreeStart, h: float) -> None:
        mj, m, d = self.mj, self.model, self.data
        st, fm = self.tree, self.tree.mech.motion
        mj.mj_resetData(m, d)
        self.set_state(s0.q, s0.qd)
        jidx = {j.name: k for k, j in enumerate(st.mech.joints)}
        for s in (fm.springs if fm else ()):
            if isinstance(s, JointSpring):
                k = jidx[s.joint]
                name, c = self._joint_tendons[k]
                offset = s0.x[k] - float(c @ s0.q)   # x = offset + tendon length
                L0 = s.free_value - offset
                m.tendon_lengthspring[m.tendon(name).id] = [L0, L0]
        m.opt.timestep = h
        self._controls(0.0, h)
        mj.mj_kinematics(m, d)
        self.apply_loads()
        mj.mj_forward(m, d)

    def _controls(self, t: float, h: float) -> None:
        for a, mo in zip(self.motor_act, self.motors, strict=True):
            self.data.ctrl[a] = mo.at(t + 0.5 * h)

    def advance(self, t: float, h: float, n: int) -> str | None:
        mj, m, d = self.mj, self.model, self.data
        m.opt.timestep = h
        step = mj.mj_step
        if not (self.tables or self.moving_loads):
            if self.motors:
                self._controls(t, h)
            for _ in range(n):
                step(m, d)
        else:
            for k in range(n):
                self._controls(t + k * h, h)
                if self.moving_loads:
                    self.apply_loads()
                step(m, d)
        if not (abs(d.qvel.sum()) < HUGE and abs(d.qacc.sum()) < HUGE):
            return "non-finite or huge velocities (simulation diverged)"
        return None

    def read(self, t: float) -> FreeRead | None:
        mj, m, d, st = self.mj, self.model, self.data, self.tree
        for a, mo in zip(self.motor_act, self.motors, strict=True):
            d.ctrl[a] = mo.at(t)
        self.apply_loads()
        mj.mj_forward(m, d)
        if d.warning[self._badqacc].number:
            return None
        q, qd = d.qpos[self.qadr].copy(), d.qvel[self.dadr].copy()
        if not (np.isfinite(q).all() and np.isfinite(qd).all()):
            return None
        rec = Recorder(st, times_plan(st, np.array([t])))
        self.convert(np.array([t]), [self._raw(0.0)], [[0]], rec)
        qdd = d.qacc[self.dadr].copy()
        th, om, al, org, vo, _ = st.propagate(q[None], qd[None], qdd[None])
        force = rec.force[0].copy()
        eff = float(sum(d.actuator_force[a] for a in self.motor_act)) if self.motors \
            else math.nan
        return FreeRead(th[0], om[0], al[0], org[0], vo[0], force, eff)


def _add_linear(current, k: float):
    """``current`` (a number or MuJoCo 4's coefficient vector) plus ``k`` linear."""
    arr = np.atleast_1d(np.asarray(current, float)).copy()
    arr[0] += float(k)
    return arr if np.ndim(current) else float(arr[0])


__all__ = ["MujocoFreeSession", "MujocoFreeSettings"]
