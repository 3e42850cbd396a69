"""The sampling plan and step schedule shared by every engine (see
:mod:`sim_models.engines.protocol`): when a run is sampled, and the steps that land on every
sample time."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from analytic import Revolute
from analytic.sweep import input_values

from ..builders.tree import SimTree
from ..engines.settings import EngineRefusal

# ============================================================================ plan
#: A limited-range (or time-sampled) run stops before the first sample whose analytic
#: loop-Jacobian condition number exceeds this (near a limit position, where no finite
#: drive effort moves the linkage and the exact accelerations reach ~1e9).
LIMITED_RANGE_CONDITION = 100.0


def near_limit(condition, limit: float = LIMITED_RANGE_CONDITION) -> np.ndarray:
    """Where a sample sits at or near a limit or singular position: its analytic
    loop-Jacobian condition number ``condition`` (array) above ``limit``, or NaN.  The one
    decision of "near a limit position": a limited-range run stops before the first such
    sample, and the verdicts leave such samples out (:mod:`reports.comparison.reference`)."""
    return ~(np.asarray(condition, float) <= limit)


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


def plan_samples(tree: SimTree, revolutions: int, samples: int) -> Plan:
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
        bad = ok & near_limit(kin.condition)
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
    bad = near_limit(kin.condition) | ~np.all(np.isfinite(kin.theta), axis=1)
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
    tl = np.asarray(times, float).tolist()  # Python floats: a loop over samples
    for i in order.tolist():
        if math.isfinite(tl[i]) and tl[i] > stops[-1] + 1e-15:
            stops.append(tl[i])
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


__all__ = ["LIMITED_RANGE_CONDITION", "Plan", "periodic_plan", "plan_samples",
           "reversal_time", "step_schedule", "steps_to", "time_of", "times_plan",
           "travel_time"]
