"""MuJoCo Warp's settings (:class:`MujocoWarpSettings`: the MuJoCo model's solver
settings, the float32 arithmetic, Warp's own fields) with their evidence; the session is
:mod:`sim_models.engines.mujoco_warp.driven`."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

from ...builders.mjcf import HARD_SOLIMP, MujocoSettings, direct_solref
from ...runs.precision import FLOAT32
from .. import ranges
from ..settings import EngineSettings

_INTEGRATORS = ("RK4", "Euler", "implicitfast", "implicit")


@dataclass(frozen=True)
class MujocoWarpSettings(EngineSettings):
    """Settings of the MuJoCo model run by MuJoCo Warp (float32; evidence below).

    Evidence (2 revolutions, 36 samples of the 2nd, worst error / peak over
    accelerations, pin forces and drive effort; 2-core CPU, Warp's CPU device):

    * **timestep 2.5e-3 s** (a cap: the step is set by ``steps_per_rev``): it shortens
      only hibbeler-two-inclines' step among the built-in cases (its 2.7 s run took 591
      steps of 4.7 ms, now 1101 of 2.5 ms): at 4.7 ms it had 1.1e-3 (slideB.a near the
      limit position), and MuJoCo float64 on the same model and step had 1.2e-3 there,
      so that miss was the step, not float32; at 2.5 ms 1.6e-4 (MuJoCo float64 1.1e-4).
    * **steps_per_rev 576**: float32 ``qpos`` rounds
      every step, so the floor grows with the step count, not with the step: seed
      four-bar RK4, one revolution, 431 / 863 / 1691 / 4211 steps: 5.9e-5 / 6.1e-5 /
      2.8e-4 / 7.0e-4.  Over 144 / 288 / 576 steps a revolution (RK4, float32 readout):
      hibbeler-16-121 1.7e-2 / 1.1e-3 / 3.3e-4, six-bar 1.1e-3 / 4.9e-4 / 6.6e-4,
      seed-four-bar 3.8e-4 / 2.8e-4 / 2.6e-4, inverted-slider-crank 4.8e-4 / 4.4e-4 /
      5.3e-4, seed-slider-crank 8.4e-5 / 8.9e-5 / 2.8e-4.  At 576 (and the 2.5 ms cap)
      every built-in case is within 1e-3 (README, "MuJoCo Warp"); at 2304 the float32
      rounding dominates (error / (u32 steps condition) 0.6-3.0: :mod:`sim_models.runs.precision`).
    * **RK4** (with ``fresh_jdotv``): Euler at dt 2.5e-4 left 1.7e-3 on the seed
      four-bar (MuJoCo's Euler 1.4e-3 there); stock RK4 lost the 200 rad/s slider-crank's
      loop.
    * **invweight_scale 1e-2**: the 200 rad/s slider-crank 4.3e-4 at 1.0, 3.6e-5 at 1e-2
      and 3.8e-5 at 1e-3 (dt 2.5e-4); the seed four-bar the same at all three.
    * **tolerance 1e-10**, **iterations 100**, **Newton**: 1e-8, 1e-10 and 20 iterations
      gave the same errors; CG before the fixes read forces 37x peak off.  Samples are
      solved with tolerance 0 (:meth:`MujocoWarpSession._sample`).
    * **readout host**: quick-return's slot moment 1.3e-2 of peak (float32 ``cfrc_int``)
      against 2.5e-4.

    Parameters
    ----------
    steps_per_rev
        The step is the smaller of ``timestep`` and one revolution / ``steps_per_rev``.
    timestep, integrator, solref, solimp, iterations, armature, invweight_scale
        As :class:`sim_models.builders.mjcf.MujocoSettings` (the same model is built).
    tolerance
        Constraint solver tolerance (MuJoCo Warp raises its default to >= 1e-6 for
        float32; the session writes this value back).
    solver
        ``"Newton"`` or ``"CG"`` (MuJoCo Warp's constraint solvers).
    fresh_jdotv
        Update ``cvel``/``cdof_dot`` at the present state before each step and sample
        (:meth:`MujocoWarpSession._fresh_velocities`: MuJoCo Warp 4.0.0 builds the loop
        rows' ``Jdot v`` from the previous call's velocities).  ``False``: stock.
    readout
        ``"warp"``: the joint forces from Warp's own ``rne_postconstraint`` (float32
        ``cfrc_int``), as a GPU user reads them; ``"host"``: Warp's accelerations and
        constraint forces read out in float64 by the host MuJoCo
        (:meth:`MujocoWarpSession._raw_host`).
    device
        ``"auto"`` (first CUDA device if any, else the CPU), ``"cpu"`` or ``"cuda"``.
    """

    timestep: float = 2.5e-3
    steps_per_rev: int = 576
    integrator: str = "RK4"
    solver: str = "Newton"
    solref: tuple[float, float] = direct_solref(1e-2)
    solimp: tuple[float, float, float, float, float] = HARD_SOLIMP
    iterations: int = 100
    tolerance: float = 1e-10
    armature: float = 1e8
    invweight_scale: float = 1e-2
    fresh_jdotv: bool = True
    readout: str = "host"
    device: str = "auto"

    engine_name: ClassVar[str] = "mujoco_warp"
    #: float32 kernels: the error floor of :mod:`sim_models.runs.precision`
    arithmetic: ClassVar = FLOAT32
    RANGES: ClassVar[Mapping[str, object]] = {
        **{k: MujocoSettings.RANGES[k] for k in ("timestep", "solref", "solimp", "iterations",
                                                 "tolerance", "armature", "invweight_scale")},
        "steps_per_rev": ranges.STEPS_PER_REV,
        "integrator": ranges.Choice(_INTEGRATORS, fold=True),
        "solver": ranges.Choice(("Newton", "CG"), fold=True),
        "fresh_jdotv": ranges.FLAG,
        "readout": ranges.Choice(("warp", "host")),
        "device": ranges.Choice(("auto", "cpu", "cuda")),
    }

    def extra_problem(self) -> tuple[str, str] | None:
        """solref: as :meth:`MujocoSettings.extra_problem`."""
        return self.mujoco_settings().extra_problem()

    def max_step(self, plan) -> float:
        """The smaller of ``timestep`` and one revolution / ``steps_per_rev`` (s)."""
        return min(float(self.timestep), plan.rev_time / int(self.steps_per_rev))

    def mujoco_settings(self) -> MujocoSettings:
        """The :class:`MujocoSettings` of the same model (DIAGEXACT off, minimal scene)."""
        return MujocoSettings(timestep=self.timestep, integrator=self.integrator,
                              solref=self.solref, solimp=self.solimp,
                              iterations=self.iterations, tolerance=self.tolerance,
                              armature=self.armature, diagexact=False,
                              invweight_scale=self.invweight_scale, scene="minimal")

    def describe(self) -> str:
        return (f"MuJoCo Warp (float32, device {self.device}) {self.integrator} "
                f"dt<={self.timestep:g} s, steps/rev<={self.steps_per_rev}, {self.solver}, "
                f"solref={self.solref}, "
                f"solimp={self.solimp}, iterations={self.iterations}, "
                f"tolerance={self.tolerance:g}, armature={self.armature:g}, "
                f"invweight_scale={self.invweight_scale:g}")
