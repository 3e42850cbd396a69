"""Free-motion description: the initial state, duration and force elements of a released
linkage (``[motion]``, ``[[springs]]``, ``[[dampers]]``, ``[[motors]]`` in the TOML).

A prescribed run reads ``[driver]``; a free run (``xval simulate``,
:func:`analytic.free_motion.simulate`) reads :class:`FreeMotion` and ignores the
driver's rates.  All values here are SI (rad, m, s, N, N m).

Sign conventions (those of :mod:`analytic.mechanism`):

* A joint's coordinate is the angle of ``body_b`` relative to ``body_a`` (rad,
  counter-clockwise) for a revolute joint, the displacement ``s`` of a prismatic one.
* A linear spring or damper between point ``a`` and point ``b`` pulls them together
  when its force ``k (L - L0) + c L'`` is positive (tension).
* A joint spring or damper acts on the joint's coordinate: its effort on ``body_b``
  (slider) is ``-k (x - x0) - c x'``, the opposite on ``body_a`` (guide).
* A motor's effort (N m or N) acts on ``body_b`` (slider) along the coordinate, the
  reaction on ``body_a`` (guide), as the driver's effort does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

from .errors import DescriptionError

#: Longest free-motion duration, s (about 3 hours of simulated time: far beyond any
#: benchmark, short enough that a 1e-12 integration still finishes).
MAX_DURATION = 1e4
#: Most output samples of a free trajectory (a table of 8 bytes x ~100 columns x 1e6
#: rows is ~1 GB).
MAX_SAMPLES = 1_000_000
#: Most values in a free trajectory's sample table (samples x :func:`sample_columns`):
#: a four-bar's 21 columns at :data:`MAX_SAMPLES`, measured at 2.4 GB peak with ``xval
#: simulate --json`` (0.75 GB printed or as CSV).  Memory grows with the joints (A02's
#: 121 joints took 1.1 GB at 1e5 samples), so a larger mechanism gets proportionally
#: fewer samples (:func:`max_samples`; A02: 56,451).
MAX_SAMPLE_VALUES = 21 * MAX_SAMPLES
#: Largest stiffness (N/m, N m/rad) and damping coefficient (N s/m, N m s/rad).
MAX_STIFFNESS = 1e12
#: Largest motor effort (N m or N), as a load.
MAX_EFFORT = 1e12
#: Most rows of a motor table.
MAX_TABLE = 100_000
#: Largest wall-clock limit (s) of one run, exact or engine: one day.  The exact
#: integration's ``wall_limit`` (:mod:`analytic.free_motion.clock`) and the engines'
#: ``--wall-limit`` range (``sim_models.engines.ranges.WALL_LIMIT``) both use it.
MAX_WALL_LIMIT = 86400.0


@dataclass(frozen=True)
class PointSpring:
    """A linear spring from ``point_a`` of ``body_a`` to ``point_b`` of ``body_b``:
    stiffness N/m, free length m."""

    body_a: str
    point_a: str
    body_b: str
    point_b: str
    stiffness: float
    free_length: float


@dataclass(frozen=True)
class JointSpring:
    """A spring on a joint's coordinate: torsional (revolute: N m/rad, free angle rad) or
    axial (prismatic: N/m, free displacement m)."""

    joint: str
    stiffness: float
    free_value: float


@dataclass(frozen=True)
class PointDamper:
    """A linear viscous damper between two body points, along their line: N s/m."""

    body_a: str
    point_a: str
    body_b: str
    point_b: str
    coefficient: float


@dataclass(frozen=True)
class JointDamper:
    """A viscous damper on a joint's coordinate: N m s/rad (revolute) or N s/m."""

    joint: str
    coefficient: float


class _NoTable(tuple):
    """The empty ``times``/``efforts`` of a constant motor (their default): told apart
    from a table given with no rows (``times=()``), which :func:`check_motion` refuses
    (it would otherwise run as a motor of no effort).  Equal to ``()``, so a motor's
    identity (``reports.regression.model_identity``) is unchanged."""

    __slots__ = ()


#: The default of :attr:`Motor.times` and :attr:`Motor.efforts`: no table.
NO_TABLE = _NoTable()


@dataclass(frozen=True)
class Motor:
    """An effort on a joint's coordinate: constant (``effort``; ``times`` and
    ``efforts`` not given) or a table ``(times s, efforts)`` of at least 2 rows
    interpolated linearly, times strictly increasing."""

    joint: str
    effort: float = 0.0
    times: tuple[float, ...] = NO_TABLE
    efforts: tuple[float, ...] = NO_TABLE

    @property
    def tabulated(self) -> bool:
        """Whether a table was given (``times`` or ``efforts``, even empty)."""
        return not (isinstance(self.times, _NoTable) and isinstance(self.efforts, _NoTable))

    def at(self, t: float) -> float:
        """The effort at time ``t`` (s): N m or N."""
        if not self.times:
            return self.effort
        import numpy as np  # only here: the description needs no numpy otherwise
        ts, es = self._table
        return float(np.interp(t, ts, es))

    @cached_property
    def _table(self):
        """The table as arrays, converted once (np.interp converts a tuple at every call:
        5 ms for 100,000 rows, at every evaluation of the equation of motion)."""
        import numpy as np
        return np.asarray(self.times, float), np.asarray(self.efforts, float)


@dataclass(frozen=True)
class FreeMotion:
    """How a linkage is released: the initial value (rad or m) and rate of ``joint``'s
    coordinate, the duration (s), the default number of output samples, and the force
    elements (besides the mechanism's gravity and constant loads)."""

    joint: str
    value: float
    rate: float
    duration: float
    samples: int = 201
    springs: tuple[PointSpring | JointSpring, ...] = ()
    dampers: tuple[PointDamper | JointDamper, ...] = ()
    motors: tuple[Motor, ...] = ()


def _w(mech, what: str) -> str:
    return f"{mech.source}: {what}" if mech.source else what


def _nonneg(x: float, limit: float, what: str, unit: str, where: str) -> None:
    if not (isinstance(x, int | float) and math.isfinite(x)):
        raise DescriptionError(f"{what} must be a finite number, got {x!r}", where)
    if x < 0:
        raise DescriptionError(f"{what} must be >= 0 {unit}, got {x:g}", where)
    if x > limit:
        raise DescriptionError(f"{what} = {x:g} {unit} is out of range: the accepted range "
                               f"is 0 to {limit:g} {unit}", where)


def _points(mech, el, where: str) -> None:
    bodies = {b.name: b for b in mech.bodies}
    for bn, pn in ((el.body_a, el.point_a), (el.body_b, el.point_b)):
        if bn not in bodies:
            raise DescriptionError(f"unknown body {bn!r}; bodies are {list(bodies)}", where)
        if pn not in bodies[bn].points:
            raise DescriptionError(f"body {bn!r} has no point {pn!r}; it has "
                                   f"{sorted(bodies[bn].points)}", where)
    if el.body_a == el.body_b:
        raise DescriptionError(f"attached to body {el.body_a!r} at both ends: a force "
                               "element must join two different bodies", where)


def _joint(mech, name: str, where: str):
    for j in mech.joints:
        if j.name == name:
            return j
    raise DescriptionError(f"unknown joint {name!r}; joints are "
                           f"{[j.name for j in mech.joints]}", where)


def check_motion(mech) -> None:
    """Validate ``mech.motion`` against the mechanism; raise :class:`DescriptionError`
    naming the file and the element (``spring 1``, ``motor 0``, ``[motion]``)."""
    fm: FreeMotion = mech.motion
    mw = _w(mech, "[motion]")
    _joint(mech, fm.joint, mw)
    for k, x in (("value", fm.value), ("rate", fm.rate)):
        if not (isinstance(x, int | float) and math.isfinite(x)):
            raise DescriptionError(f"{k} must be a finite number, got {x!r}", mw)
    if not (isinstance(fm.duration, int | float) and 0 < fm.duration <= MAX_DURATION):
        raise DescriptionError(f"duration = {fm.duration!r} s is out of range: the accepted "
                               f"range is 0 < duration <= {MAX_DURATION:g} s", mw)
    if (bad := samples_problem(mech, fm.samples)) is not None:
        raise DescriptionError(f"samples = {bad}", mw)
    for i, s in enumerate(fm.springs):
        sw = _w(mech, f"spring {i}")
        if isinstance(s, PointSpring):
            _points(mech, s, sw)
            _nonneg(s.free_length, 1e4, "free_length", "m", sw)
        else:
            _joint(mech, s.joint, sw)
        _nonneg(s.stiffness, MAX_STIFFNESS, "stiffness", "N/m or N m/rad", sw)
    for i, d in enumerate(fm.dampers):
        dw = _w(mech, f"damper {i}")
        if isinstance(d, PointDamper):
            _points(mech, d, dw)
        else:
            _joint(mech, d.joint, dw)
        _nonneg(d.coefficient, MAX_STIFFNESS, "coefficient", "N s/m or N m s/rad", dw)
    for i, m in enumerate(fm.motors):
        _check_motor(mech, m, fm.duration, _w(mech, f"motor {i}"))


def sample_columns(mech) -> int:
    """Columns of a free trajectory's sample table (``xval simulate --csv``/``--json``):
    the time, each joint's coordinate, rate and acceleration, the integrated coordinate,
    and 7 energy, work and power columns."""
    return 3 * len(mech.joints) + 9


def max_samples(mech) -> int:
    """The most output samples of ``mech``'s free trajectory: :data:`MAX_SAMPLES`, fewer
    for a mechanism whose table would exceed :data:`MAX_SAMPLE_VALUES` values."""
    return max(2, min(MAX_SAMPLES, MAX_SAMPLE_VALUES // sample_columns(mech)))


def samples_problem(mech, n) -> str | None:
    """``None`` when ``n`` output samples are in range for ``mech`` (every door: the
    file's ``[motion] samples``, ``xval simulate --samples``), else the range in words."""
    top = max_samples(mech)
    if not isinstance(n, bool) and isinstance(n, int) and 2 <= n <= top:
        return None
    why = "" if top == MAX_SAMPLES else (
        f" for {len(mech.joints)} joints ({sample_columns(mech)} columns a sample, at "
        f"most {MAX_SAMPLE_VALUES:,} values: memory)")
    return f"{n!r} is out of range: the accepted range is 2 to {top}{why}"


def _check_motor(mech, m: Motor, duration: float, where: str) -> None:
    _joint(mech, m.joint, where)
    if not m.tabulated:
        if not (math.isfinite(m.effort) and abs(m.effort) <= MAX_EFFORT):
            raise DescriptionError(f"effort = {m.effort:g} is out of range: the accepted range "
                                   f"is |effort| <= {MAX_EFFORT:g} N m or N", where)
        return
    if m.effort != 0.0:
        raise DescriptionError("a motor needs exactly one of effort (constant) or table "
                               "([[time s, effort], ...]), not both", where)
    if len(m.times) != len(m.efforts):
        raise DescriptionError(f"table: {len(m.times)} times and {len(m.efforts)} efforts; "
                               "each row [time, effort] needs both", where)
    if len(m.times) < 2:
        raise DescriptionError(f"table has {len(m.times)} row(s): a motor table needs at "
                               "least 2 rows [time, effort] (a constant effort: give effort "
                               "instead)", where)
    if len(m.times) > MAX_TABLE:
        raise DescriptionError(f"a motor table has at most {MAX_TABLE} rows, got "
                               f"{len(m.times)}", where)
    for k, (t, e) in enumerate(zip(m.times, m.efforts, strict=True)):
        if not (math.isfinite(t) and math.isfinite(e) and abs(e) <= MAX_EFFORT):
            raise DescriptionError(f"table row {k} [{t!r}, {e!r}]: time and effort must be "
                                   f"finite, |effort| <= {MAX_EFFORT:g}", where)
        if k and not t > m.times[k - 1]:
            raise DescriptionError(f"table times must be strictly increasing: row {k} has "
                                   f"t = {t:g} s after t = {m.times[k - 1]:g} s", where)
    if m.times[0] > 0 or m.times[-1] < duration:
        raise DescriptionError(f"the table covers t = {m.times[0]:g} to {m.times[-1]:g} s; "
                               f"it must cover the run, 0 to {duration:g} s", where)


def check_duration(mech, duration: float) -> None:
    """A run of ``duration`` s other than the description's (``xval simulate
    --duration``): in range, and covered by every motor table (a table is never
    extrapolated); :class:`DescriptionError` naming the file and the motor."""
    if not (isinstance(duration, int | float) and 0 < duration <= MAX_DURATION):
        raise DescriptionError(f"duration = {duration!r} s is out of range: the accepted "
                               f"range is 0 < duration <= {MAX_DURATION:g} s", mech.source)
    for i, m in enumerate(mech.motion.motors):
        if m.times and m.times[-1] < duration:
            raise DescriptionError(f"the table covers t = {m.times[0]:g} to {m.times[-1]:g} s; "
                                   f"it must cover the run, 0 to {duration:g} s (the duration "
                                   "asked)", _w(mech, f"motor {i}"))


def unreachable(mech, err, rev: bool) -> DescriptionError:
    """The one line of an initial state the loops cannot reach: ``err`` the solver's
    :class:`analytic.errors.AssemblyError` at ``[motion]``'s joint and value, said as
    the description's ``[motion]`` (not a driver), with the feasible ranges it found;
    ``rev`` whether that joint is revolute (degrees) or prismatic (metres).  The caller
    says which: this module sits below :mod:`analytic.mechanism`."""
    fm: FreeMotion = mech.motion

    def shown(v: float) -> str:
        return f"{math.degrees(v):.6g} deg" if rev else f"{v:.6g} m"

    feas = getattr(err, "feasible", None)
    rng = (f"the feasible range(s) of joint {fm.joint!r}: "
           + ", ".join(f"[{shown(a)}, {shown(b)}]" for a, b in feas) if feas
           else "no assembly was found at that value")
    return DescriptionError(f"the initial state cannot be reached: the loops cannot close "
                            f"at joint {fm.joint!r} = {shown(fm.value)}; {rng}",
                            _w(mech, "[motion]"))
