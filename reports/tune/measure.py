"""One measured candidate of the search: an engine run at one setting, judged as the
verdict judges it, with the process CPU time of the run.

The run and the judging are the verdicts' own: prescribed runs are
:func:`sim_models.engines.run` with :class:`~sim_models.runs.engine_run.RunRequest`'s
defaults (what ``xval compare`` runs) compared by
:func:`reports.comparison.compare.compare_run`; free runs are
:func:`sim_models.runs.free.run_free` over the case as ``xval simulate --engine``
releases and samples it, judged by :func:`reports.comparison.free_compare.compare_free`.
The CPU time is :func:`time.process_time` around the engine run alone (building the
engine model, stepping, reading out; not the comparison, not the exact reference).

:func:`measure_task` is a picklable top-level function of plain values, so the studies'
executor (local processes or a Dask cluster) runs it anywhere; it never raises (a
setting the engine refuses is a result with ``ok = False``).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from dataclasses import dataclass

from reports.comparison.quantities import judged
from reports.tune.measured import (
    FREE_FAMILIES,
    PRESCRIBED_FAMILIES,
    PRESCRIBED_FAMILY,
    Measured,
    free_errors,
    prescribed_errors,
)


@dataclass(frozen=True)
class TuneCase:
    """What is tuned: ``case`` (a built-in name or an absolute file path), ``free``
    (released under gravity for ``duration`` s, or its own ``[motion]``, judged at
    ``samples`` times) or prescribed."""

    case: str
    free: bool = False
    duration: float | None = None
    #: free runs: samples judged (None: the description's, as ``xval simulate``)
    samples: int | None = None
    #: a user's MJCF model (``case`` ends in .xml, :mod:`reports.tune.own`): its input
    #: joint and reference keyframe, as ``xval compare MODEL --driver --keyframe``
    driver: str | None = None
    keyframe: str | None = None

    @property
    def own(self) -> bool:
        """Whether the case is a user's own MJCF model."""
        from reports.tune.own import is_own
        return is_own(self.case)


# ============================================================================ cases
@functools.lru_cache(maxsize=8)
def prescribed_tree(case: str):
    """The compiled linkage of ``case`` (once per worker process)."""
    from analytic import load_case
    from sim_models import compile_linkage
    return compile_linkage(load_case(case))


@functools.lru_cache(maxsize=4)
def free_reference(case: str, duration: float | None, samples: int | None = None):
    """``(mech, traj, request, reference samples)`` of a free case as ``xval simulate
    --engine`` runs it (``samples``: judged times, None: the description's; once per
    worker process)."""
    from analytic.free_motion import simulate
    from reports.comparison.free_cases import command_case
    from reports.comparison.free_compare import reference_samples
    from sim_models.runs.free_run import FreeRequest
    mech, _release = command_case(case, duration)
    traj = simulate(mech, duration)
    n = samples or mech.motion.samples
    req = FreeRequest(duration=traj.duration, samples=max(1, n - 1))
    return mech, traj, req, reference_samples(traj, req.times())


def unit_time(tc: TuneCase) -> float:
    """One revolution's duration (prescribed) or 1 s (free): what ``unit_steps`` counts
    steps per."""
    if tc.own:
        from reports.tune.own import unit_time as own_unit_time
        return own_unit_time(tc)
    if tc.free:
        return 1.0
    from sim_models.engines.protocol import travel_time
    return float(travel_time(prescribed_tree(tc.case).mech.driver, 2 * math.pi))


def settings_of(tc: TuneCase, engine: str, overrides: dict):
    """The engine's settings for the case's mode with ``overrides`` (a user's model: its
    file's settings with ``overrides`` set over them)."""
    if tc.own:
        from reports.tune.own import settings_of as own_settings_of
        return own_settings_of(tc, overrides)
    from reports.comparison.settings_file import settings_class
    return settings_class(engine, "free" if tc.free else "run").from_overrides(overrides,
                                                                               engine)


# ============================================================================ the task
#: Steps of the bare-loop timing of a candidate (at most; the run's own count if fewer)
#: and its repeats (the best is kept: a shared machine's load only adds time).
TIMING_STEPS, TIMING_REPEATS = 2000, 3


def measure_task(tc: TuneCase, engine: str, overrides: dict, timed: bool = False) -> Measured:
    """Run ``engine`` on ``tc`` at ``overrides`` of its recommended settings and judge it
    (see the module docstring); ``timed``: also time the bare stepping loop at these
    settings (the studies' timing, :func:`sim_models.engines.time_engine`, free runs
    :func:`sim_models.runs.timing.time_free_steps`, on the process CPU clock) for the
    cost model.  Never raises."""
    t0 = time.process_time()
    try:
        s = settings_of(tc, engine, overrides)
        if tc.own:
            from reports.tune.own import measure
            m = measure(tc, s, overrides, timed, TIMING_STEPS, TIMING_REPEATS)
        else:
            m = _free(tc, engine, s, overrides, timed) if tc.free else \
                _prescribed(tc, engine, s, overrides, timed)
    except Exception as e:  # noqa: BLE001 - a refused setting is a measured result
        m = Measured(dict(overrides), False, f"{type(e).__name__}: {e}")
    return dataclasses.replace(m, task_cpu=time.process_time() - t0)


def _prescribed(tc: TuneCase, engine: str, s, overrides: dict, timed: bool) -> Measured:
    from reports.comparison.compare import compare_run
    from sim_models.runs.driven import run
    from sim_models.runs.engine_run import RunRequest
    tree = prescribed_tree(tc.case)
    req = RunRequest()
    t0 = time.process_time()
    r = run(tree, engine, s, revolutions=req.revolutions, samples=req.samples,
            max_violation=req.max_violation, max_speed_error=req.max_speed_error)
    cpu = time.process_time() - t0
    comps = judged(compare_run(r)) if r.ok else []
    errs = prescribed_errors(comps)
    cost = math.nan
    if timed and r.ok and r.steps > 0:
        from sim_models.runs.driven import time_engine
        sps = time_engine(tree, engine, s, r.timestep, TIMING_STEPS, TIMING_REPEATS,
                          time.process_time)
        cost = 1.0 / sps if sps > 0 else math.nan
    return Measured(dict(overrides), bool(r.ok), r.reason or "", errs,
                    float(r.steps_per_rev), int(r.steps), cpu, float(req.revolutions),
                    s.describe(), cost)


def _free(tc: TuneCase, engine: str, s, overrides: dict, timed: bool) -> Measured:
    from reports.comparison.free_compare import compare_free
    from sim_models.runs.free import run_free
    mech, traj, req, ref = free_reference(tc.case, tc.duration, tc.samples)
    t0 = time.process_time()
    r = run_free(mech, engine, s, req, traj)
    cpu = time.process_time() - t0
    v = compare_free(r, traj, ref)
    errs = free_errors(v)
    dur = float(req.duration)
    cost = math.nan
    if timed and r.ok and r.steps > 0:
        cost = _free_step_cost(mech, engine, r, traj)
    return Measured(dict(overrides), bool(r.ok), r.reason or "", errs,
                    float(r.steps) / dur, int(r.steps), cpu, dur, s.describe(), cost)


def _free_step_cost(mech, engine: str, r, traj) -> float:
    """s per step of the bare free stepping loop from the released state (the free
    grid's timing, :func:`sim_models.runs.timing.time_free_steps`, over TIMING_STEPS)."""
    import numpy as np

    from sim_models.engines.free_protocol import free_start
    from sim_models.runs.free import open_free_session
    from sim_models.runs.timing import time_free_steps
    session = open_free_session(mech, engine, r.settings)
    try:
        start = free_start(session.tree, traj.at(np.array([0.0]), forces=False))
        sps = time_free_steps(session, start, float(r.timestep), TIMING_STEPS,
                              TIMING_REPEATS, time.process_time)
    finally:
        session.close()
    return 1.0 / sps if sps > 0 else math.nan


__all__ = ["FREE_FAMILIES", "Measured", "PRESCRIBED_FAMILIES", "PRESCRIBED_FAMILY",
           "TuneCase", "free_reference", "measure_task", "prescribed_tree", "settings_of",
           "unit_time"]
