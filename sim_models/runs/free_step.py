"""The free-motion step chosen from the motion (issue 30, "engines on any description"):
as the prescribed runs cap the input's angle per step (``steps_per_rev``), a free run
caps the angle the fastest body turns in one step.

Each engine's recommended free step is a fixed time (MuJoCo 5e-4 s, PyBullet 1e-4 s,
Exudyn 5e-4 s, Pinocchio and MuJoCo Warp 1e-3 s).  A motion faster than the built-in
releases turns a body further per step than any of them was measured at; there the step
is shortened so that the exact trajectory's peak body angular rate times the step is
:data:`MAX_TURN_PER_STEP`.  A step the user sets (``--timestep``, ``--set timestep=``,
a ``timestep`` override) always wins: :func:`choose_step` is then not called.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..engines.ranges import MIN_TIMESTEP

#: The largest angle a body may turn in one free-motion step at the recommended step,
#: rad (0.15 rad = 8.6 deg).  Measured 2026-11-28 (peak body rate of the exact
#: trajectory x the engine's recommended step, at the report's 400 samples): the built-in
#: releases turn at most 0.141 rad a step (the offset slider-crank, 141 rad/s, in
#: Pinocchio and MuJoCo Warp at 1e-3 s; 0.070 rad in MuJoCo and Exudyn at 5e-4 s; A03's
#: 1140 rad/s at its 7.5e-5 s sample interval 0.085 rad; A01, the seed four-bar, the seed,
#: inverted and six-bar slider-cranks 0.004-0.04 rad), and those runs complete; so every
#: one of them keeps its recommended step exactly.  The released quick-return (a body at
#: 229 rad/s) turns 0.229 rad a step at 1e-3 s, and Pinocchio and MuJoCo Warp stop there
#: with loop gaps (0.6 and 1.7 % of the size); at 7e-4 s (0.16 rad) and 6.5e-4 s both
#: complete.  The cap is the measured envelope of the recommended steps, not an accuracy
#: target: where an engine's error needs a shorter step it is stated in the verdict
#: (``reports/comparison/free_limits.py``), as for the releases below the cap.
MAX_TURN_PER_STEP = 0.15


@dataclass(frozen=True)
class StepChoice:
    """A free run's step shortened from the motion: ``recommended`` (the engine's step
    as the run would take it, s), ``chosen`` (s), ``peak_rate`` (rad/s, of ``body``, at
    ``at`` s of the exact trajectory) and the ``cap`` (rad a step)."""

    recommended: float
    chosen: float
    peak_rate: float
    body: str
    at: float
    cap: float = MAX_TURN_PER_STEP

    @property
    def text(self) -> str:
        """The settings line's words: the step was chosen from the motion, and why."""
        return (f"step {self.chosen:.3g} s chosen from the motion (recommended "
                f"{self.recommended:.3g} s): body {self.body} turns at up to "
                f"{self.peak_rate:.4g} rad/s (t = {self.at:.4g} s), "
                f"{self.peak_rate * self.recommended:.3g} rad a step at the recommended "
                f"step, above the cap of {self.cap:g} rad a step "
                "(sim_models/runs/free_step.py MAX_TURN_PER_STEP)"
                + (f"; held at the smallest step an engine takes, {MIN_TIMESTEP:g} s, "
                   f"{self.peak_rate * self.chosen:.3g} rad a step"
                   if self.peak_rate * self.chosen > self.cap * (1 + 1e-9) else "")
                + "; --timestep sets it")

    def as_json(self) -> dict:
        return {"recommended_s": self.recommended, "chosen_s": self.chosen,
                "peak_body_rate_rad_s": self.peak_rate, "body": self.body,
                "at_s": self.at, "max_turn_per_step_rad": self.cap}


def peak_body_rate(reference, times) -> tuple[float, str, float]:
    """``(rate rad/s, body, t s)``: the largest absolute body angular rate of the exact
    trajectory (:class:`analytic.free_motion.FreeTrajectory`) over its integrator's
    accepted steps and ``times`` (the run's samples)."""
    ts = [np.asarray(times, float)] + [np.asarray(s.ts, float) for s in reference.segments]
    t = np.unique(np.clip(np.concatenate(ts), 0.0, reference.duration))
    om = np.abs(reference.at(t, forces=False).omega)
    om[~np.isfinite(om)] = 0.0
    if not om.size:
        return 0.0, "", 0.0
    k, b = np.unravel_index(int(np.argmax(om)), om.shape)
    return float(om[k, b]), reference.mech.bodies[b].name, float(t[k])


def choose_step(reference, times, step: float,
                cap: float = MAX_TURN_PER_STEP) -> StepChoice | None:
    """The step chosen from the motion: None when the peak body rate times the run's
    step (``step`` s, no longer than the shortest sample interval) is within ``cap``
    rad, else the :class:`StepChoice` whose step turns the fastest body by ``cap`` (not
    below :data:`sim_models.engines.ranges.MIN_TIMESTEP`, the settings' range)."""
    gaps = np.diff(np.asarray(times, float))
    h = min(float(step), float(gaps.min())) if gaps.size else float(step)
    rate, body, at = peak_body_rate(reference, times)
    if not (math.isfinite(rate) and rate * h > cap):
        return None
    return StepChoice(h, max(cap / rate, MIN_TIMESTEP), rate, body, at, cap)


__all__ = ["MAX_TURN_PER_STEP", "StepChoice", "choose_step", "peak_body_rate"]
