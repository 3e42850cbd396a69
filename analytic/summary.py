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
import sys
from dataclasses import dataclass, field

import numpy as np

from .refine import peak, unit_rate_kinematics
from .sweep_facts import ArrayFacts
from .tolerances import LIMIT_BISECTION

#: An extremum's position (the peak drive effort, the least transmission angle) is
#: determined only to ~sqrt(2 eps) rad of its curvature: the value is flat there, so a
#: rounding of eps in the value moves the located maximum by sqrt(2 eps) = 2.1e-8 rad
#: (1.2e-6 deg).  Closer to 0 than that, a position is shown as 0 (a peak located at
#: 1e-26 deg, or at 360 deg - 6e-7 deg on a full turn, is at 0 deg).
EXTREMUM_RESOLUTION = math.sqrt(2 * sys.float_info.epsilon)

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
    #: terms (the peak of each body's m |v| |a| + I |omega alpha|, or of the drive and load powers)
    power_balance: float | None = None

    def shown_input(self, x: float, resolution: float = LIMIT_BISECTION) -> float:
        """An input position ``x`` (frame units) as the text shows it, known to
        ``resolution`` rad (a limit or singular position located by bisection:
        :data:`analytic.tolerances.LIMIT_BISECTION`; an extremum:
        :data:`EXTREMUM_RESOLUTION`): a revolute input of a full cycle wrapped to the
        table's range ``[first, first + 360)`` deg, and a position within the resolution
        of 0 (or of ``first + 360``) shown as 0 (or ``first``): a 1e-26 deg is round-off,
        not a position."""
        if self.unit != "deg" or x is None or not math.isfinite(x):
            return x
        res = math.degrees(resolution)
        if self.full_cycle and math.isfinite(self.first):
            x = self.first + (x - self.first) % 360.0
            if x - self.first >= 360.0 - res or f"{x:.6g}" == f"{self.first + 360.0:.6g}":
                x = self.first  # the same position on the circle, in the table's range
        return 0.0 if abs(x) < res else float(x)

    def input_text(self, x: float, resolution: float = LIMIT_BISECTION) -> str:
        """:meth:`shown_input` to 6 significant digits, with the unit."""
        return f"{self.shown_input(x, resolution):.6g} {self.unit}"

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
                       f"{self.input_text(t.at, EXTREMUM_RESOLUTION)}, largest deviation "
                       "from 90 deg "
                       f"{t.largest_deviation_deg:.3f} deg")
        if self.peak_effort is not None:
            line = (f"peak |{self.effort_name}| {self.peak_effort:.6g} {self.effort_unit} at "
                    f"{self.input_text(self.peak_effort_at, EXTREMUM_RESOLUTION)}")
            ev = self.peak_event
            if ev is not None:
                what = "input limit" if ev.kind == "limit" else ev.kind.replace("_", " ")
                line += (f", {ev.distance:.3g} {u} from the {what} position ({ev.where}) at "
                         f"{self.input_text(ev.input)}")
            out.append(line)
        if self.singular_samples:
            out.append(f"{self.singular_samples} sample(s) at singular positions: left out "
                       "of the peaks above (their values are limits along the branch, or "
                       "empty where unbounded or not determined: column singular)")
        return out


def _turning_points(lk, F, key, roots, value, turn):
    """The limit positions ``roots`` (SI, :func:`analytic.refine.turning_points`) with
    the series' value there: ``[(input SI, value)]``, the value (``value(kinematics)``)
    on the samples' own turn when ``turn`` (360 for an unwrapped angle in deg): the
    turn of the sample nearest the root (``F.near``)."""
    if not roots:
        return []
    vals = np.asarray(value(unit_rate_kinematics(lk, np.array(roots))), float)
    if turn:  # on the turn of the nearest sample
        near = F.near(key, roots)
        vals = vals + turn * np.round((near - vals) / turn)
    return list(zip(roots, vals.tolist(), strict=True))


def _vertex_x(F, st, i: int, conv) -> float:
    """The input (frame units) of the vertex of the parabola through sample ``i`` of
    the series ``st`` (:class:`analytic.sweep_facts.SeriesStats`) and its neighbours."""
    (lo_i, *lo), (_, *hi) = st.low, st.high
    a, b, c = lo if i == lo_i else hi
    den = a - 2 * b + c
    x0, x1, xi = (float(v) for v in conv(F.x_at([0, 1, i])))
    h = x1 - x0
    return xi + (0.5 * h * (a - c) / den if den != 0 else 0.0)


def _spans(F, st, period: float, turns=(), conv=None):
    """Input spans of the increasing and decreasing strokes of a periodic series
    ``st`` (:class:`analytic.sweep_facts.SeriesStats`) with one maximum and one minimum
    per period: between its two limit positions ``turns`` (:func:`_turning_points`),
    else by parabolic interpolation of the samples."""
    if len(turns) == 2:
        (x0, y0), (x1, y1) = turns
        xmax, xmin = (x0, x1) if y0 > y1 else (x1, x0)
        inc = float(conv(xmax) - conv(xmin)) % period
        return inc, period - inc
    xmax, xmin = _vertex_x(F, st, st.high[0], conv), _vertex_x(F, st, st.low[0], conv)
    inc = (xmax - xmin) % period
    return inc, period - inc


def _extremes(st, periodic: bool, turns=()) -> tuple[float, float]:
    """Least and greatest value of the series ``st``
    (:class:`analytic.sweep_facts.SeriesStats`): of the samples and of the limit
    positions ``turns`` located between them (:func:`_turning_points`); without those,
    an interior extreme (or any, when periodic) is the vertex of the parabola through
    it and its neighbours, which removes the sampling error (O(h^2)) of the plain
    min/max."""
    if len(turns):
        v = [t[1] for t in turns]
        return min(st.low[1], min(v)), max(st.high[1], max(v))
    out = []
    n = st.n
    for (i, b, a, c), sgn in ((st.low, -1), (st.high, 1)):
        v = float(b)
        if n >= 3 and (periodic or 0 < i < n - 1):
            den = a - 2 * b + c
            if den * sgn < 0:
                v = float(b - (a - c) ** 2 / (8 * den))
        out.append(v)
    return out[0], out[1]


def summarise(result, nearest_event=None) -> Summary:
    """The :class:`Summary` of a :class:`analytic.sweep.SweepResult`; ``nearest_event``
    (:func:`analytic.sweep.nearest_event`) names the event beside the peak effort.  The
    series are read through ``result.kinematics.facts`` where a streamed sweep gathered
    them (:class:`analytic.sweep_facts.StreamFacts`), else from the arrays."""
    kin = result.kinematics
    lk = kin.linkage
    F = getattr(kin, "facts", None) or ArrayFacts(lk, kin, result.forces)
    mech, topo = lk.mech, lk.topo
    rev = lk.driver_is_revolute
    unit = "deg" if rev else "m"
    conv = np.degrees if rev else (lambda v: np.asarray(v, float))
    n = F.n
    ends = conv(F.x_at([0, -1])) if n else (math.nan, math.nan)
    summ = Summary(unit, float(ends[0]), float(ends[1]), result.full_cycle,
                   float(conv(mech.driver.value)), constant_speed=F.constant_speed)
    if not n:
        return summ
    period = 360.0 if rev else None
    periodic = result.full_cycle and rev
    moving = F.moving()
    turns_all = F.turns(periodic)
    for key, st in moving.items():
        if key[0] == "slider":
            jn = key[1]
            turns = _turning_points(lk, F, key, turns_all[("slider", jn)],
                                    lambda k, jn=jn: k.slider(jn)[0], None)
            lo, hi = _extremes(st, periodic, turns)
            sk = dict(kind="slider", name=jn, low=lo, high=hi, travel=hi - lo)
            if periodic and st.reversals == 2:
                inc, dec = _spans(F, st, period, turns, conv)
                slow, quick, dirn = (inc, dec, "increasing") if inc >= dec else \
                    (dec, inc, "decreasing")
                sk.update(slow_span=slow, quick_span=quick, slow_direction=f"(s {dirn})")
            summ.strokes.append(Stroke(**sk))
    for key, st in moving.items():
        if key[0] != "rocker":
            continue
        b = key[1]
        body = topo.body_names[b]
        net = st.last + (st.last - st.second_last) - st.first if st.n > 1 else 0.0
        if periodic and abs(net) > 180.0:
            summ.strokes.append(Stroke("rocker", body, math.nan, math.nan, math.nan, True))
            continue
        turns = _turning_points(lk, F, key, turns_all[("group", int(topo.group_of[b]))],
                                lambda k, b=b: np.degrees(k.theta[:, b]), 360.0)
        lo, hi = _extremes(st, periodic, turns)
        sk = dict(kind="rocker", name=body, low=lo, high=hi, travel=hi - lo)
        if periodic and st.reversals == 2:
            inc, dec = _spans(F, st, period, turns, conv)
            slow, quick, dirn = (inc, dec, "ccw") if inc >= dec else (dec, inc, "cw")
            sk.update(slow_span=slow, quick_span=quick, slow_direction=f"({dirn})")
        summ.strokes.append(Stroke(**sk))
    for jn, least, at, _ in F.transmission(periodic):
        summ.transmission.append(TransmissionSummary(jn, least, float(conv(at)),
                                                     90.0 - least))
    # forces at a singular sample are not determined by the motion: left out
    summ.singular_samples = len(F.singular())
    eff = F.effort()
    if eff is not None and summ.singular_samples < n:
        _peak_effort(summ, result, F, eff, lk, periodic, conv, nearest_event)
        # relative to the size of the terms the balance sums, not to its net rate (a
        # linkage of constant kinetic energy, a parallelogram at constant speed, has a
        # net rate of 0: relative to that, rounding would look large)
        res, terms, power, load = F.power_peaks(_power_terms)
        peak = max(terms, power, load)
        summ.power_balance = float(res / (peak if peak > 0 else 1e-300))
    return summ


def _peak_effort(summ, result, F, eff, lk, periodic, conv, nearest_event):
    """The peak drive effort over the regular samples, located between them."""
    i, v, prev, nxt = eff.high
    if not math.isfinite(v):
        return
    rev = lk.driver_is_revolute
    summ.effort_name = "drive torque" if rev else "drive force"
    summ.effort_unit = "N m" if rev else "N"
    xi = float(conv(F.x_at([i])[0]))
    summ.peak_effort, summ.peak_effort_at = v, xi
    got = _located_peak(lk, F, eff, periodic)
    if got is not None and got[1] >= summ.peak_effort:
        summ.peak_effort, summ.peak_effort_at = got[1], float(conv(got[0]))
    if nearest_event is not None:
        ev = nearest_event(result, xi, kinds=("singular", "change_point", "input_limit"))
        lo, hi = F.bounds
        span = 360.0 if periodic else float(conv(hi) - conv(lo))
        if ev is not None and ev.distance <= NEAR_EVENT * span:
            summ.peak_event = ev


def _located_peak(lk, F, eff, periodic: bool):
    """The peak drive effort next to the largest sample (``eff.high``), located on the
    solver between its neighbours (:func:`analytic.refine.peak`) at the sweep's own input
    rates: ``(input SI, |effort|)``; ``None`` at an end of a limited sweep or beside a
    singular sample (where the largest sample is what the table shows)."""
    n = eff.n
    i, _, prev, nxt = eff.high
    if n < 3 or not (periodic or 0 < i < n - 1) or \
            not (np.isfinite(prev) and np.isfinite(nxt)):
        return None
    x0, x1, xl = (float(v) for v in F.x_at([0, 1, n - 1]))
    period = (xl - x0) + (x1 - x0) if periodic else 0.0
    lo = float(F.x_at([i - 1])[0]) if i > 0 else xl - period
    hi = float(F.x_at([i + 1])[0]) if i < n - 1 else x0 + period
    vel, acc = F.rates_at(i)

    def value(t):
        k = lk.kinematics(t, np.full(len(t), vel), np.full(len(t), acc), on_singular="flag")
        return np.abs(lk.forces(k).effort)
    got = peak(lk, lo, hi, value)
    if got is not None and periodic:
        got = (float(x0 + np.mod(got[0] - x0, period)), got[1])
    return got


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
