"""Exudyn's settings (:class:`ExudynSettings`: generalized-alpha, index 3, full Newton)
and the library's import check (:func:`require_exudyn`); the model and the evidence are in
:mod:`sim_models.engines.exudyn.driven`."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

from ...builders.tree import SimModelError
from .. import ranges
from ..protocol import (
    EngineSettings,
    Plan,
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

