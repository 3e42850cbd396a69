"""The result of an engine's free-motion run (issue 21): what every engine returns, in
the analytic conventions, for the comparison against the exact trajectory
(:class:`analytic.free_motion.FreeTrajectory`).

An engine is released from the exact state at t = 0 (every body's pose and rate from
the reference, not from a drive spun up) and integrates on its own; the harness reads
it at the request's sample times.  After a divergence (non-finite state, exploding
energy, loop gap beyond ``max_gap`` of the size, wall-clock limit) the run ends with
``ok = False``, ``t_fail`` and ``reason``, and every later sample row is NaN ("not
measured from t on").  Nothing raises for a diverging simulation.

Conventions (as :class:`analytic.free_motion.FreeSamples` and :mod:`sim_models.engines.protocol`;
SI, world axes):

* ``x, xd`` (N, J): every joint's coordinate and rate, in the order of
  ``mechanism.joints`` (revolute: ``theta_b - theta_a`` in rad, continuous over turns;
  prismatic: the slider displacement in m); cut (loop-closing) joints are read from
  the bodies' poses as the analytic side defines them;
* ``theta, omega, alpha`` (N, B): absolute body angles (continuous), rates,
  accelerations, in the order of ``body_names``;
* ``joint_force`` (N, J, 2): the force by body_a on body_b of each joint, N;
* ``loop_gap`` (N,): the largest loop-closure gap over the cut joints, m;
* ``kinetic, potential`` (N,): J, computed by the harness from the engine's body
  states with the same masses, springs and gravity as the reference (one function
  for every engine), so energy drift is the engine's, not a convention's;
* ``motor_effort_engine`` (N,) or None: the engine's own effort on the motor joint
  (N m or N), unjudged where the engine applies the harness's value;
* ``extra`` (filled by :func:`sim_models.engines.free_protocol.drive_free`): ``native`` (which force
  elements are the engine's own, which the harness applies), ``energy_scale`` and
  ``E0`` (J: the reference's scale and initial energy, the drift's yardstick),
  ``motor_effort_source`` (``"engine"``: an actuator's own reading; ``"harness"``: the
  value applied), ``start_q``/``start_qd`` (the released state in tree coordinates).

Runs come from :func:`sim_models.runs.free.run_free`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from analytic import Mechanism

from ..engines.ranges import WALL_LIMIT, free_interval_problem
from ..engines.settings import EngineSettings, SettingsError
from .free_step import StepChoice


@dataclass(frozen=True)
class FreeRequest:
    """What a free run is asked: ``duration`` s from the released state, read at
    ``samples + 1`` evenly spaced times from 0 to ``duration`` inclusive; a run ends
    (``ok = False``) when the loop gap exceeds ``max_gap`` times the mechanism's size,
    when the total energy leaves ``[E0 - max_energy_growth * scale, E0 +
    max_energy_growth * scale]`` (scale: the reference's energy scale), or after
    ``wall_limit`` s of wall-clock time."""

    duration: float
    samples: int = 200
    max_gap: float = 1e-2
    max_energy_growth: float = 10.0
    wall_limit: float = 120.0

    def __post_init__(self):
        """``wall_limit`` within :data:`sim_models.engines.ranges.WALL_LIMIT` (the command
        line's ``--wall-limit`` range), and samples no closer than an engine's smallest
        step (:func:`sim_models.engines.ranges.free_interval_problem`): :class:`SettingsError`
        naming it otherwise."""
        problem = WALL_LIMIT.problem(self.wall_limit)
        if problem:
            raise SettingsError(f"free run request wall_limit={self.wall_limit!r}: {problem}",
                                "wall_limit", self.wall_limit, problem)
        # every door builds this request: the same floor on the sample interval for all
        problem = free_interval_problem(self.duration, self.samples)
        if problem:
            raise SettingsError(f"free run request: {problem}", "samples", self.samples,
                                problem)

    def times(self) -> np.ndarray:
        """The sample times, s: ``samples + 1`` points, 0 and ``duration`` included."""
        return np.linspace(0.0, self.duration, self.samples + 1)


@dataclass
class FreeEngineRun:
    """One engine's free-motion run, read at :meth:`FreeRequest.times` (see the module
    docstring for shapes, units and conventions)."""

    case: str
    engine: str
    mechanism: Mechanism
    settings: EngineSettings
    request: FreeRequest
    ok: bool
    reason: str | None
    t_fail: float | None
    times: np.ndarray
    joint_names: tuple[str, ...]
    body_names: tuple[str, ...]
    x: np.ndarray
    xd: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    joint_force: np.ndarray
    loop_gap: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    motor_effort_engine: np.ndarray | None
    #: seconds of wall-clock time in the stepping loop only (no readout, no build)
    wall: float
    steps: int
    timestep: float
    integrator: str
    precision: str = "float64"
    notes: tuple[str, ...] = ()
    extra: dict = field(default_factory=dict)
    #: the step chosen from the motion (:mod:`sim_models.runs.free_step`), or None: the
    #: engine's recommended or the user's step
    step_choice: StepChoice | None = None

    @property
    def cpu_per_simulated_second(self) -> float:
        """Wall-clock seconds of stepping per simulated second stepped (NaN if nothing
        ran): a run that stopped stepped to ``t_fail`` (the sample time the stop was
        seen at; an engine that gave up within the last interval stepped a little less),
        not to the requested duration."""
        reached = self.request.duration if self.t_fail is None else self.t_fail
        return self.wall / reached if reached > 0 else np.nan
