"""The engine protocol: settings, session, sampling plan, step schedule, recorder, run loop.

Everything an engine author needs is in this module; an engine is one module
(``sim_models/<name>_engine.py``) with a settings class and a session class, plus one
line in :mod:`sim_models.registry`.  Nothing here imports an engine library.

Data flow (one compiled object passed down)::

    mech = load_case(...)                    # description (analytic.Mechanism)
    tree = compile_linkage(mech)             # SimTree: Linkage + reference solution + tree
    run_ = run(tree, "mujoco", settings)     # EngineRun (carries tree.mech and settings)
    comps = compare_run(run_, tree.linkage)  # reports.compare, the same Linkage

Writing an engine
-----------------
1. **Settings**: subclass :class:`EngineSettings` (a frozen dataclass).  Every field has
   the recommended default, and the class docstring gives the evidence for it (the
   speed-against-error grid, the worst error).  Field types are ``float``, ``int``,
   ``bool``, ``str`` or ``tuple[float, ...]`` so :meth:`EngineSettings.from_overrides`
   can build it from ``key=value`` strings (``xval compare --set steps_per_rev=1008``).
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
   * ``sample(self, t: float, rows, rec: Recorder) -> float``: read the state at time
     ``t`` into rows ``rows`` of ``rec`` in the analytic conventions (below), with
     :meth:`Recorder.put_motion` (tree coordinates) or :meth:`Recorder.put_absolute`
     (absolute body angles/rates) and :meth:`Recorder.put_forces`; return the time the
     session advanced past ``t`` while sampling (0.0, or one step when accelerations
     are finite differences over the next step);
   * ``state(self) -> tuple[np.ndarray, np.ndarray]``: the raw tree coordinates ``q, qd``
     (:class:`SimTree` conventions) for the default divergence check, **or** override
     ``divergence(self, t) -> str | None`` (an engine in absolute coordinates: use
     :func:`check_motion` with the loop gap and the driver rate);
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
samples from there on.  Nothing raises for a diverging simulation.
"""

from __future__ import annotations

import dataclasses
import math
import time
import typing
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from analytic import Linkage, Mechanism, Prismatic, Revolute
from analytic.sweep import input_values

from .tree import SimModelError, SimTree


# ============================================================================ errors
class EngineRefusal(SimModelError):
    """An engine cannot run this mechanism or motion; the message says why (one line).

    The command line prints it and exits with status 2 (never the failed-verdict 1)."""


class SettingsError(SimModelError):
    """A setting key or value is not accepted (names the engine, key and value)."""


# ============================================================================ settings
@dataclass(frozen=True)
class EngineSettings:
    """Base of every engine's settings (frozen dataclass; subclass it).

    ``timestep`` is the largest step, s; the run shortens it so that every sample
    falls on a step.  Subclasses redefine it with their recommended default.
    """

    timestep: float = 1e-3

    # -- construction ----------------------------------------------------------
    @classmethod
    def field_types(cls) -> dict[str, type]:
        hints = typing.get_type_hints(cls)
        return {f.name: hints[f.name] for f in dataclasses.fields(cls)}

    @classmethod
    def from_overrides(cls, overrides: Mapping[str, object] | None = None,
                       engine: str = ""):
        """The recommended settings with ``overrides`` applied.

        Values may be typed (``{"timestep": 1e-4}``) or strings as typed on the command
        line (``{"timestep": "1e-4", "integrator": "Euler", "solref": "-1e4,-200"}``).
        An unknown key or an unparsable value raises :class:`SettingsError` naming it
        and the accepted keys."""
        return cls().with_overrides(overrides, engine)

    def with_overrides(self, overrides: Mapping[str, object] | None, engine: str = ""):
        """A copy with ``overrides`` applied (see :meth:`from_overrides`)."""
        if not overrides:
            return self
        types = self.field_types()
        who = engine or type(self).__name__
        kw = {}
        for key, raw in overrides.items():
            if key not in types:
                raise SettingsError(f"engine {who!r} has no setting {key!r}; settings: "
                                    f"{', '.join(sorted(types))}")
            kw[key] = _convert(who, key, raw, types[key], getattr(self, key))
        return dataclasses.replace(self, **kw)

    # -- use --------------------------------------------------------------------
    def max_step(self, plan: Plan) -> float:
        """Largest step for ``plan`` (s); default :attr:`timestep`."""
        return float(self.timestep)

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)

    def describe(self) -> str:
        """One line: every field as ``key=value``."""
        return " ".join(f"{k}={_fmt_setting(v)}" for k, v in self.as_dict().items())


def _fmt_setting(v) -> str:
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, tuple):
        return "(" + ",".join(_fmt_setting(x) for x in v) + ")"
    return str(v)


def _convert(who: str, key: str, raw, typ, current):
    """``raw`` (typed or a string) as a value of field type ``typ``."""
    origin = typing.get_origin(typ)
    where = f"engine {who!r} setting {key}={raw!r}"
    try:
        if origin is tuple or isinstance(current, tuple):
            parts = raw if isinstance(raw, (tuple, list)) else \
                [x for x in str(raw).strip("()[] ").split(",") if x.strip()]
            val = tuple(float(x) for x in parts)
            if current is not None and len(val) != len(current):
                raise ValueError(f"needs {len(current)} numbers")
            bad = [x for x in val if not math.isfinite(x)]
            if bad:
                raise ValueError("numbers must be finite")
            return val
        if typ is bool or isinstance(current, bool):
            if isinstance(raw, bool):
                return raw
            s = str(raw).strip().lower()
            if s in ("1", "true", "yes", "on"):
                return True
            if s in ("0", "false", "no", "off"):
                return False
            raise ValueError("use true or false")
        if typ is int or (isinstance(current, int) and not isinstance(current, bool)):
            f = float(raw)
            if not math.isfinite(f) or f != int(f):
                raise ValueError("needs a whole number")
            return int(f)
        if typ is float or isinstance(current, float):
            f = float(raw)
            if not math.isfinite(f):
                raise ValueError("needs a finite number")
            return f
        return str(raw)
    except (TypeError, ValueError) as e:
        raise SettingsError(f"{where}: {e}") from None


# ============================================================================ compile
def compile_linkage(mech: Mechanism | SimTree, linkage: Linkage | None = None,
                    chords: str = "moving") -> SimTree:
    """The compiled linkage every engine builds from: the spanning tree, the analytic
    :class:`Linkage` and its reference solution (:class:`SimTree`).  A ``SimTree`` is
    returned as is; pass ``linkage`` to reuse an already built one."""
    if isinstance(mech, SimTree):
        return mech
    return SimTree(mech, linkage, chords=chords)


# ============================================================================ plan
#: A limited-range (or time-sampled) run stops before the first sample whose analytic
#: loop-Jacobian condition number exceeds this (near a limit position, where no finite
#: drive effort moves the linkage and the exact accelerations reach ~1e9).
LIMITED_RANGE_CONDITION = 100.0


@dataclass(frozen=True)
class Plan:
    """When and where a run is sampled.

    ``values`` (N,) driver value at each sample (rad or m; unwrapped), ``times`` (N,)
    s from the start (NaN: not reached), ``velocity``/``acceleration`` (N,) prescribed
    driver rate and acceleration there, ``full`` (a full-turn value plan),
    ``by_time`` (sampled at equal time intervals), ``t_end`` (s, last sample),
    ``rev_time`` (s of one revolution, or of the whole run when not a full turn),
    ``revolutions`` (turns simulated; 1 otherwise)."""

    values: np.ndarray
    times: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    full: bool
    by_time: bool
    t_end: float
    rev_time: float
    revolutions: int

    @property
    def n(self) -> int:
        return len(self.values)


def time_of(d, u: float) -> float:
    """Smallest t >= 0 with value(t) = u for value(t) = v0 + w t + a t^2 / 2 (NaN if none)."""
    c = d.value - u
    if d.acceleration == 0.0:
        if d.velocity == 0.0:
            return 0.0 if c == 0 else math.nan
        t = -c / d.velocity
        return t if t >= -1e-12 else math.nan
    disc = d.velocity ** 2 - 2 * d.acceleration * c
    if disc < 0:
        return math.nan
    r = math.sqrt(disc)
    ts = sorted(((-d.velocity - r) / d.acceleration, (-d.velocity + r) / d.acceleration))
    for t in ts:
        if t >= -1e-12:
            return max(t, 0.0)
    return math.nan


def reversal_time(d) -> float:
    """Time (s) at which the driver's rate changes sign (inf when it never does)."""
    if d.acceleration == 0.0 or d.velocity == 0.0 or d.velocity * d.acceleration > 0:
        return math.inf
    return -d.velocity / d.acceleration


def travel_time(d, distance: float) -> float:
    """Time (s) at which the driver has travelled ``distance`` (rad or m, path length,
    counting both directions of a reversing input)."""
    t_r = reversal_time(d)
    if math.isinf(t_r):
        return time_of(d, d.value + math.copysign(distance, d.velocity or d.acceleration))
    back = abs(d.velocity) * t_r / 2  # travel until the reversal
    if distance <= back:
        return time_of(d, d.value + math.copysign(distance, d.velocity))
    # after the reversal: |a| (t - t_r)^2 / 2 = distance - back
    return t_r + math.sqrt(2 * (distance - back) / abs(d.acceleration))


def plan_samples(tree: SimTree, revolutions: int = 2, samples: int = 36) -> Plan:
    """The sampling plan of a run (see the module docstring).

    Raises :class:`EngineRefusal` when the driver does not move or no sample can be
    reached inside the feasible range."""
    d = tree.mech.driver
    if d.velocity == 0.0 and d.acceleration == 0.0:
        raise EngineRefusal(f"mechanism {tree.mech.name!r}: driver {d.joint!r} has neither "
                            "velocity nor acceleration: there is no motion to simulate")
    if samples < 1:
        raise EngineRefusal(f"samples must be at least 1, got {samples}")
    plan = _value_plan(tree, revolutions, samples)
    if plan is not None:
        return plan
    return _time_plan(tree, revolutions, samples)


def _value_plan(tree: SimTree, revolutions: int, samples: int) -> Plan | None:
    """The sweep's inputs, reached monotonically; None when the motion does not reach
    them so (a reversing or decelerating input)."""
    lk, d = tree.linkage, tree.mech.driver
    vals, full, _ = input_values(lk, samples)
    sgn = math.copysign(1.0, d.velocity if d.velocity != 0 else d.acceleration)
    if full:
        R = max(int(revolutions), 1)
        off = 2 * math.pi * (R - 1) if sgn > 0 else -2 * math.pi * R
        targets = vals + off
        if sgn < 0:  # value v0 itself is reached after R full turns backwards
            targets = np.where(np.isclose(vals, d.value), d.value - 2 * math.pi * (R - 1),
                               targets)
        t_rev = [time_of(d, d.value + sgn * 2 * math.pi * r) for r in range(R + 1)]
    else:
        R = 1
        targets = vals.copy()
        t_rev = [0.0]
    times = np.array([time_of(d, u) for u in targets])
    ok = np.isfinite(times)
    t_reverse = reversal_time(d)
    if full and not ok.all():
        return None
    if not ok.any() or np.nanmax(times) >= t_reverse:
        return None
    if not full:
        kin = lk.kinematics(vals, on_singular="flag")
        bad = ok & ~(kin.condition <= LIMITED_RANGE_CONDITION)
        if bad.any():
            times[times >= np.min(times[bad])] = np.nan
        ok = np.isfinite(times)
        if not ok.any():
            return None
    t_end = float(np.nanmax(times))
    rev_time = (t_rev[-1] - t_rev[0]) / R if full else t_end
    t0 = np.nan_to_num(times)
    vel = np.where(ok, d.velocity + d.acceleration * t0, np.nan)
    return Plan(vals, times, vel, np.full(len(vals), float(d.acceleration)), full, False,
                t_end, rev_time, R)


def _time_plan(tree: SimTree, revolutions: int, samples: int) -> Plan:
    """Equal time intervals over the run, cut before the input leaves its feasible range
    (or comes within :data:`LIMITED_RANGE_CONDITION` of a limit position)."""
    lk, d, mech = tree.linkage, tree.mech.driver, tree.mech
    vals, full, feas = input_values(lk, max(samples, 2))
    R = max(int(revolutions), 1)
    span = 2 * math.pi if full else float(vals[-1] - vals[0])
    t_run = travel_time(d, R * span)
    if not math.isfinite(t_run) or t_run <= 0:
        raise EngineRefusal(f"mechanism {mech.name!r}: driver {d.joint!r} never travels "
                            f"{R} x its range; nothing to sample")
    # cut where the input leaves the feasible interval or nears a limit position: a dense
    # scan of the prescribed path (limit positions are where the input turns back)
    if not full:
        # stay half a sample spacing of the range inside the limit positions: toward one
        # the drive effort and the accelerations grow without bound (1/sqrt of the
        # distance), and a sample there judges the engine on a singularity
        lo, hi = float(vals[0]), float(vals[-1])
        margin = (hi - lo) / (2 * max(samples, 2))
        lo, hi = lo + margin, hi - margin
        tt = np.linspace(0.0, t_run, 4001)
        x = tree.driver_path(tt)[0]
        out = (x < lo) | (x > hi)
        if out.any():
            k = int(np.argmax(out))
            t_run = float(tt[max(k - 1, 0)])
    times = np.linspace(0.0, t_run, samples) if samples > 1 else np.zeros(1)
    x, v, a = (np.asarray(z, float) for z in tree.driver_path(times))
    kin = lk.kinematics(x, v, a, on_singular="flag")
    bad = ~(kin.condition <= LIMITED_RANGE_CONDITION) | ~np.all(np.isfinite(kin.theta), axis=1)
    if bad.any():
        k = int(np.argmax(bad))
        if k == 0:
            raise EngineRefusal(
                f"mechanism {mech.name!r}: the reference input of driver {d.joint!r} sits "
                f"at a limit or singular position (loop condition number "
                f"{float(kin.condition[0]):.3g}); no engine can be driven from there")
        times = np.where(np.arange(len(times)) >= k, np.nan, times)
    ok = np.isfinite(times)
    t_end = float(np.nanmax(times))
    return Plan(x, times, np.where(ok, v, np.nan), a, False, True, t_end, t_end, 1)


def times_plan(tree: SimTree, times) -> Plan:
    """A plan sampling at the given times (s, from the start; e.g. ``per_rev`` equal
    times per revolution over a long run, :func:`periodic_plan`)."""
    times = np.asarray(times, float)
    x, v, a = (np.broadcast_to(np.asarray(z, float), times.shape).copy()
               for z in tree.driver_path(times))
    t_end = float(np.nanmax(times)) if times.size else 0.0
    d = tree.mech.driver
    t_turn = travel_time(d, 2 * math.pi) if isinstance(tree.mech.driver_joint, Revolute) \
        else math.nan
    full = math.isfinite(t_turn) and t_turn > 0
    revs = max(1, round(t_end / t_turn)) if full else 1
    return Plan(x, times, v, a, False, True, t_end, t_turn if full else t_end, revs)


def periodic_plan(tree: SimTree, revolutions: int, per_rev: int) -> Plan:
    """``per_rev`` equal times per revolution (of the driver's first turn) over
    ``revolutions`` turns, from t = 0 (``revolutions * per_rev + 1`` samples)."""
    d = tree.mech.driver
    T = travel_time(d, 2 * math.pi)
    if not (math.isfinite(T) and T > 0):
        raise EngineRefusal(f"mechanism {tree.mech.name!r}: driver {d.joint!r} never "
                            "completes a turn; no periodic sampling")
    return times_plan(tree, np.arange(revolutions * per_rev + 1) * T / per_rev)


def step_schedule(times: np.ndarray, dt_max: float):
    """Step sizes so that every finite sample time is a step boundary.

    Returns ``order`` (sample indices by time), ``stops`` (0 and the distinct sample
    times) and ``steps``: one ``(h, n)`` per interval between consecutive stops
    (``n = 0`` for a sample at t = 0).  When every interval is a whole multiple of one
    step (evenly spaced samples) that common step is used, so that finite differences
    see equal steps on both sides of a sample."""
    order = np.argsort(np.where(np.isfinite(times), times, np.inf))
    stops = [0.0]
    steps = []
    if np.any(np.asarray(times)[np.isfinite(times)] <= 1e-15):
        stops.append(0.0)
        steps.append((dt_max, 0))
    for i in order:
        if np.isfinite(times[i]) and times[i] > stops[-1] + 1e-15:
            stops.append(float(times[i]))
    lengths = np.diff(stops[len(steps):]) if len(stops) > len(steps) + 1 else np.array([])
    h_common = None
    if len(lengths):
        lmin = float(np.min(lengths))
        h = lmin / max(1, math.ceil(lmin / dt_max - 1e-9))
        k = lengths / h
        if np.all(np.abs(k - np.round(k)) < 1e-6 * np.maximum(k, 1.0)):
            h_common = h
    for a, b in zip(stops[len(steps):-1], stops[len(steps) + 1:], strict=True):
        if h_common is not None:
            n = max(1, int(round((b - a) / h_common)))
        else:
            n = max(1, math.ceil((b - a) / dt_max - 1e-9))
        steps.append(((b - a) / n, n))
    return order, stops, steps


def steps_to(t: float, t_stop: float, h: float, dt_max: float) -> tuple[float, int]:
    """``(h, n)`` reaching ``t_stop`` from ``t``: keep ``h`` when the gap is a whole
    number of it (a session that stepped past a sample), else the fewest equal steps no
    longer than ``dt_max``."""
    rem = t_stop - t
    if rem <= 1e-15:
        return h, 0
    k = rem / h
    if abs(k - round(k)) < 1e-6 * max(k, 1.0) and round(k) >= 1:
        return rem / round(k), int(round(k))
    n = max(1, math.ceil(rem / dt_max - 1e-9))
    return rem / n, n


# ============================================================================ recorder
class Recorder:
    """Sample arrays of a run, NaN until filled (shapes as :class:`EngineRun`).

    Besides the analytic-convention arrays it keeps the raw tree coordinates ``q, qd,
    qdd`` (N, nt) of each sample (for the long-run diagnostics)."""

    def __init__(self, tree: SimTree, plan: Plan):
        N = plan.n
        B = len(tree.body_names)
        J = len(tree.mech.joints)
        P = len(tree.prismatic)
        nt = len(tree.joints)
        nan = np.nan
        self.tree = tree
        self.times = plan.times
        self.theta = np.full((N, B), nan)
        self.omega = np.full((N, B), nan)
        self.alpha = np.full((N, B), nan)
        self.slider_acc = np.full((N, P), nan)
        self.effort = np.full(N, nan)
        self.effort_engine = np.full(N, nan)
        self.force = np.full((N, J, 2), nan)
        self.force_engine = np.full((N, J, 2), nan)
        self.normal = np.full((N, P), nan)
        self.moment = np.full((N, P), nan)
        self.viol = np.full(N, nan)
        self.speed = np.full(N, nan)
        self.measured = np.full(N, nan)
        self.q = np.full((N, nt), nan)
        self.qd = np.full((N, nt), nan)
        self.qdd = np.full((N, nt), nan)

    def put_motion(self, rows, t: float, q, qd, qdd):
        """Fill the motion of ``rows`` from tree coordinates (SimTree conventions):
        absolute theta/omega/alpha, slider accelerations, the measured driver value, the
        driver-rate deviation from the prescribed rate at ``t`` and the loop gap.
        Returns ``(theta, omega, alpha, origin, v_origin, a_origin)`` of
        :meth:`SimTree.propagate` (each with one row) for the force readout."""
        st = self.tree
        q, qd, qdd = (np.asarray(x, float) for x in (q, qd, qdd))
        prop = st.propagate(q[None], qd[None], qdd[None])
        th, om, al, org = prop[:4]
        gap = loop_gap(st, th, org)
        _, vel, _ = st.driver_path(t)
        rate = st.driver_sigma * qd[st.driver_tree]
        for i in np.atleast_1d(rows):
            self.theta[i], self.omega[i], self.alpha[i] = th[0], om[0], al[0]
            self.q[i], self.qd[i], self.qdd[i] = q, qd, qdd
            self.measured[i] = st.driver_value(q[st.driver_tree])
            self.viol[i] = gap
            self.speed[i] = rate - float(vel)
            for p, k in enumerate(st.prismatic):
                ti = st.tree_joint_indices.index(k)
                self.slider_acc[i, p] = st.joints[ti].sigma * qdd[ti]
        return prop

    def put_absolute(self, rows, t: float, theta, omega, alpha, slider_acc, origin,
                     driver_value: float, driver_rate: float):
        """Fill the motion of ``rows`` from absolute body quantities, for engines in
        absolute coordinates: ``theta, omega, alpha`` (B,) rad, rad/s, rad/s^2 of every
        body's own frame (the description's body frame, ground included), ``slider_acc``
        (P,) m/s^2 of each prismatic joint's ``s''``, ``origin`` (B, 2) m the body-frame
        origins (for the loop gap), the engine's driver value (rad or m) and rate."""
        st = self.tree
        th = np.asarray(theta, float)[None]
        gap = loop_gap(st, th, np.asarray(origin, float)[None])
        _, vel, _ = st.driver_path(t)
        for i in np.atleast_1d(rows):
            self.theta[i], self.omega[i], self.alpha[i] = theta, omega, alpha
            self.slider_acc[i] = slider_acc
            self.measured[i] = driver_value
            self.viol[i] = gap
            self.speed[i] = driver_rate - float(vel)

    def put_forces(self, rows, joint_force, effort, normal=None, moment=None,
                   force_engine=None, effort_engine=None):
        """Fill the forces of ``rows``: ``joint_force`` (J, 2) by body_a on body_b,
        ``effort`` (drive, on body_b), ``normal``/``moment`` (P,), and the engine's own
        unjudged readings when it has them."""
        for i in np.atleast_1d(rows):
            self.force[i] = joint_force
            self.effort[i] = effort
            if normal is not None:
                self.normal[i] = normal
            if moment is not None:
                self.moment[i] = moment
            if force_engine is not None:
                self.force_engine[i] = force_engine
            if effort_engine is not None:
                self.effort_engine[i] = effort_engine

    def fail(self, t_stop: float, reason: str) -> tuple[str, float]:
        """End a run at ``t_stop``: samples at or after it become NaN.  Returns the
        reason naming the (prescribed) driver value there, and that value."""
        st = self.tree
        fail = float(st.driver_path(t_stop)[0])
        late = np.asarray(self.times) >= t_stop - 1e-15
        for arr in (self.theta, self.omega, self.alpha, self.slider_acc, self.effort,
                    self.force, self.normal, self.moment, self.viol, self.speed,
                    self.effort_engine, self.force_engine, self.q, self.qd, self.qdd):
            arr[late] = np.nan
        return f"{reason} at driver {st.mech.driver.joint!r} = {fmt_value(st, fail)}", fail


def loop_gap(tree: SimTree, theta, origin) -> float:
    """Largest distance (m) between the two points of a loop-closing joint."""
    gap = 0.0
    for ch in tree.chords:
        pa = tree.point_world(theta, origin, ch.body_a, ch.point_a)[0]
        pb = tree.point_world(theta, origin, ch.body_b, ch.point_b)[0]
        gap = max(gap, float(np.linalg.norm(pa - pb)))
    return gap


def fmt_value(tree: SimTree, v: float) -> str:
    if isinstance(tree.mech.driver_joint, Revolute):
        return f"{math.degrees(v):.4g} deg"
    return f"{v:.6g} m"


# ============================================================================ result
@dataclass(frozen=True)
class RunRequest:
    """How a run was asked for: enough, with the mechanism and settings, to re-run it
    exactly (:func:`rerun`)."""

    revolutions: int = 2
    samples: int = 36
    max_violation: float = 1e-3
    max_speed_error: float = 1e-2
    chords: str = "moving"
    mode: str = "run"               # "run" or "instantaneous"


@dataclass(frozen=True)
class EngineRun:
    """Engine results at the sampled driver values (SI, world axes, analytic conventions).

    Arrays have N rows, one per sample; B bodies (``body_names``, the description's
    order), J joints (``joint_names``), P prismatic joints (``prismatic_names``).
    ``mechanism``, ``settings`` (the settings object) and ``request`` re-run it exactly:
    :func:`rerun`.  ``settings_text`` is ``settings.describe()``.
    """

    case: str
    engine: str
    mechanism: Mechanism
    settings: EngineSettings
    request: RunRequest
    ok: bool
    reason: str | None
    fail_value: float | None          # driver value (rad or m) where the run failed
    values: np.ndarray                # (N,) driver values at the samples
    times: np.ndarray                 # (N,) s from the start of the run (NaN: unreached)
    driver_velocity: np.ndarray       # (N,) prescribed driver rate at the sample
    driver_acceleration: np.ndarray   # (N,) prescribed driver acceleration
    measured_values: np.ndarray       # (N,) driver value in the engine at the sample
    body_names: tuple[str, ...]
    joint_names: tuple[str, ...]
    prismatic_names: tuple[str, ...]
    theta: np.ndarray                 # (N, B) rad
    omega: np.ndarray                 # (N, B) rad/s
    alpha: np.ndarray                 # (N, B) rad/s^2, absolute
    slider_acc: np.ndarray            # (N, P) m/s^2 (s'' of each prismatic joint)
    drive_effort: np.ndarray          # (N,) N m or N, on body_b / the slider
    joint_force: np.ndarray           # (N, J, 2) N, by body_a on body_b
    normal: np.ndarray                # (N, P) N
    moment: np.ndarray                # (N, P) N m
    loop_violation: np.ndarray        # (N,) m, largest gap at a loop-closing joint
    speed_deviation: np.ndarray       # (N,) driver rate minus prescribed rate
    wall_per_rev: float               # s of stepping per revolution (per run if not full)
    timestep: float
    steps_per_rev: float
    steps: int                        # steps taken (pre-roll included)
    wall: float                       # s of the whole stepping loop
    has_forces: bool                  # False: placeholder masses, forces not comparable
    by_time: bool = False             # sampled at equal times (not the sweep's inputs)
    notes: tuple[str, ...] = ()
    drive_effort_engine: np.ndarray | None = None      # engine's own drive reading
    joint_force_engine: np.ndarray | None = None       # engine's own pin-force reading
    q: np.ndarray | None = None       # (N, nt) raw tree coordinates (SimTree)
    qd: np.ndarray | None = None
    qdd: np.ndarray | None = None
    extra: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(self.values)

    @property
    def settings_text(self) -> str:
        return self.settings.describe()

    def frame(self):
        """A DataFrame with the sweep's column names (see :mod:`analytic.sweep`)."""
        import pandas as pd
        revolute = not self.extra.get("prismatic_driver", False)
        cols = {"input": np.degrees(self.values) if revolute else self.values}
        for b, name in enumerate(self.body_names):
            cols[f"{name}.angle_deg"] = 180.0 - np.mod(180.0 - np.degrees(self.theta[:, b]),
                                                       360.0)
            cols[f"{name}.omega"] = self.omega[:, b]
            cols[f"{name}.alpha"] = self.alpha[:, b]
        for p, name in enumerate(self.prismatic_names):
            cols[f"{name}.a"] = self.slider_acc[:, p]
            cols[f"{name}.normal"] = self.normal[:, p]
            cols[f"{name}.moment"] = self.moment[:, p]
        for j, name in enumerate(self.joint_names):
            cols[f"{name}.fx"] = self.joint_force[:, j, 0]
            cols[f"{name}.fy"] = self.joint_force[:, j, 1]
        cols["drive.torque" if revolute else "drive.force"] = self.drive_effort
        cols["loop_violation"] = self.loop_violation
        cols["speed_deviation"] = self.speed_deviation
        return pd.DataFrame(cols)


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
        case=mech.name, engine=engine or session.name, mechanism=mech,
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
        q=rec.q, qd=rec.qd, qdd=rec.qdd, extra=ex)


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
        self.max_violation = 1e-3
        self.max_speed_error = 1e-2

    # -- the contract -------------------------------------------------------------
    @abstractmethod
    def reset(self, t: float, h: float) -> None:
        """Analytic assembled state at time ``t`` (s) of the prescribed motion, drive
        set; ``h`` is the first step the run will take (s)."""

    @abstractmethod
    def advance(self, t: float, h: float, n: int) -> str | None:
        """``n`` steps of ``h`` s from time ``t``; a divergence reason or None."""

    @abstractmethod
    def sample(self, t: float, rows, rec: Recorder) -> float:
        """Fill ``rows`` of ``rec`` at time ``t``; return the time stepped past ``t``."""

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
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
        return "non-finite state (simulation diverged)"
    if np.max(np.abs(qd), initial=0.0) > HUGE:
        return "huge velocities (simulation diverged)"
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


#: Velocities above this (MuJoCo's own "huge value" threshold) count as divergence.
HUGE = 1e10


# ============================================================================ run loop
def drive(session: Session, plan: Plan, request: RunRequest | None = None) -> EngineRun:
    """Step ``session`` through ``plan`` and sample it: **the one run loop** of the
    verdict runs, the speed grids, the hard cases, the long runs and the scene study.

    Resets to the analytic state at t = 0, then for each stop of
    :func:`step_schedule`: :meth:`Session.advance` to it, :meth:`Session.sample` the
    samples there, :meth:`Session.divergence`.  A divergence ends the run (``ok =
    False``, NaN samples from there on).  ``wall`` times the whole loop."""
    request = request or RunRequest()
    session.max_violation = request.max_violation
    session.max_speed_error = request.max_speed_error
    st = session.tree
    rec = Recorder(st, plan)
    dt_max = session.settings.max_step(plan)
    order, stops, steps = step_schedule(plan.times, dt_max)
    sample_at: dict[float, list[int]] = {}
    for i in order:
        if np.isfinite(plan.times[i]):
            key = float(plan.times[i]) if plan.times[i] > 1e-15 else 0.0
            sample_at.setdefault(key, []).append(int(i))
    reason = fail = None
    dt_used = max((h for h, n in steps if n > 0), default=dt_max)
    nsteps = 0
    t0 = time.perf_counter()
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
            ahead = session.sample(t, sample_at.get(t_stop, []), rec)
            if ahead:
                nsteps += 1
            reason = session.divergence(t + ahead)
            t += ahead
        if reason is not None:
            reason, fail = rec.fail(t_stop, reason)
            break
    wall = time.perf_counter() - t0
    return finish(session, plan, rec, request, reason, fail, wall, dt_used, nsteps)


def time_steps(session: Session, h: float, n: int, repeats: int = 3) -> float:
    """Steps per second of ``n`` bare steps (:meth:`Session.advance`, no readout) from
    the analytic reference state, best of ``repeats``: what the speed studies time.  A
    loop that diverges is timed up to that point."""
    best = 0.0
    chunk = max(1, min(n, 200))
    for _ in range(max(1, repeats)):
        session.reset(0.0, h)
        done, t = 0, 0.0
        t0 = time.perf_counter()
        while done < n:
            k = min(chunk, n - done)
            why = session.advance(t, h, k)
            done += k
            t += k * h
            if why is not None:
                break
        el = time.perf_counter() - t0
        if el > 0:
            best = max(best, done / el)
    return best


__all__ = ["HUGE", "LIMITED_RANGE_CONDITION", "EngineRefusal", "EngineRun", "EngineSettings",
           "Plan", "Recorder", "RunRequest", "Session", "SettingsError", "check_motion",
           "check_state",
           "compile_linkage", "drive", "finish", "fmt_value", "loop_gap", "plan_samples",
           "periodic_plan", "reversal_time", "step_schedule", "steps_to", "time_of",
           "time_steps", "times_plan", "travel_time"]
