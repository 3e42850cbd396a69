"""Pinocchio's settings (:class:`PinocchioSettings`: the integrator, the Baumgarte
corrector, the proximal solver) and the library's import check (:func:`require_pinocchio`);
the model and the evidence are in :mod:`sim_models.engines.pinocchio.driven`."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

from ...builders.tree import SimModelError
from .. import ranges
from ..protocol import EngineSettings, Plan


def require_pinocchio():
    """The ``pinocchio`` module (PyPI ``pin``), or a :class:`SimModelError` saying how to
    install it."""
    try:
        import pinocchio
    except ImportError as e:
        raise SimModelError("the pinocchio engine needs the pin package (pip install "
                            f"'linkage-xval[pinocchio]'): {e}") from None
    return pinocchio


@dataclass(frozen=True)
class PinocchioSettings(EngineSettings):
    """Pinocchio settings (``constraintDynamics``, proximal solver, RK4 or semi-implicit
    Euler, Baumgarte stabilisation).

    Parameters
    ----------
    timestep
        Largest step, s.
    steps_per_rev
        Steps per revolution of the input (per run for a limited-range input); the step
        is the smaller of ``timestep`` and the one these give.
    integrator
        ``"rk4"`` (classical Runge-Kutta on q, v: four dynamics evaluations a step) or
        ``"euler"`` (semi-implicit Euler: one).
    baumgarte
        Baumgarte corrector of the loop constraints, ``omega h`` (dimensionless; ``Kp =
        omega^2``, ``Kd = 2 omega``: critical damping); 0 switches it off.
    prox_mu
        Proximal regularisation of ``constraintDynamics`` (the multiplier's step
        weight; it is what makes the z row of a planar loop's 3D constraint harmless).
    prox_accuracy
        Absolute and relative accuracy of the proximal iterations.
    prox_max_iter
        Most proximal iterations per dynamics evaluation.

    Evidence: speed-against-error grid over every built-in case, RK4, 2 revolutions, 36
    samples of the 2nd; worst error relative to peak over every judged quantity
    (accelerations, joint reactions, prismatic normal force and couple, drive effort),
    the worst case in parentheses (pin 4.1.0; grid script and CSV in the README
    "Pinocchio" section):

    ==============  =========  ======================  ======================
    timestep cap    steps/rev  baumgarte 0             baumgarte 0.05
    ==============  =========  ======================  ======================
    1e-2 s          90         1.5e-4 (quick-return)   4.0e-6 (quick-return)
    1e-2 s          180        1.9e-5 (quick-return)   3.7e-6 (two-inclines)
    1e-2 s          360        1.2e-6 (quick-return)   1.5e-6 (two-inclines)
    1e-3 s          90         1.1e-6 (slider-crank)   3.9e-7 (slider-crank)
    1e-3 s          180        1.5e-7 (inverted s-c)   3.9e-7 (hibbeler-16-30)
    1e-3 s          360        1.2e-7 (quick-return)   1.7e-7 (inverted s-c)
    ==============  =========  ======================  ======================

    * every run of the grid passes (1e-3 of peak) with 250x to spare or more;
    * cost is proportional to the steps a revolution (four constraint solves of two
      ``constraintDynamics`` calls each per RK4 step): the 1e-3 s cap makes the slow
      cases (quick-return, hibbeler-two-inclines: 1-2 s a revolution) take 1000-2000
      steps a revolution for 1e-7, where 180 a revolution give 4e-6;
    * Baumgarte 0.05 (omega h) pays where the steps are coarse (5x better at 1e-2 s
      and 180 steps) and costs little where they are fine (2e-7 to 4e-7 instead of
      1e-7..1e-10): the readout is the dynamics at the integrated state, without the
      corrector, so what it adds is the corrector's disturbance of the motion itself;
    * semi-implicit Euler (``integrator="euler"``, first order; measured with the
      corrector also in the readout) is 9e-5..8e-3 at 5760 steps a revolution and
      ends in a loop-gap divergence on 7 of 10 cases at 360;
    * the z multipliers of the loop constraints were 0.0 in every run.

    The defaults (1e-2 s, 180 steps, Baumgarte 0.05) are the cheapest row within
    4e-6 of peak on every case.
    """

    timestep: float = 1e-2
    steps_per_rev: int = 180
    integrator: str = "rk4"
    baumgarte: float = 0.05
    prox_mu: float = 1e-8
    prox_accuracy: float = 1e-12
    prox_max_iter: int = 20

    engine_name: ClassVar[str] = "pinocchio"
    RANGES: ClassVar[Mapping[str, object]] = {
        "timestep": ranges.TIMESTEP,
        "steps_per_rev": ranges.STEPS_PER_REV,
        "integrator": ranges.Choice(("rk4", "euler")),
        "baumgarte": ranges.BAUMGARTE_PER_STEP,
        "prox_mu": ranges.PROX_MU,
        "prox_accuracy": ranges.PROX_ACCURACY,
        "prox_max_iter": ranges.PROX_MAX_ITER,
    }

    def max_step(self, plan: Plan) -> float:
        return min(float(self.timestep), plan.rev_time / int(self.steps_per_rev))

    def describe(self) -> str:
        return (f"{self.integrator} steps/rev={self.steps_per_rev} dt<={self.timestep:g} "
                f"baumgarte={self.baumgarte:g} prox mu={self.prox_mu:g}")

