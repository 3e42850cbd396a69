"""MuJoCo Warp released (free motion): :class:`MujocoWarpFreeSession`,
:class:`MujocoWarpFreeSettings`.

The released MuJoCo model of :mod:`sim_models.engines.mujoco.free` (the same build: no drive,
the description's springs, dampers and motors as MuJoCo's tendons and actuators,
gravity MuJoCo's, constant loads harness-applied each step) put on a Warp device and
stepped by MuJoCo Warp in **float32** (:class:`sim_models.engines.mujoco_warp.driven.
WarpStepping`: the step captured as a Warp graph, ``Jdot v`` refreshed before each RK4
stage).  Motor controls and moving loads are written to Warp's data before each step
(harness side, as in MuJoCo's free session).

Readout: the **trajectory is Warp's** (``qpos``, ``qvel`` copied from the device at
each sample time); the accelerations, joint reactions and motor effort at a sample are
the host MuJoCo's ``forward`` at that state (float64), so what is judged (the joint
coordinates and rates, the energy and the loop gap, all functions of the state) is
what float32 stepping made of the motion, and the readout adds no float32 error of its
own.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ...builders.tree import SimTree
from ...runs.precision import FLOAT32
from .. import ranges
from ..free_protocol import FreeRead, FreeStart
from ..mujoco.free import MujocoFreeSession, MujocoFreeSettings
from .driven import WarpStepping, require_warp


@dataclass(frozen=True)
class MujocoWarpFreeSettings(MujocoFreeSettings):
    """MuJoCo Warp's free-motion settings: MuJoCo's released model
    (:class:`sim_models.engines.mujoco.free.MujocoFreeSettings`) and Warp's own fields (as
    :class:`sim_models.engines.mujoco_warp.driven.MujocoWarpSettings`).

    Evidence (seed four-bar released under gravity for 2 s, 200 samples; worst error of
    range, CPU s per simulated s on the shared 2-core machine):

    * **invweight_scale 3e-2** (measured 2026-11-28, the full report's releases, 2 s,
      400 samples, CG, RK4 1e-3 s): at 1 (stock weights) the offset and inverted
      slider-cranks failed with 0.123 and 0.046 (MuJoCo float64 with the same settings
      gives the same 0.123 and 0.046, and the step does not move them: the soft loop,
      not float32 nor the step); worst error at 1 / 0.1 / 3e-2 / 1e-2: offset 0.123 /
      9.3e-3 / 7.5e-4 / 3.8e-3, inverted 4.6e-2 / 5.1e-3 / 2.0e-3 / 7.4e-4, six-bar
      7.1e-4 / 6.2e-4 / 1.6e-3 / 9.0e-3, seed four-bar 2.3e-3 / - / 1.6e-3 / 3.7e-3:
      3e-2 keeps every case within a fifth of the 1e-2 tolerance.
    * **solver CG** (earlier, at invweight_scale 1, stock MuJoCo's inverse weights): Newton at the
      prescribed runs' 1e-2 starts from wrong accelerations without the drive's armature
      (coupler qacc -19.2 for MuJoCo's -22.77 rad/s^2) and its state is NaN after one
      step; Newton at 0.1 diverges at 0.05 s, Newton at 1 reaches 2.4e-2 (horizon 1.07 s
      at 1e-2).  CG at 1: 2.2e-3 (MuJoCo float64 with stock weights: 1.6e-3); CG at 1e-2
      3.6e-3, at 1e-3 0.13 (float32 cannot carry the near-hard rows' regularisation).
    * **RK4 1e-3 s**: CG at 1e-2, 5e-4 / 1e-3 / 2e-3 s: 2.5e-3 / 3.6e-3 / 6.2e-3 at
      0.56 / 0.34 / 0.23 CPU s per s.
    ``tolerance`` 1e-10 (``put_model`` raises it to 1e-6; written back).
    * **iterations 1000** (the range's cap): on A02 (N = 40, 120 loop rows) CG at 100
      iterations hits its cap (``d.overflow`` ``ITERATIONS``) and the energy wanders by
      1.01 J over the first 2 s (MuJoCo float64, same model and step: 4.5e-3 J); at 1000
      the cap is not hit and it is 4.2e-2 J (Newton: 4.6e-2 J; half the step at 100
      iterations: 0.78 J, so the unconverged solve, not the step).  On the released seed
      four-bar, where CG converges first, 100 and 1000 give the same run.
    """

    timestep: float = 1e-3
    iterations: int = 1000
    tolerance: float = 1e-10
    invweight_scale: float = 3e-2
    solver: str = "CG"
    fresh_jdotv: bool = True
    device: str = "auto"

    engine_name: ClassVar[str] = "mujoco_warp"
    arithmetic: ClassVar = FLOAT32
    RANGES: ClassVar[Mapping[str, object]] = {
        **MujocoFreeSettings.RANGES,
        "solver": ranges.Choice(("Newton", "CG"), fold=True),
        "fresh_jdotv": ranges.FLAG,
        "device": ranges.Choice(("auto", "cpu", "cuda")),
    }


class MujocoWarpFreeSession(WarpStepping, MujocoFreeSession):
    """A released MuJoCo model stepped by MuJoCo Warp (see the module docstring)."""

    name = "mujoco_warp"
    settings_class = MujocoWarpFreeSettings
    native = ("as MuJoCo's free session (gravity, tendons, motor actuators: the engine's "
              "own; constant loads: harness), stepped by MuJoCo Warp in float32")

    def __init__(self, tree: SimTree, settings: MujocoWarpFreeSettings | None = None):
        self.wp, self.mjw = require_warp()
        super().__init__(tree, settings)

    def _build(self) -> None:
        super()._build()  # the released host model (MujocoFreeSession)
        self._put_warp()

    def extra(self) -> dict:
        return {"device": self.device.alias, "precision": self.settings.arithmetic.name}

    # -- the free protocol ----------------------------------------------------------
    def start(self, s0: FreeStart, h: float) -> None:
        super().start(s0, h)  # host: state, joint springs' lengths, controls, loads
        wp, m = self.wp, self.model
        with wp.ScopedDevice(self.device):
            if m.ntendon:  # a joint spring's free length is set at the start
                self.wm.tendon_lengthspring.assign(
                    np.asarray(m.tendon_lengthspring, np.float32))
            self.wm.opt.timestep.fill_(float(h))
            self._put_state()
            self._put_controls()
        self.wp.capture_launch(self._graphs()[1])

    def _put_controls(self) -> None:
        if self.model.nu:
            self.wd.ctrl.assign(np.asarray(self.data.ctrl, np.float32)[None])

    def advance(self, t: float, h: float, n: int) -> str | None:
        wp = self.wp
        self.wm.opt.timestep.fill_(float(h))
        step = self._graphs()[0]
        if not (self.tables or self.moving_loads):
            if self.motors:
                self._controls(t, h)
                self._put_controls()
            for _ in range(n):
                wp.capture_launch(step)
        else:
            for k in range(n):
                self._controls(t + k * h, h)
                self._put_controls()
                if self.moving_loads:
                    self._loads()
                wp.capture_launch(step)
        return self._diverged()

    def read(self, t: float) -> FreeRead | None:
        """Warp's state at ``t`` read out by the host MuJoCo (module docstring)."""
        h, d = self.data, self.wd
        h.qpos[:] = d.qpos.numpy()[0]
        h.qvel[:] = d.qvel.numpy()[0]
        h.time = float(t)
        if not (np.isfinite(h.qpos).all() and np.isfinite(h.qvel).all()):
            return None
        return super().read(t)


__all__ = ["MujocoWarpFreeSession", "MujocoWarpFreeSettings"]
