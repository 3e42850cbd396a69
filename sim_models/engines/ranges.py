"""The accepted range of every engine setting and run-request value, defined once.

Every door checks these: the settings dataclasses (``__post_init__`` of
:class:`sim_models.engines.settings.EngineSettings`, so defaults, ``--set KEY=VALUE``,
option flags such as ``--timestep`` and a baseline file's ``settings.fields`` all pass
through it), :class:`sim_models.runs.engine_run.RunRequest` (``--revolutions``,
``--samples`` and a baseline file's ``request``) and the command line's option types
(:mod:`reports.cli.options`, which reads the bounds from here).  A value outside its
range is a setting the run cannot honour (an impossible physical value, or a run of
hours); it is refused before any engine runs.  A value inside the range may still give
a failed verdict: that is a measurement, not a user error.

This module imports nothing but the standard library.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

from analytic.motion_spec import MAX_WALL_LIMIT  # one bound for the exact side too


@dataclass(frozen=True)
class Range:
    """A closed or open interval of accepted numbers (``None``: unbounded side).

    ``unit`` is SI (printed after the bounds), ``why`` one short reason (printed in
    parentheses), ``whole`` asks for an integer (``True``/``False`` are not numbers),
    ``name`` names a component of a setting of several numbers (solimp's ``width``)."""

    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    unit: str = ""
    why: str = ""
    whole: bool = False
    name: str = ""                  # the component's name, in a setting of several numbers

    def text(self) -> str:
        """The accepted range in words, e.g. ``1e-06 to 0.1 s`` or ``above 0 and at most 1``."""
        lo, hi = self.lo, self.hi
        low = None if lo is None else (f"above {lo:g}" if self.lo_open else f"at least {lo:g}")
        high = None if hi is None else (f"below {hi:g}" if self.hi_open else f"at most {hi:g}")
        if low and high:
            core = f"{lo:g} to {hi:g}" if not (self.lo_open or self.hi_open) \
                else f"{low} and {high}"
        else:
            core = low or high or "any finite number"
        return core + (f" {self.unit}" if self.unit else "")

    def problem(self, value) -> str | None:
        """``None`` when ``value`` is accepted, else why not (one phrase, with the range)."""
        if isinstance(value, bool):
            return f"a true/false value is not a number: the accepted range is {self.text()}" \
                + self._why()
        if not isinstance(value, (int, float)):
            return f"{value!r} is not a number: the accepted range is {self.text()}" + \
                self._why()
        v = float(value)
        if not math.isfinite(v):
            return f"{value!r} is not a finite number: the accepted range is " \
                   f"{self.text()}{self._why()}"
        if self.whole and v != int(v):
            return f"{value!r} is not a whole number: the accepted range is " \
                   f"{self.text()}{self._why()}"
        lo_ok = self.lo is None or (v > self.lo if self.lo_open else v >= self.lo)
        hi_ok = self.hi is None or (v < self.hi if self.hi_open else v <= self.hi)
        if lo_ok and hi_ok:
            return None
        shown = f"{int(v)}" if self.whole else \
            (f"{v:g}" if float(f"{v:g}") == v else f"{v:.12g}")  # no typed digit hidden
        return f"{shown} is out of range: the accepted range is {self.text()}{self._why()}"

    def _why(self) -> str:
        return f" ({self.why})" if self.why else ""


@dataclass(frozen=True)
class Choice:
    """One of a few words, in any letter case (``RK4``, ``rk4`` and ``Rk4`` are one
    integrator for every engine); :meth:`canonical` gives the listed spelling, which the
    settings keep.  ``fold`` is kept for the callers that name it: every choice folds."""

    values: tuple[str, ...]
    fold: bool = True

    def text(self) -> str:
        return "one of " + ", ".join(self.values) + " (any letter case)"

    def canonical(self, value):
        """``value``'s listed spelling when it is one of :attr:`values` in another letter
        case; anything else unchanged (for :meth:`problem` to refuse)."""
        if isinstance(value, str):
            for v in self.values:
                if v.lower() == value.lower():
                    return v
        return value

    def problem(self, value) -> str | None:
        if isinstance(value, str) and self.canonical(value) in self.values:
            return None
        return f"{value!r} is not accepted: use {self.text()}"


@dataclass(frozen=True)
class Flag:
    """``true`` or ``false`` (a bool; numbers and words are converted before, where a
    door accepts them)."""

    def text(self) -> str:
        return "true or false"

    def problem(self, value) -> str | None:
        return None if isinstance(value, bool) else f"{value!r} is not true or false"


FLAG = Flag()


def first_problem(rng, value) -> str | None:
    """``rng.problem(value)`` for a scalar range; for a tuple of ranges (a setting of
    several numbers) the first component's problem, naming the component."""
    if not isinstance(rng, tuple):
        return rng.problem(value)
    vals = tuple(value) if isinstance(value, (tuple, list)) else (value,)
    if len(vals) != len(rng):
        return f"{len(vals)} numbers given: it needs {len(rng)}"
    for i, (part, v) in enumerate(zip(rng, vals, strict=True)):
        p = part.problem(v)
        if p:
            return f"{part.name or f'number {i + 1}'} ({i + 1} of {len(rng)}): {p}"
    return None


# ============================================================================ run request
#: Engine time step, s: below 1e-6 s a revolution at the built-in cases' speeds takes
#: 1e5-1e6 steps per engine (minutes); above 0.1 s a crank at 15 rad/s turns 86 deg a
#: step.  Every engine's ``timestep`` and the ``--timestep`` option.
MIN_TIMESTEP, MAX_TIMESTEP = 1e-6, 0.1
TIMESTEP = Range(MIN_TIMESTEP, MAX_TIMESTEP, unit="s",
                 why="the step must be positive; the bounds keep a run between minutes "
                     "and a few steps per revolution")

#: Engine samples per revolution: 0.1 deg apart at the ceiling.  The engine's step is
#: shortened so that every sample falls on a step, so more samples make a run longer
#: without showing anything between them that 3600 do not.
MAX_SAMPLES = 3600
SAMPLES = Range(2, MAX_SAMPLES, whole=True,
                why="0.1 deg apart at most; every sample falls on an engine step")
#: Samples of the instantaneous mode: states, not a cycle; one is enough.
STATES = Range(1, 100 * MAX_SAMPLES, whole=True, why="states evaluated one by one")

#: Engine revolutions: the last one is compared; beyond 1000 a run measures only drift,
#: which the report's long-run study covers.
#: Wall-clock limit of one engine's free run (s): a run past it ends as a result ("wall-clock
#: limit reached"), not an error.  The default 120 s suits the report's short runs; A02's
#: 20 s takes PyBullet about 30 min on a shared 2-core machine.
WALL_LIMIT = Range(0, MAX_WALL_LIMIT, lo_open=True, unit="s",
                   why="at most one day of stepping per engine run")


def free_interval_problem(duration: float, intervals: int) -> str | None:
    """Why a free run of ``duration`` s read at ``intervals + 1`` evenly spaced times
    cannot be asked of an engine, or None.  An engine steps at most one sample interval
    (the step is shortened so that every sample falls on one), so samples closer than
    :data:`MIN_TIMESTEP` would run every engine below the smallest step it accepts,
    where its readings are not what it was measured at (51 samples over 1e-6 s step
    Exudyn at 2e-8 s: its accelerations 255 of their scale off; MuJoCo, Pinocchio and
    MuJoCo Warp pass there); the exact trajectory alone (no engine) has no such floor."""
    if isinstance(intervals, bool) or not isinstance(intervals, numbers.Integral) or \
            intervals < 1:
        return None  # not a count of intervals: for the request's own checks to name
    try:
        dt = float(duration) / int(intervals)
    except (TypeError, ValueError):
        return None
    if not (math.isfinite(dt) and dt > 0):
        return None  # a duration that is not a positive number: named where it is read
    if not dt >= MIN_TIMESTEP * (1 - 1e-9):
        most = max(1, int(float(duration) / MIN_TIMESTEP * (1 + 1e-9))) + 1
        return (f"{int(intervals) + 1} sample times over {float(duration):g} s are "
                f"{dt:.3g} s apart, below the engines' smallest step {MIN_TIMESTEP:g} s: "
                f"ask for at most {most} samples over {float(duration):g} s, or a duration "
                f"of at least {MIN_TIMESTEP * int(intervals):.3g} s")
    return None


MAX_REVOLUTIONS = 1000
REVOLUTIONS = Range(1, MAX_REVOLUTIONS, whole=True, why="the last revolution is compared")

#: Divergence thresholds of a run: relative to the mechanism's size (loop gap) and to
#: the input's speed (driver rate).  A threshold of 0 ends every run at its first step;
#: above 1 (a gap as large as the mechanism, a rate 100% off) the check is off.
MAX_VIOLATION = Range(0, 1, lo_open=True, why="a loop gap relative to the mechanism's "
                      "size; above 1 the check is off")
MAX_SPEED_ERROR = Range(0, 1, lo_open=True, why="the driver rate's error relative to "
                        "its speed; above 1 the check is off")
CHORDS = Choice(("moving", "analytic"))
MODES = Choice(("run", "instantaneous"))

#: Steps per revolution (Exudyn): the step is the smaller of ``timestep`` and one
#: revolution / steps_per_rev.  1e6 steps a revolution at Exudyn's 25-55 us a step is
#: about a minute per revolution, the run time the 1e-6 s floor of ``timestep`` allows.
STEPS_PER_REV = Range(1, 1_000_000, whole=True,
                      why="1e6 steps a revolution run about a minute per revolution")

#: Pinocchio's Baumgarte corrector per step, ``omega h`` (``Kp = omega^2``, ``Kd = 2 omega``):
#: 0 switches it off; above 1 the correction acts faster than one step, which an
#: explicit step cannot follow (it overshoots).
BAUMGARTE_PER_STEP = Range(0, 1, why="omega h of a critically damped correction; above 1 "
                           "it is faster than a step")
#: Pinocchio's proximal regularisation: 0 leaves the planar loop's zero z row of its 3D
#: point constraints unregularised; above 1 the multipliers move by less than the
#: residual each iteration (it stalls).
PROX_MU = Range(0, 1, lo_open=True, why="the proximal weight; 0 leaves the redundant z "
                "row singular")
#: Accuracy of Pinocchio's proximal iterations: below 1e-15 no double-precision solve
#: can meet it, above 1e-3 the multipliers are off by more than the verdict tolerance.
PROX_ACCURACY = Range(1e-15, 1e-3, why="double round-off below, the verdict tolerance "
                      "above")
#: Proximal iterations per dynamics evaluation (each one a back substitution).
PROX_MAX_ITER = Range(1, 1000, whole=True, why="each iteration is a back substitution "
                      "per dynamics evaluation")

__all__ = ["CHORDS", "MAX_REVOLUTIONS", "MAX_SAMPLES", "MAX_SPEED_ERROR", "MAX_TIMESTEP",
           "MAX_VIOLATION", "MIN_TIMESTEP", "MODES", "REVOLUTIONS", "SAMPLES", "STATES",
           "FLAG", "STEPS_PER_REV", "BAUMGARTE_PER_STEP", "PROX_MU", "PROX_ACCURACY",
           "PROX_MAX_ITER", "TIMESTEP", "Choice", "Flag", "Range", "first_problem"]
