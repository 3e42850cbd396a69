"""The engineering summary of a sweep: stroke, swing, time ratio, transmission, peak effort.

All figures come from the sweep's own arrays and events (:mod:`analytic.sweep`), so
the summary and the table beside it are the same computation.

* **Stroke** of each slider (not the driver): ``max s - min s`` over the sweep (m).
* **Swing** of each rocker (a moving body pivoted on the ground, other than the
  input): ``max - min`` of its unwrapped angle (deg); a body that turns fully in a full
  cycle is a crank and has no swing.
* **Time ratio**: where a slider or rocker reverses twice per full cycle, the input
  spans of its two strokes (between its limit positions); at constant input speed the
  times are in the same ratio.  Reported as slower / quicker (>= 1), with the
  direction of the slower stroke.
* The limit positions (where the rate changes sign), and the stroke's and swing's
  extremes there, are located on the solver between the samples
  (:func:`analytic.refine.turning_points`, to 1e-12 rad or of the size), so they, the spans
  and the ratio are exact to the digits printed, at any number of points.
* **Transmission angle** of each dyad: its least value folded into 0..90 deg and its
  largest deviation from 90 deg (= 90 - least), with where it occurs.
* **Peak drive effort** and the event nearest it (a peak next to a limit or singular
  position is the mechanism's own, not an error); an interior peak is located on the
  solver between the samples beside the largest one (:func:`analytic.refine.peak`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .mechanism import Revolute
from .refine import least_transmission, peak, turning_points, unit_rate_kinematics
from .tolerances import SINGULAR_CONDITION

#: The peak drive effort is said to sit at an event (singular position, change point,
#: input limit) when within this fraction of the swept range: 5 deg of a turn.
NEAR_EVENT = 5.0 / 360.0


@dataclass(frozen=True)
class Stroke:
    """A slider's (``kind="slider"``, m) or rocker's (``"rocker"``, deg) travel."""

    kind: str
    name: str
    low: float
    high: float
    travel: float
    turns_fully: bool = False
    #: input spans (frame units) of the two strokes between the limit positions, the
    #: slower first, and the direction of the slower one ("increasing"/"decreasing")
    slow_span: float | None = None
    quick_span: float | None = None
    slow_direction: str | None = None

    @property
    def time_ratio(self) -> float | None:
        if self.slow_span is None or not self.quick_span:
            return None
        return self.slow_span / self.quick_span


@dataclass(frozen=True)
class TransmissionSummary:
    joint: str
    least_deg: float
    at: float
    largest_deviation_deg: float


@dataclass
class Summary:
    """See the module docstring.  Inputs are in the sweep frame's units (``unit``)."""

    unit: str
    first: float
    last: float
    full_cycle: bool
    reference: float
    strokes: list[Stroke] = field(default_factory=list)
    transmission: list[TransmissionSummary] = field(default_factory=list)
    effort_name: str | None = None
    effort_unit: str | None = None
    peak_effort: float | None = None
    peak_effort_at: float | None = None
    peak_event: object = None
    constant_speed: bool = True
    #: samples at singular positions (condition number >= SINGULAR_CONDITION), whose
    #: rates and forces are not determined by the input: left out of the peak effort
    singular_samples: int = 0
    #: power balance error over the regular samples, relative to the size of the power
    #: terms (:func:`_power_scale`)
    power_balance: float | None = None

    def lines(self) -> list[str]:
        """Plain-text lines for the command line."""
        u = self.unit
        out = [f"input {self.first:.6g} to {self.last:.6g} {u}"
               + (" (one full turn)" if self.full_cycle else " (limited range)")
               + f"; reference value {self.reference:.6g} {u}"]
        for s in self.strokes:
            unit = "m" if s.kind == "slider" else "deg"
            if s.turns_fully:
                out.append(f"{s.name} turns fully")
                continue
            # "stroke of slider ram", "swing of rocker" (a body's name often is its kind)
            what = f"stroke of slider {s.name}" if s.kind == "slider" else f"swing of {s.name}"
            line = f"{what}: {s.travel:.6g} {unit} ({s.low:.6g} to {s.high:.6g} {unit})"
            if s.time_ratio is not None:
                line += (f", time ratio {s.time_ratio:.4f} (slower stroke {s.slow_direction}"
                         f" over {s.slow_span:.4f} {u} of input, quicker over "
                         f"{s.quick_span:.4f} {u}"
                         + ("" if self.constant_speed else "; input spans, the input "
                            "accelerates") + ")")
            out.append(line)
        for t in self.transmission:
            out.append(f"transmission angle at {t.joint}: least {t.least_deg:.3f} deg at "
                       f"{t.at:.6g} {u}, largest deviation from 90 deg "
                       f"{t.largest_deviation_deg:.3f} deg")
        if self.peak_effort is not None:
            line = (f"peak |{self.effort_name}| {self.peak_effort:.6g} {self.effort_unit} at "
                    f"{self.peak_effort_at:.6g} {u}")
            ev = self.peak_event
            if ev is not None:
                what = "input limit" if ev.kind == "limit" else ev.kind.replace("_", " ")
                line += (f", {ev.distance:.3g} {u} from the {what} position ({ev.where}) at "
                         f"{ev.input:.6g} {u}")
            out.append(line)
        if self.singular_samples:
            out.append(f"{self.singular_samples} sample(s) at singular positions: left out "
                       "of the peaks above (their values are limits along the branch, or "
                       "empty where unbounded or not determined: column singular)")
        return out


def _turning_points(lk, kin, roots, value, samples, turn):
    """The limit positions ``roots`` (SI, :func:`analytic.refine.turning_points`) with
    the series' value there: ``[(input SI, value)]``, the value (``value(kinematics)``)
    on the samples' own turn when ``turn`` (360 for an unwrapped angle in deg)."""
    if not roots:
        return []
    vals = np.asarray(value(unit_rate_kinematics(lk, np.array(roots))), float)
    if turn:  # on the turn of the nearest sample
        near = np.asarray(samples)[np.argmin(np.abs(np.asarray(kin.value)[None, :]
                                                    - np.array(roots)[:, None]), axis=1)]
        vals = vals + turn * np.round((near - vals) / turn)
    return list(zip(roots, vals.tolist(), strict=True))


def _spans(x: np.ndarray, y: np.ndarray, period: float, turns=(), conv=None):
    """Input spans of the increasing and decreasing strokes of a periodic ``y(x)``
    with one maximum and one minimum per period: between its two limit positions
    ``turns`` (:func:`_turning_points`), else by parabolic interpolation of the
    samples."""
    if len(turns) == 2:
        (x0, y0), (x1, y1) = turns
        xmax, xmin = (x0, x1) if y0 > y1 else (x1, x0)
        inc = float(conv(xmax) - conv(xmin)) % period
        return inc, period - inc

    def vertex(i):
        n = len(y)
        a, b, c = y[(i - 1) % n], y[i], y[(i + 1) % n]
        den = a - 2 * b + c
        h = x[1] - x[0]
        return x[i] + (0.5 * h * (a - c) / den if den != 0 else 0.0)
    xmax, xmin = vertex(int(np.argmax(y))), vertex(int(np.argmin(y)))
    inc = (xmax - xmin) % period
    return inc, period - inc


def _extremes(y: np.ndarray, periodic: bool, turns=()) -> tuple[float, float]:
    """Least and greatest value of ``y``: of the samples and of the limit positions
    ``turns`` located between them (:func:`_turning_points`); without those, an
    interior extreme (or any, when periodic) is the vertex of the parabola through it
    and its neighbours, which removes the sampling error (O(h^2)) of the plain min/max."""
    if len(turns):
        v = [t[1] for t in turns]
        return min(float(np.min(y)), min(v)), max(float(np.max(y)), max(v))
    out = []
    n = len(y)
    for i, sgn in ((int(np.argmin(y)), -1), (int(np.argmax(y)), 1)):
        v = float(y[i])
        if n >= 3 and (periodic or 0 < i < n - 1):
            a, b, c = y[(i - 1) % n], y[i], y[(i + 1) % n]
            den = a - 2 * b + c
            if den * sgn < 0:
                v = float(b - (a - c) ** 2 / (8 * den))
        out.append(v)
    return out[0], out[1]


def _reversals(y: np.ndarray) -> int:
    d = np.diff(np.concatenate([y, y[:1]]))
    peak = np.max(np.abs(d)) if len(d) else 0.0
    s = np.sign(d[np.abs(d) > 1e-9 * peak]) if peak > 0 else np.array([])
    return int(np.sum(s != np.roll(s, 1))) if len(s) else 0


def summarise(result, nearest_event=None) -> Summary:
    """The :class:`Summary` of a :class:`analytic.sweep.SweepResult`; ``nearest_event``
    (:func:`analytic.sweep.nearest_event`) names the event beside the peak effort."""
    kin = result.kinematics
    lk = kin.linkage
    mech, topo = lk.mech, lk.topo
    rev = lk.driver_is_revolute
    unit = "deg" if rev else "m"
    conv = np.degrees if rev else (lambda v: np.asarray(v, float))
    x = conv(kin.value)
    summ = Summary(unit, float(x[0]) if len(x) else math.nan,
                   float(x[-1]) if len(x) else math.nan, result.full_cycle,
                   float(conv(mech.driver.value)),
                   constant_speed=bool(np.all(kin.acceleration == 0)))
    if not len(x):
        return summ
    period = 360.0 if rev else None
    periodic = result.full_cycle and rev
    for j in topo.prismatic:
        if j == topo.driver_joint:
            continue
        jn = topo.joint_names[j]
        s = kin.slider(jn)[0]
        turns = _turning_points(lk, kin, turning_points(lk, kin, periodic)[("slider", jn)],
                                lambda k, jn=jn: k.slider(jn)[0], s, None)
        lo, hi = _extremes(s, periodic, turns)
        st = dict(kind="slider", name=jn, low=lo, high=hi, travel=hi - lo)
        if periodic and _reversals(s) == 2:
            inc, dec = _spans(x, s, period, turns, conv)
            slow, quick, dirn = (inc, dec, "increasing") if inc >= dec else \
                (dec, inc, "decreasing")
            st.update(slow_span=slow, quick_span=quick, slow_direction=f"(s {dirn})")
        summ.strokes.append(Stroke(**st))
    dj = mech.driver_joint
    driven = {dj.body_a, dj.body_b} - {mech.ground}
    for jt in mech.joints:
        if not _is_revolute(jt) or mech.ground not in jt.bodies or jt.name == dj.name:
            continue
        body = jt.body_b if jt.body_a == mech.ground else jt.body_a
        if body in driven:
            continue
        b = topo.body_names.index(body)
        th = np.degrees(kin.theta[:, b])
        net = th[-1] + (th[-1] - th[-2]) - th[0] if len(th) > 1 else 0.0
        if periodic and abs(net) > 180.0:
            summ.strokes.append(Stroke("rocker", body, math.nan, math.nan, math.nan, True))
            continue
        turns = _turning_points(lk, kin, turning_points(lk, kin, periodic)[
            ("group", int(topo.group_of[b]))], lambda k, b=b: np.degrees(k.theta[:, b]),
            th, 360.0)
        lo, hi = _extremes(th, periodic, turns)
        st = dict(kind="rocker", name=body, low=lo, high=hi, travel=hi - lo)
        if periodic and _reversals(th) == 2:
            inc, dec = _spans(x, th, period, turns, conv)
            slow, quick, dirn = (inc, dec, "ccw") if inc >= dec else (dec, inc, "cw")
            st.update(slow_span=slow, quick_span=quick, slow_direction=f"({dirn})")
        summ.strokes.append(Stroke(**st))
    for jn, least, at, _ in least_transmission(lk, kin, periodic):
        summ.transmission.append(TransmissionSummary(jn, least, float(conv(at)),
                                                     90.0 - least))
    # forces at a singular sample are not determined by the motion: left out
    regular = kin.condition < SINGULAR_CONDITION
    summ.singular_samples = int(np.sum(~regular))
    if result.forces is not None and regular.any():
        frc = result.forces
        eff = np.where(regular, np.abs(frc.effort), np.nan)
        if np.any(np.isfinite(eff)):
            i = int(np.nanargmax(eff))
            summ.effort_name = "drive torque" if rev else "drive force"
            summ.effort_unit = "N m" if rev else "N"
            summ.peak_effort, summ.peak_effort_at = float(eff[i]), float(x[i])
            got = _located_peak(lk, kin, eff, i, periodic)
            if got is not None and got[1] >= summ.peak_effort:
                summ.peak_effort, summ.peak_effort_at = got[1], float(conv(got[0]))
            if nearest_event is not None:
                ev = nearest_event(result, float(x[i]),
                                   kinds=("singular", "change_point", "input_limit"))
                span = 360.0 if periodic else float(np.ptp(x))
                if ev is not None and ev.distance <= NEAR_EVENT * span:
                    summ.peak_event = ev
        summ.power_balance = float(np.max(np.abs(frc.power_residual[regular]))
                                   / _power_scale(kin, frc, regular))
    return summ


def _located_peak(lk, kin, eff: np.ndarray, i: int, periodic: bool):
    """The peak drive effort next to the largest sample ``i``, located on the solver
    between its neighbours (:func:`analytic.refine.peak`) at the sweep's own input rates:
    ``(input SI, |effort|)``; ``None`` at an end of a limited sweep or beside a singular
    sample (where the largest sample is what the table shows)."""
    n = len(eff)
    if n < 3 or not (periodic or 0 < i < n - 1) or \
            not (np.isfinite(eff[i - 1]) and np.isfinite(eff[(i + 1) % n])):
        return None
    x = np.asarray(kin.value, float)
    period = (x[-1] - x[0]) + (x[1] - x[0]) if periodic else 0.0
    lo = x[i - 1] if i > 0 else x[-1] - period
    hi = x[i + 1] if i < n - 1 else x[0] + period
    vel, acc = float(kin.velocity[i]), float(kin.acceleration[i])

    def value(t):
        k = lk.kinematics(t, np.full(len(t), vel), np.full(len(t), acc), on_singular="flag")
        return np.abs(lk.forces(k).effort)
    got = peak(lk, lo, hi, value)
    if got is not None and periodic:
        got = (float(x[0] + np.mod(got[0] - x[0], period)), got[1])
    return got


def _power_scale(kin, frc, regular) -> float:
    """The size of the terms the power balance sums: the peak over the regular samples
    of each body's m |v| |a| + I |omega alpha| summed, or of the drive and load powers when
    larger.  (A linkage whose kinetic energy is constant, such as a parallelogram at
    constant speed, has a net rate of zero: relative to that, rounding looks large.)"""
    terms = kin.series(_power_terms)[regular]  # a streamed sweep's: block by block
    peak = max(float(np.max(terms)) if terms.size else 0.0,
               float(np.max(np.abs(frc.power[regular]))),
               float(np.max(np.abs(frc.load_power[regular]))))
    return peak if peak > 0 else 1e-300


def _power_terms(kin) -> np.ndarray:
    """Per sample, each moving body's m |v| |a| + I |omega alpha| summed (W)."""
    mech = kin.linkage.mech
    terms = np.zeros(kin.n)
    for b, body in enumerate(mech.bodies):
        if b == kin.linkage.topo.ground or not body.mass:
            continue
        _, v, a = kin.com_c(b)
        terms += body.mass * (np.abs(v) * np.abs(a))
        terms += (body.inertia or 0.0) * np.abs(kin.omega[:, b] * kin.alpha[:, b])
    return terms


def _is_revolute(jt) -> bool:
    return isinstance(jt, Revolute)
