"""PyBullet released (free motion): :class:`PybulletFreeSession`, :class:`PybulletFreeSettings`.

The prescribed model (:class:`sim_models.engines.pybullet.driven.PybulletSim`: the URDF tree,
loops closed by ``JOINT_POINT2POINT`` constraints, ERP-stabilised) with every joint's
motor switched off (``VELOCITY_CONTROL`` with force 0, as loaded) and no drive.
Gravity is PyBullet's.  PyBullet has no spring, damper or motor element between two
bodies, so the harness applies them **every step**: from the joint states (tree
coordinates) it computes each element's force (:class:`sim_models.engines.free_elements.
ElementLoads`) and applies it with ``applyExternalForce`` at the body's centre of
mass and ``applyExternalTorque`` (world frame); constant loads as in the prescribed
runs.  PyBullet clears external forces after each step, and the element forces are
those at the step's start (the semi-implicit Euler step's own order).

Readout at a sample (a step boundary): positions ``q_n``; the step leaves ``v_n``
about half a step behind them, so the velocity is ``v_n + (v_n - v_{n-1}) / 2`` and
the acceleration ``2 a_{n-1/2} - a_{n-3/2}`` from the last three velocities (both
second order; the prescribed runs step once more instead, which a free run cannot
undo).  Tree-joint forces by Newton-Euler from these accelerations and the loops'
constraint forces (:func:`sim_models.runs.newton_euler.reconstruct`), with the
harness-applied element forces taken out of each subtree
(:func:`sim_models.engines.free_protocol.subtree_correction`).  At t = 0, before any step, PyBullet
has no acceleration and no constraint force (it reads 0): alpha and the joint forces of
that sample are NaN (not measured).

Start: ``resetJointState`` to the released state, motors off.  The prescribed runs
pre-roll because PyBullet's first step after a reset ignores the loop under the
velocity motor; released, with the motors off, no such effect was measured: the seed
four-bar released at 15 rad/s (0.2 s, 1 ms samples) has the same x error at 1 ms
(2.89e-6 of range), the same alpha error at 1, 2, 3 ms (1.38e-4, 1.32e-4, 1.25e-4 of
range) and the same loop gap (1.2e-7 m) with a full first step and with a 1e-9 s first
step (``first_step``, default 0: none).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ...builders.tree import SimTree
from ...runs.newton_euler import reconstruct
from .. import ranges
from ..free_elements import ElementLoads
from ..free_protocol import (
    FreeRead,
    FreeSession,
    FreeStart,
    bodies_at,
    subtree_correction,
)
from ..protocol import EngineSettings
from .driven import PybulletModel, PybulletSettings, PybulletSim


@dataclass(frozen=True)
class PybulletFreeSettings(EngineSettings):
    """PyBullet's recommended free-motion settings.

    Parameters
    ----------
    timestep
        Step, s (shortened so samples fall on steps).  Semi-implicit Euler: first order.
    solver_iterations, residual_threshold, erp
        As :class:`sim_models.engines.pybullet.driven.PybulletSettings` (the loop constraints'
        solver sweeps, early stop, error-reduction parameter).
    max_joint_velocity
        PyBullet's speed clamp of every joint, rad/s or m/s.
    first_step
        Length of an extra first step after the reset, s (0: none; measured no effect,
        see the module docstring).

    Evidence (``benchmarks/free_engine_grid.py grid``; worst joint-coordinate error
    relative to its range, energy drift relative to the energy scale, stepping CPU s
    per simulated s on this shared 2-core machine):

    ========  ===========================  ==================================
    timestep  A01, 5 s                     seed four-bar released, 2 s
    ========  ===========================  ==================================
    4e-4      2.8e-4, drift 1.4e-6, 0.14   0.69, drift 1.4e-3, 0.18
    1e-4      7.1e-5, drift 9.0e-8, 0.32   0.25, drift 3.6e-4, 0.45
    2.5e-5    1.8e-5, drift 5.6e-9, 1.2    0.066, drift 8.9e-5, 1.6
    ========  ===========================  ==================================

    The error is first order in the step (semi-implicit Euler) and nothing else moves
    it: ``erp`` 0.2 / 0.8 / 1, 100 solver iterations and ``first_step`` change the
    seed's error by < 1% (the loop gap stays < 4e-6 of the size).  1e-4 s is the
    cost/accuracy compromise; an accuracy of 1e-3 of range over 2 s would need ~1e-7 s
    (about 500 CPU s per simulated s).
    """

    timestep: float = 1e-4
    solver_iterations: int = 20
    residual_threshold: float = 1e-30
    erp: float = 1.0
    max_joint_velocity: float = 1e4
    first_step: float = 0.0

    engine_name: ClassVar[str] = "pybullet"
    RANGES: ClassVar[Mapping[str, object]] = {
        **{k: PybulletSettings.RANGES[k] for k in ("timestep", "solver_iterations",
                                                   "residual_threshold", "erp",
                                                   "max_joint_velocity")},
        "first_step": ranges.Range(0, 1e-3, unit="s", why="a step before the first full "
                                   "one that absorbs PyBullet's first-step quirk; 0: none"),
    }

    def prescribed(self) -> PybulletSettings:
        return PybulletSettings(timestep=self.timestep,
                                solver_iterations=self.solver_iterations,
                                residual_threshold=self.residual_threshold, erp=self.erp,
                                max_joint_velocity=self.max_joint_velocity, preroll_steps=0)


class PybulletFreeSession(PybulletModel, FreeSession):
    """A released PyBullet model (see the module docstring)."""

    name = "pybullet"
    settings_class = PybulletFreeSettings
    integrator_name = "semi-implicit Euler"
    native = ("gravity: PyBullet's; springs, dampers, motors and constant loads: harness "
              "(applyExternalForce/applyExternalTorque each step, motors off)")

    def __init__(self, tree: SimTree, settings: PybulletFreeSettings | None = None):
        super().__init__(tree, settings)
        self.sim = PybulletSim(tree, self.settings.prescribed())
        self.elements = ElementLoads(tree)
        self.h = None
        self.v_hist: list[np.ndarray] = []
        self.link = [self.sim.link[n] for n in tree.body_names]
        fm = tree.mech.motion
        self.motors = list(fm.motors) if fm else []

    def _apply_elements(self, t: float) -> None:
        sim, p = self.sim, self.sim.p
        q, v, _, _ = sim.states()
        th, om, org, vo = bodies_at(self.tree, q, v)
        F, M = self.elements.wrenches(th, om, org, vo, t)
        st = self.tree
        for b in range(len(st.body_names)):
            if b == st.ground or not (F[b].any() or M[b]):
                continue
            G = org[0, b] + np.array([math.cos(th[0, b]) * st.com[b][0]
                                      - math.sin(th[0, b]) * st.com[b][1],
                                      math.sin(th[0, b]) * st.com[b][0]
                                      + math.cos(th[0, b]) * st.com[b][1]])
            p.applyExternalForce(sim.body, self.link[b], (F[b][0], F[b][1], 0.0),
                                 (G[0], G[1], 0.0), p.WORLD_FRAME, physicsClientId=sim.cid)
            p.applyExternalTorque(sim.body, self.link[b], (0.0, 0.0, M[b]), p.WORLD_FRAME,
                                  physicsClientId=sim.cid)

    def _step(self, t: float, h: float) -> None:
        self._set_step(h)
        if self.elements.any:
            self._apply_elements(t)
        if self.sim.loads:
            self.sim.apply_loads()
        self.sim.step()

    # -- the free protocol ----------------------------------------------------------
    def start(self, s0: FreeStart, h: float) -> None:
        self.elements.x0 = s0.x
        self.sim.set_state(s0.q, s0.qd)
        self.h = None
        self.v_hist = [np.asarray(s0.qd, float)]
        self.t0_step = float(self.settings.first_step)
        self._set_step(h)

    def advance(self, t: float, h: float, n: int) -> str | None:
        sim = self.sim
        plain = not (self.elements.any or sim.loads)
        self._set_step(h)
        for k in range(n):
            if self.t0_step > 0:  # the quirk-absorbing first step (module docstring)
                self._step(t, self.t0_step)
                self.t0_step = 0.0
                self._set_step(h)
            if plain and k < n - 3:
                sim.step()
            else:
                self._step(t + k * h, h)
            if k >= n - 3:  # the last three velocities (read())
                self.v_hist = (self.v_hist + [sim.states()[1]])[-3:]
        q, v = sim.states()[:2]
        if not (np.isfinite(q).all() and np.isfinite(v).all()):
            return "non-finite state (simulation diverged)"
        return None

    def read(self, t: float) -> FreeRead | None:
        st, sim = self.tree, self.sim
        q, v, _, tau = sim.states()
        if not (np.isfinite(q).all() and np.isfinite(v).all()):
            return None
        h = self.h or self.settings.timestep
        vh = self.v_hist
        if len(vh) >= 3:
            a1, a0 = (vh[2] - vh[1]) / h, (vh[1] - vh[0]) / h
            acc = 2 * a1 - a0
            vel = vh[2] + 0.5 * h * a1
        elif len(vh) == 2:
            acc = (vh[1] - vh[0]) / h
            vel = vh[1] + 0.5 * h * acc
        else:  # at the start: the exact rates; the acceleration is not read
            vel, acc = np.asarray(v, float), np.full(len(v), np.nan)
        th, om, al, org, vo, ao = st.propagate(q[None], vel[None], acc[None])
        cf = sim.constraint_forces()[None]
        F, _, _, _ = reconstruct(st, th, om, al, org, ao, cf)
        J = len(st.mech.joints)
        force = np.full((J, 2), np.nan)
        for k, jt in enumerate(st.mech.joints):
            if jt.name in F:
                force[k] = F[jt.name][0]
        if len(vh) < 2:
            # before the first step PyBullet has no constraint force (it reads 0) and no
            # acceleration: not measured
            force[:] = np.nan
        elif self.elements.any:
            Fe, _ = self.elements.wrenches(th, om, org, vo, t)
            force = subtree_correction(st, force, Fe)
        eff = self.elements.motor_effort(t)
        return FreeRead(th[0], om[0], al[0], org[0], vo[0], force, eff)


__all__ = ["PybulletFreeSession", "PybulletFreeSettings"]
