"""Exudyn released (free motion): :class:`ExudynFreeSession`, :class:`ExudynFreeSettings`.

The prescribed model (:mod:`sim_models.engines.exudyn.driven`: one ``ObjectRigidBody2D`` per
moving body, every joint a constraint, index-3 generalized-alpha) without the drive
constraint, and the description's force elements as Exudyn's own items:

* gravity ``LoadMassProportional`` and constant loads ``LoadForceVector`` /
  ``LoadTorqueVector``, as in the prescribed runs;
* **point springs and dampers**: ``ObjectConnectorSpringDamper`` between markers at the
  two points (``stiffness``, ``damping``, ``referenceLength`` = the free length);
* **revolute joint springs and dampers**: ``ObjectConnectorCoordinateSpringDamper``
  between the two bodies' rotation coordinates (the ground: a ground coordinate),
  its ``offset`` set from the released state so that it acts on the joint's
  coordinate ``x - x0``;
* **motors** on a revolute joint: ``LoadTorqueVector`` on body_b and the opposite on
  body_a (a table through a load user function: Python per evaluation);
* prismatic joints' springs, dampers and motors are not built (a refusal).

Readout: positions and velocities, the integrator's own accelerations at the step end,
joint forces from the multipliers as the prescribed runs (revolute ``-lambda``;
prismatic the normal force ``-l0`` along the line's normal).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from analytic import Prismatic, Revolute
from analytic.motion_spec import JointSpring, PointDamper, PointSpring

from ...builders.tree import SimTree
from ..free_protocol import FreeRead, FreeSession, FreeStart
from ..settings import EngineRefusal, EngineSettings
from .driven import ExudynSession
from .planar import _perp, _rot
from .settings import ExudynSettings, require_exudyn


@dataclass(frozen=True)
class ExudynFreeSettings(EngineSettings):
    """Exudyn's recommended free-motion settings (generalized-alpha, index 3, full
    Newton).  ``timestep`` s; ``spectral_radius`` rho_inf; ``newton_tolerance``
    relative and absolute (as :class:`sim_models.engines.exudyn.driven.ExudynSettings`).

    Evidence (``benchmarks/free_engine_grid.py grid``; worst joint-coordinate error
    relative to its range, energy drift relative to the energy scale, stepping CPU s
    per simulated s on this shared 2-core machine), rho_inf 0.6 / 0.8 / 0.95:

    ========  ====================================  ==================================
    timestep  A01, 5 s                              seed four-bar released, 2 s
    ========  ====================================  ==================================
    4e-3      2.1e-4 / 1.7e-4 / 1.6e-4              5.7e-2 / 2.0e-3 / 5.4e-3
    2e-3      6.8e-5 / 5.6e-5 / 5.3e-5              1.6e-2 / 1.2e-3 / 2.4e-3
    1e-3      2.0e-5 / 1.6e-5 / 1.5e-5 (0.06)       3.1e-3 / 5.6e-4 / 8.7e-4 (0.12)
    5e-4      5.3e-6 / 4.4e-6 / 4.2e-6 (0.12)       2.5e-4 / 1.9e-4 / 2.2e-4 (0.15)
    ========  ====================================  ==================================

    Second order in the step; rho_inf 0.8 is the best on the four-bar (0.6 damps the
    motion, 0.95 lets the constraint modes ring), and rho_inf 1 fails: its Newton gives
    up at t = 2.7 s of the released seed four-bar after the energy grew by 1.1 of its
    scale.  The loop gap stays at round-off (index 3).  The energy drift is the
    integrator's numerical dissipation: 2.1e-4 of the scale over 20 s at 1e-3 s,
    1.3e-5 at 2.5e-4 s (h^2).  5e-4 s costs little more than 1e-3 s (fewer Newton
    iterations a step) for 3x less error.
    """

    timestep: float = 5e-4
    spectral_radius: float = 0.8
    newton_tolerance: float = 1e-10

    engine_name: ClassVar[str] = "exudyn"
    RANGES: ClassVar[Mapping[str, object]] = {
        k: ExudynSettings.RANGES[k] for k in ("timestep", "spectral_radius",
                                              "newton_tolerance")}


class ExudynFreeSession(ExudynSession, FreeSession):
    """A released Exudyn model (see the module docstring)."""

    name = "exudyn"
    settings_class = ExudynFreeSettings
    integrator_name = "generalized-alpha (index 3)"
    native = ("gravity, constant loads, point springs/dampers (ConnectorSpringDamper), "
              "revolute joint springs/dampers (ConnectorCoordinateSpringDamper), motors "
              "(LoadTorqueVector; a table by a load user function): Exudyn's own")

    def __init__(self, tree: SimTree, settings: ExudynFreeSettings | None = None):
        FreeSession.__init__(self, tree, settings)
        self.exu = require_exudyn()
        self._refuse_prismatic_elements()
        self._may_cross = False
        self.solver = None
        self.sim = None
        self.t = 0.0
        self._build()

    def _refuse_prismatic_elements(self) -> None:
        mech = self.tree.mech
        fm = mech.motion
        for el in ((fm.springs + fm.dampers + fm.motors) if fm else ()):
            j = getattr(el, "joint", None)
            if j is not None and isinstance(mech.joint(j), Prismatic):
                raise EngineRefusal(f"mechanism {mech.name!r}: the exudyn free run does not "
                                    f"build springs, dampers or motors on prismatic joint "
                                    f"{j!r}")

    def _body_mass(self, b: int, body) -> tuple[float, float]:
        """The description's own mass and inertia (a free run needs them: the exact
        reference refuses a moving body without mass)."""
        return float(body.mass), float(body.inertia)

    def _build(self):
        self.ground_node = self._new_system()
        self._add_loads()
        self._coordinate_springs = self._add_elements()
        self._assemble()

    def _rotation_marker(self, b: int):
        from exudyn import itemInterface as ii
        if b == self.g:
            return self.mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=self.ground_node,
                                                              coordinate=0))
        return self.mbs.AddMarker(ii.MarkerNodeCoordinate(nodeNumber=self.node[b],
                                                          coordinate=2))

    def _add_elements(self) -> list[tuple[int, int, float]]:
        """Exudyn items of the force elements; returns (object, joint index, free
        value) of each coordinate spring-damper for :meth:`start` (its offset)."""
        from exudyn import itemInterface as ii
        st, mbs = self.tree, self.mbs
        mech = st.mech
        fm = mech.motion
        if fm is None:
            return []
        idx = {n: i for i, n in enumerate(st.body_names)}
        jidx = {j.name: k for k, j in enumerate(mech.joints)}
        coord = []
        for el in fm.springs + fm.dampers:
            if isinstance(el, PointSpring | PointDamper):
                a, b = idx[el.body_a], idx[el.body_b]
                ma = self._marker(a, mech.bodies[a].points[el.point_a])
                mb = self._marker(b, mech.bodies[b].points[el.point_b])
                spring = isinstance(el, PointSpring)
                mbs.AddObject(ii.ObjectConnectorSpringDamper(
                    markerNumbers=[ma, mb], stiffness=el.stiffness if spring else 0.0,
                    damping=0.0 if spring else el.coefficient,
                    referenceLength=el.free_length if spring else 0.0))
                continue
            jt = mech.joint(el.joint)
            a, b = idx[jt.body_a], idx[jt.body_b]
            spring = isinstance(el, JointSpring)
            o = mbs.AddObject(ii.ObjectConnectorCoordinateSpringDamper(
                markerNumbers=[self._rotation_marker(a), self._rotation_marker(b)],
                stiffness=el.stiffness if spring else 0.0,
                damping=0.0 if spring else el.coefficient, offset=0.0))
            coord.append((o, jidx[el.joint], el.free_value if spring else 0.0))
        for mo in fm.motors:
            jt = mech.joint(mo.joint)
            for b, sign in ((idx[jt.body_b], 1.0), (idx[jt.body_a], -1.0)):
                if b == self.g:
                    continue
                mk = self._marker(b, self.com[b])
                if not mo.times:
                    mbs.AddLoad(ii.LoadTorqueVector(markerNumber=mk,
                                                    loadVector=[0.0, 0.0, sign * mo.effort]))
                    continue

                def torque(mbs, t, load, mo=mo, sign=sign):
                    return [0.0, 0.0, sign * mo.at(t)]

                mbs.AddLoad(ii.LoadTorqueVector(markerNumber=mk, loadVector=[0.0, 0.0, 0.0],
                                                loadVectorUserFunction=torque))
        return coord

    # -- the free protocol ----------------------------------------------------------
    def start(self, s0: FreeStart, h: float) -> None:
        exu = self.exu
        q, qd = np.zeros(self.n_ode2), np.zeros(self.n_ode2)
        for b, ltg in self.ltg.items():
            r = _rot(s0.theta[b], self.com[b])
            rG, vG = s0.origin[b] + r, s0.v_origin[b] + s0.omega[b] * _perp(r)
            q[ltg] = [rG[0] - self.ref[b][0], rG[1] - self.ref[b][1],
                      s0.theta[b] - self.ref[b][2]]
            qd[ltg] = [vG[0], vG[1], s0.omega[b]]
        # a coordinate spring acts on u_b - u_a - offset (displacements, measured); the
        # joint's coordinate is x = x(0) + (u_b - u_a) - (u_b - u_a)(0)
        mech = self.tree.mech
        idx = {n: i for i, n in enumerate(self.tree.body_names)}
        for o, k, x_free in self._coordinate_springs:
            jt = mech.joints[k]
            ua, ub = (q[self.ltg[x][2]] if x != self.g else 0.0
                      for x in (idx[jt.body_a], idx[jt.body_b]))
            self.mbs.SetObjectParameter(o, "offset", float(x_free - s0.x[k] + (ub - ua)))
        sd = self.mbs.systemData
        initial = exu.ConfigurationType.Initial
        sd.SetODE2Coordinates(q, configuration=initial)
        sd.SetODE2Coordinates_t(qd, configuration=initial)
        self.solver = self._initialise(0.0, compute=True)
        self.t = 0.0

    def read(self, t: float) -> FreeRead | None:
        st = self.tree
        sd = self.mbs.systemData
        q, qd = np.array(sd.GetODE2Coordinates()), np.array(sd.GetODE2Coordinates_t())
        qdd, lam = np.array(sd.GetODE2Coordinates_tt()), np.array(sd.GetAECoordinates())
        if not (np.isfinite(q).all() and np.isfinite(qd).all()):
            return None
        th, om, al, xG, vG, _ = self._bodies(q[None], qd[None], qdd[None])
        B = len(st.body_names)
        org, vo = np.zeros((B, 2)), np.zeros((B, 2))
        for b in range(B):
            if b == self.g:
                org[b] = st.kin_ref.origin[0, b]
                continue
            r = _rot(th[0, b], self.com[b])
            org[b], vo[b] = xG[0, b] - r, vG[0, b] - om[0, b] * _perp(r)
        mech = st.mech
        force = np.full((len(mech.joints), 2), np.nan)
        idx = {n: i for i, n in enumerate(st.body_names)}
        for k, jt in enumerate(mech.joints):
            if isinstance(jt, Revolute):
                force[k] = -lam[self.joint_ae[k][:2]]
                continue
            # the normal force -l0 along the line's normal, as the prescribed readout
            ang = th[0, idx[jt.guide]] + jt.direction
            force[k] = -lam[self.joint_ae[k][0]] * np.array([-math.sin(ang), math.cos(ang)])
        fm = mech.motion
        eff = float(sum(mo.at(t) for mo in fm.motors)) if fm and fm.motors else math.nan
        return FreeRead(th[0], om[0], al[0], org, vo, force, eff)

    def integrator(self) -> str:
        return f"{self.integrator_name}, rho_inf={self.settings.spectral_radius:g}"


__all__ = ["ExudynFreeSession", "ExudynFreeSettings"]
