"""Pinocchio released (free motion): :class:`PinocchioFreeSession`, :class:`PinocchioFreeSettings`.

The prescribed model (:class:`sim_models.engines.pinocchio.driven.PinocchioSession`: the tree of
``JointModelRZ`` / ``JointModelPrismaticUnaligned`` joints added depth first, the loops
closed by ``CONTACT_3D`` rigid constraints, ``constraintDynamics`` with the proximal
solver) with no drive: every evaluation is one ``constraintDynamics`` call with the
joint forces ``tau`` of the loads and force elements.  Gravity is ``model.gravity``.
Pinocchio has no spring, damper or motor element, and ``constraintDynamics`` takes no
external forces, so the harness applies the description's springs, dampers and motors
(:class:`sim_models.engines.free_elements.ElementLoads`, world wrenches about each centre of mass
from the bodies' state) as joint forces ``J^T f`` (two RNEA calls) at **every dynamics
evaluation**, i.e. at each RK4 stage with the stage's state and time: the elements are
integrated to the scheme's own order.

Integration: RK4 (or semi-implicit Euler) on ``q, v`` with the Baumgarte corrector of
the loop constraints, as the prescribed runs (:class:`PinocchioSettings`).  Readout at a
sample: the dynamics at the integrated state without the corrector; absolute body
states from the tree coordinates (:meth:`SimTree.propagate`); joint forces as the
prescribed runs (loops from the multipliers, tree joints from the RNEA with the
constraint forces, loads and element wrenches as ``fext``); the motor effort is the
harness's value (Pinocchio applies what it is given).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ...builders.tree import SimTree
from ..free_elements import ElementLoads
from ..free_protocol import FreeRead, FreeSession, FreeStart
from ..protocol import EngineSettings, check_raw_state
from .driven import PinocchioSession
from .model import _couple, _v3
from .settings import PinocchioSettings


@dataclass(frozen=True)
class PinocchioFreeSettings(EngineSettings):
    """Pinocchio's recommended free-motion settings (fields as
    :class:`sim_models.engines.pinocchio.driven.PinocchioSettings`, without ``steps_per_rev``:
    a free run has no revolution).

    Evidence: ``tests/sim_models/engines/test_free_engines.py`` and the README "Pinocchio"
    section (A01 and the released seed four-bar against the exact reference).
    """

    timestep: float = 1e-3
    integrator: str = "rk4"
    baumgarte: float = 0.05
    prox_mu: float = 1e-8
    prox_accuracy: float = 1e-12
    prox_max_iter: int = 20

    engine_name: ClassVar[str] = "pinocchio"
    RANGES: ClassVar[Mapping[str, object]] = {
        k: v for k, v in PinocchioSettings.RANGES.items() if k != "steps_per_rev"}


class PinocchioFreeSession(FreeSession):
    """A Pinocchio model of one linkage, released."""

    name = "pinocchio"
    settings_class = PinocchioFreeSettings
    integrator_name = "rk4"
    native = ("gravity (model.gravity) and the loop constraints; springs, dampers and "
              "motors applied by the harness as joint forces J^T f at every dynamics "
              "evaluation (each RK4 stage)")

    def __init__(self, tree: SimTree, settings: PinocchioFreeSettings | None = None):
        super().__init__(tree, settings)
        # the prescribed session builds the model; its drive is never used here
        self.m = PinocchioSession(tree, self.settings)
        self.pin = self.m.pin
        self.elements = ElementLoads(tree)
        self.t = 0.0

    # ------------------------------------------------------------------ elements
    def _absolute(self, Q, V):
        """theta, omega, origin, v_origin (1 row each) of the state ``Q, V``."""
        m, nt = self.m, len(self.tree.joints)
        th, om, _, org, vo, _ = self.tree.propagate(Q[m.vidx][None], V[m.vidx][None],
                                                    np.zeros((1, nt)))
        return th, om, org, vo

    def _element_fext(self, Q, V, t: float):
        """A function adding the force elements' wrenches at ``Q, V, t`` to joint-local
        ``fext`` (needs ``data.oMi`` of ``Q``); None when there are none."""
        if not self.elements.any:
            return None
        st, m, pin = self.tree, self.m, self.pin
        F, M = self.elements.wrenches(*self._absolute(Q, V), t)

        def add(fext):
            for b in range(len(st.body_names)):
                j = m.jid.get(b, 0)
                if j == 0 or not (F[b].any() or M[b]):
                    continue
                R = m.data.oMi[j].rotation
                f = R.T @ _v3(F[b])
                r = _v3(np.asarray(st.com[b], float) - m.offset[b])
                fext[j] = fext[j] + pin.Force(f, _couple(r, f, M[b]))
        return add

    def _tau(self, Q, V, t: float) -> np.ndarray:
        """Joint forces of the loads and the force elements at ``Q, V, t``."""
        m, pin = self.m, self.pin
        tau = m._tau_loads(Q, V)
        add = self._element_fext(Q, V, t)
        if add is None:
            return tau
        pin.forwardKinematics(m.model, m.data, Q)
        fext = pin.StdVec_Force()
        for _ in range(m.model.njoints):
            fext.append(pin.Force.Zero())
        add(fext)
        z = np.zeros(m.nv)
        return tau + pin.rnea(m.model, m.data, Q, V, z) - pin.rnea(m.model, m.data, Q, V, z,
                                                                   fext)

    def _acc(self, Q, V, t: float) -> np.ndarray:
        return self.m._solve(Q, V, self._tau(Q, V, t))[0]

    # ------------------------------------------------------------------ protocol
    def start(self, s0: FreeStart, h: float) -> None:
        m = self.m
        self.Q, self.V = np.zeros(m.model.nq), np.zeros(m.nv)
        self.Q[m.vidx], self.V[m.vidx] = s0.q, s0.qd
        self.elements = ElementLoads(self.tree, s0.x)
        m.set_baumgarte(h)
        m._h = h
        self.t = 0.0

    def advance(self, t: float, h: float, n: int) -> str | None:
        m = self.m
        if h != m._h:
            m.set_baumgarte(h)
            m._h = h
        Q, V = self.Q, self.V
        f = self._acc
        try:
            for i in range(n):
                ti = t + i * h
                if self.settings.integrator == "euler":
                    V = V + h * f(Q, V, ti)
                    Q = Q + h * V
                    continue
                a1 = f(Q, V, ti)
                v2 = V + 0.5 * h * a1
                a2 = f(Q + 0.5 * h * V, v2, ti + 0.5 * h)
                v3 = V + 0.5 * h * a2
                a3 = f(Q + 0.5 * h * v2, v3, ti + 0.5 * h)
                v4 = V + h * a3
                a4 = f(Q + h * v3, v4, ti + h)
                Q, V = (Q + h / 6.0 * (V + 2 * v2 + 2 * v3 + v4),
                        V + h / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4))
        except (RuntimeError, ValueError) as e:  # a failed factorisation: a divergence
            return f"Pinocchio failed ({str(e).strip().splitlines()[0][:120]})"
        self.Q, self.V, self.t = Q, V, t + n * h
        return check_raw_state(Q, V)

    def read(self, t: float) -> FreeRead | None:
        m, st = self.m, self.tree
        Q, V = self.Q, self.V
        if not (np.isfinite(Q).all() and np.isfinite(V).all()):
            return None
        J, P = len(st.mech.joints), len(st.prismatic)
        force, normal, moment = np.zeros((J, 2)), np.zeros(P), np.zeros(P)
        m._gains(0.0)   # the dynamics at the state, no corrector (as the prescribed runs)
        try:
            a, lam = m._solve(Q, V, self._tau(Q, V, t))
            if not np.isfinite(a).all():
                return None
            m.element_fext = self._element_fext(Q, V, t)
            m._forces(Q, V, a, lam, 0.0, force, normal, moment)
        except (RuntimeError, ValueError):
            return None
        finally:
            m.element_fext = None
            if m._h:
                m.set_baumgarte(m._h)
        nt = len(st.joints)
        th, om, al, org, vo, _ = st.propagate(Q[m.vidx][None], V[m.vidx][None],
                                              a[m.vidx][None] if nt else np.zeros((1, 0)))
        effort = self.elements.motor_effort(t)
        return FreeRead(th[0], om[0], al[0], org[0], vo[0], force,
                        effort if math.isfinite(effort) else math.nan)

    def close(self) -> None:
        self.m.close()


__all__ = ["PinocchioFreeSession", "PinocchioFreeSettings"]
