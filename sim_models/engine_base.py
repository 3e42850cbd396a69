"""The engine protocol: settings, session, sampling plan, step schedule, recorder, run loop.

Everything an engine author needs is importable from this module (the settings base and
errors live in :mod:`sim_models.engine_settings`, the sampling plan and step schedule in
:mod:`sim_models.sampling`, the recorder and :class:`EngineRun` in
:mod:`sim_models.engine_run`; all re-exported here); an engine is one module
(``sim_models/<name>_engine.py``) with a settings class and a session class, plus one
line in :mod:`sim_models.registry`.  Nothing here imports an engine library.

Data flow (one compiled object passed down)::

    mech = load_case(...)                    # description (analytic.Mechanism)
    tree = compile_linkage(mech)             # SimTree: Linkage + reference solution + tree
    run_ = run(tree, "mujoco", settings)     # EngineRun (carries tree.linkage and settings)
    comps = compare_run(run_)                # reports.comparison.compare: run_.linkage

Writing an engine
-----------------
1. **Settings**: subclass :class:`EngineSettings` (a frozen dataclass).  Every field has
   the recommended default, and the class docstring gives the evidence for it (the
   speed-against-error grid, the worst error).  Field types are ``float``, ``int``,
   ``bool``, ``str`` or ``tuple[float, ...]`` so :meth:`EngineSettings.from_overrides`
   can build it from ``key=value`` strings (``xval compare --set steps_per_rev=1008``).
   Give every field its accepted range in ``RANGES`` (:mod:`sim_models.ranges`): the
   dataclass checks it on construction, for every door (``--set``, flags, baselines).
   Override :meth:`EngineSettings.max_step` when the step is not given as ``timestep``
   (e.g. by steps per revolution).
2. **Session**: subclass :class:`Session` and implement

   * ``__init__(self, tree: SimTree, settings)``: build and load the model (call
     ``super().__init__(tree, settings)`` first);
   * ``reset(self, t: float, h: float) -> None``: put the model in the analytic
     assembled state at time ``t`` (s) of the prescribed motion
     (:meth:`Session.analytic_state` gives the tree coordinates ``q, qd`` and the
     drive's value/rate/acceleration) and set the drive; ``h`` is the step the run
     will take first (s; an engine that must pre-roll uses it);
   * ``advance(self, t: float, h: float, n: int) -> str | None``: ``n`` steps of ``h``
     seconds from time ``t``, the drive following the prescribed motion
     (:meth:`SimTree.driver_path`); return a reason string when the state diverged
     (non-finite, huge), else ``None``.  Do no readout here: this loop is what the
     speed studies time (:func:`time_steps`);
   * the readout, preferably **deferred** (what the MuJoCo and PyBullet sessions do):
     ``record(self, t: float) -> (raw, ahead, reason)`` copies the engine's own state
     at time ``t`` (no conversion; ``ahead`` = time stepped past ``t`` while reading,
     0.0 or one step when accelerations are finite differences over the next step;
     ``reason`` = a divergence the raw state already shows: non-finite, huge, an
     engine warning), and ``convert(self, times, raws, rows, rec) -> (gap, rate)``
     turns all records at once, vectorised, into ``rec``'s sample rows
     (:meth:`Recorder.put_motions` for tree coordinates, :meth:`Recorder.put_forces_many`)
     and returns each record's loop gap (m) and driver rate, which :func:`drive`
     checks after the run (:func:`first_divergence`: the same tests and messages as
     :func:`check_motion`, at the same stops).  **Or** the per-sample readout:
     ``sample(self, t: float, rows, rec: Recorder) -> float`` reads the state at time
     ``t`` into rows ``rows`` of ``rec`` in the analytic conventions (below), with
     :meth:`Recorder.put_motion` (tree coordinates) or :meth:`Recorder.put_absolute`
     (absolute body angles/rates) and :meth:`Recorder.put_forces`, returning the time
     the session advanced past ``t``; with it ``state(self) -> tuple[np.ndarray,
     np.ndarray]`` (the raw tree coordinates ``q, qd`` for the default divergence
     check) **or** ``divergence(self, t) -> str | None`` (an engine in absolute
     coordinates: use :func:`check_motion` with the loop gap and the driver rate);
   * optionally ``divergence(self, t)`` (engine-specific checks, call ``super()``),
     ``forward_at(self, q, qd, acc, rows, rec)`` (accelerations and forces at a given
     state without stepping: the instantaneous mode), ``close(self)``.
   * class attributes ``name`` (registry name), ``settings_class`` and
     ``engine_readings`` (True when ``sample`` also fills the engine's own, unjudged
     readings ``rec.force_engine`` / ``rec.effort_engine``).
3. **Registry**: one ``EngineEntry`` line in :data:`sim_models.registry.BUILTIN`.
4. **Refusals**: raise :class:`EngineRefusal` (from ``__init__`` or ``reset``) when the
   engine cannot run this mechanism or motion, with one line saying why; never let an
   engine exception escape for a diverging simulation (return a reason instead).

Conventions of a sample (as :mod:`analytic.kinetostatics`; SI, world axes)
------------------------------------------------------------------------
* ``theta, omega, alpha`` (N, B): **absolute** body angles and rates (rad, rad/s,
  rad/s^2), never relative joint coordinates (:meth:`Recorder.put_motion` converts tree
  coordinates);
* ``slider_acc`` (N, P): ``s''`` of each prismatic joint (m/s^2) along its line;
* ``joint_force`` (N, J, 2): the force **by body_a on body_b** of each joint (for a
  prismatic joint the guide on the slider), N;
* ``normal, moment`` (N, P): the prismatic joint's force along the line normal (the line
  direction turned +90 deg) and the couple on the slider about the slider point;
* ``drive_effort`` (N,): the torque (N m) the driver applies to body_b, or the force
  (N) on the slider along its line.

Sampling (:func:`plan_samples`)
-------------------------------
A constant-speed (or monotonic) full-turn driver is sampled at the analytic sweep's
inputs (:func:`analytic.sweep.input_values`) during the last of ``revolutions`` turns;
a limited-range driver once from its reference value in the direction of motion.  Any
other motion (an input that reverses, or is not reached monotonically) is sampled **by
time**: ``samples`` equal intervals of the run, which lasts until the input has
travelled ``revolutions`` turns (or its feasible range) or is about to leave the
feasible range.  The step is shortened so every sample time is a step boundary
(:func:`step_schedule`).

Divergence (non-finite state, loop gap above ``max_violation`` of the mechanism's size,
driver rate off by ``max_speed_error``) ends a run: ``ok = False``, ``reason``, NaN
samples from there on.  Nothing raises for a diverging simulation.  It is checked at
every stop of the step schedule (once per sample interval, never per step); for a
deferred session the loop gap and driver rate of every stop are checked when its block
of :data:`RAW_BLOCK` records is converted (vectorised), and the run ends at the first
stop that fails either check, exactly as a per-stop check would have ended it (the
same reason, ``steps`` counted to there, later samples NaN).
"""

from __future__ import annotations

import math
import time
from abc import ABC, abstractmethod
from typing import ClassVar

import numpy as np

from analytic import Linkage, Mechanism, Prismatic

from .engine_run import EngineRun, Recorder, RunRequest, fmt_value, loop_gap, loop_gaps
from .engine_settings import EngineRefusal, EngineSettings, SettingsError
from .sampling import (
    LIMITED_RANGE_CONDITION,
    Plan,
    periodic_plan,
    plan_samples,
    reversal_time,
    step_schedule,
    steps_to,
    time_of,
    times_plan,
    travel_time,
)
from .tree import SimTree


# ============================================================================ compile
def compile_linkage(mech: Mechanism | SimTree, linkage: Linkage | None = None,
                    chords: str = "moving") -> SimTree:
    """The compiled linkage every engine builds from: the spanning tree, the analytic
    :class:`Linkage` and its reference solution (:class:`SimTree`).  A ``SimTree`` is
    returned as is; pass ``linkage`` to reuse an already built one."""
    if isinstance(mech, SimTree):
        return mech
    return SimTree(mech, linkage, chords=chords)


def finish(session: Session, plan: Plan, rec: Recorder, request: RunRequest,
           reason: str | None, fail_value: float | None, wall: float, dt: float,
           steps: int, engine: str | None = None) -> EngineRun:
    """The :class:`EngineRun` of a session's recorder."""
    st, mech = session.tree, session.tree.mech
    steps_per_rev = plan.rev_time / dt if dt > 0 else math.nan
    ex = {"prismatic_driver": isinstance(mech.driver_joint, Prismatic),
          "tree": st.tree_names, "chords": [c.name for c in st.chords],
          "analytic_chords": st.analytic_chords(), "t_end": plan.t_end}
    ex.update(session.extra())
    readings = session.engine_readings
    return EngineRun(
        case=mech.name, engine=engine or session.name, mechanism=mech, linkage=st.linkage,
        settings=session.settings, request=request, ok=reason is None, reason=reason,
        fail_value=fail_value, values=plan.values, times=plan.times,
        driver_velocity=plan.velocity, driver_acceleration=plan.acceleration,
        measured_values=rec.measured,
        body_names=tuple(st.body_names), joint_names=tuple(j.name for j in mech.joints),
        prismatic_names=tuple(mech.joints[k].name for k in st.prismatic),
        theta=rec.theta, omega=rec.omega, alpha=rec.alpha, slider_acc=rec.slider_acc,
        drive_effort=rec.effort, joint_force=rec.force, normal=rec.normal, moment=rec.moment,
        loop_violation=rec.viol, speed_deviation=rec.speed,
        wall_per_rev=wall / plan.revolutions if plan.full else wall, timestep=dt,
        steps_per_rev=steps_per_rev, steps=steps, wall=wall, has_forces=st.has_mass,
        by_time=plan.by_time, notes=tuple(session.notes),
        drive_effort_engine=rec.effort_engine if readings else None,
        joint_force_engine=rec.force_engine if readings else None,
        q=rec.q, qd=rec.qd, qdd=rec.qdd, extra=ex, origin=rec.origin)


# ============================================================================ session
class Session(ABC):
    """One engine model of one compiled linkage, stepped through a prescribed motion.

    Subclass per engine (see the module docstring for the contract).  Attributes set by
    :meth:`__init__`: ``tree`` (:class:`SimTree`), ``settings``, ``notes`` (list of
    str: warnings and remarks that end up in :attr:`EngineRun.notes`)."""

    #: registry name ("mujoco", "pybullet", ...)
    name: ClassVar[str] = ""
    #: the engine's :class:`EngineSettings` subclass
    settings_class: ClassVar[type[EngineSettings]] = EngineSettings
    #: whether :meth:`sample` fills the engine's own (unjudged) force readings
    engine_readings: ClassVar[bool] = False

    def __init__(self, tree: SimTree, settings: EngineSettings | None = None):
        self.tree = tree
        self.settings = settings if settings is not None else self.settings_class()
        self.notes: list[str] = []
        self.max_violation = RunRequest.max_violation
        self.max_speed_error = RunRequest.max_speed_error

    # -- the contract -------------------------------------------------------------
    @abstractmethod
    def reset(self, t: float, h: float) -> None:
        """Analytic assembled state at time ``t`` (s) of the prescribed motion, drive
        set; ``h`` is the first step the run will take (s)."""

    @abstractmethod
    def advance(self, t: float, h: float, n: int) -> str | None:
        """``n`` steps of ``h`` s from time ``t``; a divergence reason or None."""

    def sample(self, t: float, rows, rec: Recorder) -> float:
        """Fill ``rows`` of ``rec`` at time ``t``; return the time stepped past ``t``
        (a session that implements :meth:`record` and :meth:`convert` instead needs
        none: :func:`drive` reads it raw and converts once)."""
        raise NotImplementedError(f"engine {self.name!r} implements neither sample() nor "
                                  "record()/convert()")

    # -- deferred readout (optional, preferred): raw state now, conversion after the run
    def record(self, t: float) -> tuple[object, float, str | None]:
        """The raw engine state at time ``t`` (a step boundary): ``(raw, ahead,
        reason)``.  ``raw`` is whatever :meth:`convert` needs (copies of the engine's
        own arrays, no conversion); ``ahead`` the time stepped past ``t`` while reading
        (0.0, or one step for finite differences); ``reason`` a divergence the raw
        state already shows (non-finite, huge, an engine's own warning; ``raw`` is then
        not used), else None.  The loop gap and the driver rate are checked after the
        run, from :meth:`convert`'s values at each record (same tests, same order as
        :func:`check_motion`)."""
        raise NotImplementedError

    def convert(self, times: np.ndarray, raws: list, rows: list, rec: Recorder):
        """Convert K raw records (:meth:`record` at ``times`` (K,), s) at once,
        vectorised, into ``rec``'s sample rows (``rows[k]``: the sample indices of
        record ``k``, possibly empty), in the conventions of the module docstring.
        Returns ``(gap, rate)`` (K,): the loop gap (m) and the driver's rate in the
        engine at each record, for the divergence check."""
        raise NotImplementedError

    @property
    def deferred(self) -> bool:
        """Whether this session reads raw state (:meth:`record`) and converts once."""
        return type(self).record is not Session.record

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """Raw tree coordinates ``q, qd`` (SimTree conventions), used by the default
        :meth:`divergence`.  An engine in absolute coordinates overrides
        :meth:`divergence` instead (with :func:`check_motion`)."""
        raise NotImplementedError

    # -- optional -----------------------------------------------------------------
    def forward_at(self, q, qd, acceleration: float, rows, rec: Recorder) -> None:
        """Accelerations and forces at a given state without stepping (instantaneous
        mode); engines without a forward-dynamics call refuse."""
        raise EngineRefusal(f"engine {self.name!r} has no instantaneous mode (no "
                            "forward-dynamics call at a given state)")

    def divergence(self, t: float) -> str | None:
        """Why the state at time ``t`` is diverged (None when it is not): non-finite
        state, loop gap above ``max_violation`` of the mechanism's size, driver rate off
        by more than ``max_speed_error`` of the prescribed speed."""
        return check_state(self.tree, *self.state(), t, self.max_violation,
                           self.max_speed_error)

    def close(self) -> None:  # noqa: B027 - optional hook, nothing to release by default
        """Release the engine's resources (idempotent)."""

    def extra(self) -> dict:
        """Engine-specific entries for :attr:`EngineRun.extra`."""
        return {}

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -- helpers for implementations ------------------------------------------------
    def analytic_state(self, t: float):
        """``q, qd`` (nt,) tree coordinates of the analytic solution at time ``t`` of the
        prescribed motion, and the driver's ``(value, rate, acceleration)`` there.  At
        ``t = 0`` it is the reference assembly; elsewhere the branch the analytic solver
        holds (raises :class:`analytic.LinkageError` where the loops cannot close)."""
        st = self.tree
        val, vel, acc = (float(x) for x in st.driver_path(t))
        if t == 0.0:
            q, qd, _ = st.coords(st.kin_ref)
            q = np.zeros_like(q)
        else:
            kin = st.linkage.kinematics(val, vel, acc)
            q, qd, _ = st.coords(kin)
        return q[0], qd[0], (val, vel, acc)


def check_state(tree: SimTree, q, qd, t: float, max_violation: float,
                max_speed_error: float) -> str | None:
    """The shared divergence check of raw tree coordinates at time ``t``."""
    q, qd = np.asarray(q, float), np.asarray(qd, float)
    why = check_raw_state(q, qd)
    if why is not None:
        return why
    th, _, _, org, _, _ = tree.propagate(q[None], qd[None], np.zeros_like(q)[None])
    return check_motion(tree, loop_gap(tree, th, org),
                        tree.driver_sigma * qd[tree.driver_tree], t, max_violation,
                        max_speed_error)


def check_motion(tree: SimTree, gap: float, rate: float, t: float, max_violation: float,
                 max_speed_error: float) -> str | None:
    """The divergence check from a loop gap (m) and the driver's rate at time ``t``
    (for engines in absolute coordinates; NaN counts as diverged)."""
    if not (math.isfinite(gap) and math.isfinite(rate)) or abs(rate) > HUGE:
        return "non-finite or huge state (simulation diverged)"
    vmax = max_violation * tree.size
    if gap > vmax:
        return f"loop violation {gap:.3g} m > {vmax:.3g} m"
    _, vel, _ = tree.driver_path(t)
    vel = float(vel)
    ref = max(abs(vel), abs(tree.mech.driver.velocity), 1e-12)
    if abs(rate - vel) > max_speed_error * ref:
        return f"driver rate off by {abs(rate - vel):.3g} (> {max_speed_error:g} relative)"
    return None


def check_raw_state(q, qd) -> str | None:
    """The part of :func:`check_state` a raw record needs no conversion for: non-finite
    or huge tree coordinates ``q, qd`` (same messages)."""
    if not (np.isfinite(q).all() and np.isfinite(qd).all()):
        return "non-finite state (simulation diverged)"
    if np.abs(qd).max(initial=0.0) > HUGE:
        return "huge velocities (simulation diverged)"
    return None


def first_divergence(tree: SimTree, gap, rate, times, max_violation: float,
                     max_speed_error: float) -> tuple[int | None, str | None]:
    """The first record (index into ``times``) whose loop gap or driver rate fails
    :func:`check_motion`, and its reason; ``(None, None)`` when none does.  Vectorised
    screen (a slightly wider net), then :func:`check_motion` itself on the candidates,
    so the verdict and the message are exactly the per-sample check's."""
    gap, rate, times = (np.asarray(x, float) for x in (gap, rate, times))
    if not len(times):
        return None, None
    _, vel, _ = tree.driver_path(times)
    ref = np.maximum(np.maximum(np.abs(vel), abs(tree.mech.driver.velocity)), 1e-12)
    with np.errstate(invalid="ignore", over="ignore"):
        net = 1.0 - 1e-9
        bad = ~(np.isfinite(gap) & np.isfinite(rate)) | (np.abs(rate) > net * HUGE) \
            | (gap > net * max_violation * tree.size) \
            | (np.abs(rate - vel) > net * max_speed_error * ref)
    for k in np.flatnonzero(bad):
        why = check_motion(tree, float(gap[k]), float(rate[k]), float(times[k]),
                           max_violation, max_speed_error)
        if why is not None:
            return int(k), why
    return None, None


#: Velocities above this (MuJoCo's own "huge value" threshold) count as divergence.
HUGE = 1e10


# ============================================================================ run loop
def drive(session: Session, plan: Plan, request: RunRequest | None = None) -> EngineRun:
    """Step ``session`` through ``plan`` and sample it: **the one run loop** of the
    verdict runs, the speed grids, the hard cases, the long runs and the scene study.

    Resets to the analytic state at t = 0, then for each stop of
    :func:`step_schedule`: :meth:`Session.advance` to it, then read the samples there.
    A session with :meth:`Session.record` is read raw at every stop (with the checks
    the raw state allows) and converted :data:`RAW_BLOCK` stops at a time (a verdict
    run's 36 samples: once, after the loop), vectorised (:meth:`Session.convert`),
    where the loop gap and driver rate of every stop are checked; otherwise
    :meth:`Session.sample` and :meth:`Session.divergence` at each stop.  A divergence
    ends the run at the first stop that shows it (``ok = False``, NaN samples from
    there on, ``steps`` counted to there).  ``wall`` times the whole loop and the
    conversion."""
    request = request or RunRequest()
    session.max_violation = request.max_violation
    session.max_speed_error = request.max_speed_error
    rec = Recorder(session.tree, plan)
    dt_max = session.settings.max_step(plan)
    order, stops, steps = step_schedule(plan.times, dt_max)
    sample_at: dict[float, list[int]] = {}
    times = np.asarray(plan.times, float).tolist()
    for i in order.tolist():
        if math.isfinite(times[i]):
            key = times[i] if times[i] > 1e-15 else 0.0
            sample_at.setdefault(key, []).append(i)
    dt_used = max((h for h, n in steps if n > 0), default=dt_max)
    t0 = time.perf_counter()
    log = _RawLog(session, rec, request) if session.deferred else None
    reason, t_fail, nsteps = _step_through(session, steps, stops, dt_used, dt_max,
                                           sample_at, rec, log)
    if log is not None:
        earlier = log.flush()  # the records left all precede a failure seen while stepping
        if earlier is not None:
            reason, t_fail, nsteps = earlier
    fail = None
    if reason is not None:
        reason, fail = rec.fail(t_fail, reason)
    wall = time.perf_counter() - t0
    return finish(session, plan, rec, request, reason, fail, wall, dt_used, nsteps)


#: Raw records converted at a time (bounds a long run's memory, and the stepping a run
#: does past a divergence that only the conversion shows, to one block).
RAW_BLOCK = 1024


class _RawLog:
    """Raw records of a run (:meth:`Session.record`): time (s), sample rows, raw state,
    steps taken up to and including the record; converted (:meth:`Session.convert`) and
    checked (:func:`first_divergence`) a block at a time, in time order."""

    def __init__(self, session: Session, rec: Recorder, request: RunRequest):
        self.session, self.rec, self.request = session, rec, request
        self.times: list[float] = []
        self.rows: list[list[int]] = []
        self.raws: list = []
        self.steps: list[int] = []

    def add(self, t: float, rows: list[int], raw, steps: int):
        """Log one record; at a full block, :meth:`flush` (its failure, or None)."""
        self.times.append(t)
        self.rows.append(rows)
        self.raws.append(raw)
        self.steps.append(steps)
        return self.flush() if len(self.times) >= RAW_BLOCK else None

    def flush(self) -> tuple[str, float, int] | None:
        """Convert the logged records into the recorder and check them: ``(reason,
        t_stop, steps)`` of the first that fails (later rows of the block are dropped:
        never reached), else None."""
        if not self.times:
            return None
        req = self.request
        gap, rate = self.session.convert(np.asarray(self.times), self.raws, self.rows,
                                         self.rec)
        k, why = first_divergence(self.session.tree, gap, rate, self.times,
                                  req.max_violation, req.max_speed_error)
        out = None
        if why is not None:
            out = (why, self.times[k], self.steps[k])
            self.rec.drop([i for rows in self.rows[k + 1:] for i in rows])
        self.times, self.rows, self.raws, self.steps = [], [], [], []
        return out


def _step_through(session: Session, steps, stops, dt_used: float, dt_max: float,
                  sample_at: dict, rec: Recorder, log: _RawLog | None):
    """The stepping phase of :func:`drive`: ``(reason, t_stop, steps)`` of the first
    failure seen while stepping (None, None, all steps when none)."""
    reason = None
    nsteps = 0
    session.reset(0.0, dt_used)
    t, h_prev = 0.0, dt_used
    for (h, n), t_stop in zip(steps, stops[1:], strict=True):
        if t > t_stop - 1e-15 and n == 0:
            h, n = h_prev, 0
        elif abs(t - (t_stop - h * n)) > 1e-12 * max(1.0, t_stop):
            h, n = steps_to(t, t_stop, h_prev, dt_max)
        if n:
            reason = session.advance(t, h, n)
            nsteps += n
            h_prev = h
        t = t_stop
        if reason is None:
            rows = sample_at.get(t_stop, [])
            if log is not None:
                raw, ahead, reason = session.record(t)
            else:
                ahead = session.sample(t, rows, rec)
            if ahead:
                nsteps += 1
            if log is None:
                reason = session.divergence(t + ahead)
            elif reason is None:
                failed = log.add(t_stop, rows, raw, nsteps)
                if failed is not None:
                    return failed
            t += ahead
        if reason is not None:
            return reason, t_stop, nsteps
    return None, None, nsteps


def time_steps(session: Session, h: float, n: int, repeats: int = 3,
               clock=time.perf_counter) -> float:
    """Steps per second of ``n`` bare steps (:meth:`Session.advance`, no readout) from
    the analytic reference state, best of ``repeats``: what the speed studies time.  A
    loop that diverges is timed up to that point.  ``clock``: wall time by default;
    ``time.process_time`` counts this process's CPU only (``xval tune``)."""
    best = 0.0
    chunk = max(1, min(n, 200))
    for _ in range(max(1, repeats)):
        session.reset(0.0, h)
        done, t = 0, 0.0
        t0 = clock()
        while done < n:
            k = min(chunk, n - done)
            why = session.advance(t, h, k)
            done += k
            t += k * h
            if why is not None:
                break
        el = clock() - t0
        if el > 0:
            best = max(best, done / el)
    return best


__all__ = ["HUGE", "LIMITED_RANGE_CONDITION", "EngineRefusal", "EngineRun", "EngineSettings",
           "Plan", "Recorder", "RunRequest", "Session", "SettingsError", "check_motion",
           "RAW_BLOCK", "check_raw_state", "check_state", "compile_linkage", "drive", "finish",
           "first_divergence", "fmt_value", "loop_gap", "loop_gaps", "periodic_plan",
           "plan_samples", "reversal_time", "step_schedule", "steps_to", "time_of",
           "time_steps", "times_plan", "travel_time"]
