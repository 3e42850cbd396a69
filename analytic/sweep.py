"""Full-cycle sweeps, singular and limit positions, Grashof classification.

Columns of :attr:`SweepResult.frame` (SI unless the name says otherwise)
-------------------------------------------------------------------------
``input``                     driver value: deg (revolute) or m (prismatic)
``input_velocity``            rad/s or m/s
``input_acceleration``        rad/s^2 or m/s^2
``<body>.angle_deg``          body angle, deg, wrapped to (-180, 180]
``<body>.omega``              rad/s, ccw positive
``<body>.alpha``              rad/s^2, ccw positive
``<body>.<point>.x|y``        m, world frame
``<body>.<point>.vx|vy``      m/s
``<body>.<point>.ax|ay``      m/s^2
``<joint>.s|v|a``             prismatic displacement m, velocity m/s, acceleration m/s^2
``<joint>.fx|fy``             joint force by body_a (the guide) on body_b (the slider), N
``<joint>.normal|moment``     prismatic normal force N and couple N m on the slider
``drive.torque`` or ``drive.force``   drive effort on body_b / the slider, N m or N
``drive.power``               W, positive when the driver does work
``power_residual``            drive power - (dKE/dt - load power), W (rounding level)
``jacobian_condition``        condition number of the loop Jacobian in the unknowns
                              (sliders in mechanism sizes: the same at any scale)
``jacobian_det``              its determinant normalised by its column norms, [-1, 1]
``singular``                  0 regular; at a singular sample (analytic.singular) 1: every
                              value is its limit along the branch; 2: as 1, but joint
                              forces unbounded there (empty cells); 3: not passed through,
                              rates and forces not determined (empty cells)
``transmission_deg.<joint>``  transmission angle at a dyad's inner joint, deg
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .errors import AssemblyError, LinkageError
from .kin_result import Kinematics
from .kinetostatics import Forces
from .mechanism import Prismatic, Revolute
from .positions import input_span, size_of
from .singular import LIMIT, REGULAR, UNBOUNDED_FORCES, UNDETERMINED
from .summary import summarise
from .sweep_facts import ArrayFacts
from .tolerances import SINGULAR_CONDITION


@dataclass
class SweepResult:
    """A sweep over input values: arrays, table, events and classification."""

    kinematics: Kinematics
    forces: Forces | None
    frame: pd.DataFrame
    events: pd.DataFrame
    full_cycle: bool
    feasible: list[tuple[float, float]]
    grashof: str | None = None
    notes: list[str] = field(default_factory=list)
    #: change points passed (:class:`analytic.branches.Crossing`), in the order met
    crossings: list = field(default_factory=list)
    #: engineering summary (:class:`analytic.summary.Summary`)
    summary: object = None

    def nearest_event(self, at: float, kinds=None):
        """See :func:`nearest_event`."""
        return nearest_event(self, at, kinds)


def exact_degrees(values: np.ndarray, lo: float = -math.inf, hi: float = math.inf,
                  snap: bool | None = None) -> np.ndarray:
    """Input angles (rad) moved to values whose degree value, printed in full, reads back
    as the same angle (``radians(degrees(v)) == v``; :func:`input_degrees` prints it):
    to the nearest 1e-10 deg where the grid is coarse enough that this cannot reorder
    it or leave ``[lo, hi]`` (``359``, not ``358.99999999999994``), else by a few ulps.
    A row of the table is then solved at exactly the input it prints.  ``snap``: whether
    the grid is that coarse (default: decided from ``values``; a block of a longer grid
    passes the whole grid's answer, :meth:`InputGrid.snaps`).  Each value's result
    depends on that answer and on the value alone."""
    v = np.asarray(values, float).copy()
    if not len(v):
        return v
    d = np.degrees(v)
    r = np.radians(np.round(d, 10))
    if snap is None:
        snap = len(v) < 2 or np.min(np.abs(np.diff(d))) > 1e-8
    if snap:
        v = np.where((r >= lo) & (r <= hi), r, v)
    for _ in range(8):  # radians(degrees(.)) reaches a fixed point in 1-2 steps
        w = np.radians(np.degrees(v))
        ok = (w == v) | (np.radians(np.round(np.degrees(v), 10)) == v)
        if ok.all():
            break
        v = np.where(ok, v, w)
    return v


@dataclass(frozen=True)
class InputGrid:
    """A sweep's input values (SI), made block by block without holding them all:
    ``a + 2 pi i / n`` over a full turn (``kind="turn"``, ``a`` the start) or
    ``np.linspace(a, b, n)`` (``"linspace"``), moved to printable angles by
    :func:`exact_degrees` within ``[lo, hi]`` when ``exact`` (a revolute input).
    :meth:`block` gives the same numbers as :meth:`values` (``tests/analytic/
    test_sweep.py`` checks it), 8 bytes per value of the block only."""

    kind: str
    a: float
    b: float
    n: int
    exact: bool
    lo: float = -math.inf
    hi: float = math.inf

    def _raw(self, i: int, k: int) -> np.ndarray:
        if self.kind == "turn":
            return self.a + 2 * math.pi * np.arange(i, k) / self.n
        # np.linspace's own arithmetic (numpy >= 1.20): i * step + start, the end exact
        y = np.arange(i, k, dtype=float)
        y *= (self.b - self.a) / (self.n - 1)
        y += self.a
        if k == self.n and k > i and self.n > 1:
            y[-1] = self.b
        return y

    @functools.cached_property
    def snaps(self) -> bool:
        """:func:`exact_degrees`'s decision for the whole grid (the least spacing in
        degrees above 1e-8), block by block with the step across each boundary."""
        if self.n < 2:
            return True
        least, prev = math.inf, None
        for i in range(0, self.n, GRID_BLOCK):
            d = np.degrees(self._raw(i, min(self.n, i + GRID_BLOCK)))
            if prev is not None:
                d = np.concatenate(([prev], d))
            least = min(least, float(np.min(np.abs(np.diff(d)))) if len(d) > 1 else least)
            prev = d[-1]
        return least > 1e-8

    def block(self, i: int, k: int) -> np.ndarray:
        """Values ``i`` to ``k - 1``."""
        x = self._raw(i, k)
        return exact_degrees(x, self.lo, self.hi, self.snaps) if self.exact else x

    def at(self, idx) -> np.ndarray:
        """The values at the indices ``idx`` (negative from the end)."""
        idx = np.asarray(idx, int) % self.n
        return np.array([self.block(int(j), int(j) + 1)[0] for j in idx])

    def values(self) -> np.ndarray:
        """Every value at once (as the in-memory sweep takes them)."""
        if self.kind == "turn":
            x = self.a + 2 * math.pi * np.arange(self.n) / self.n
        else:
            x = np.linspace(self.a, self.b, self.n)
        return exact_degrees(x, self.lo, self.hi) if self.exact else x


#: values per block where :class:`InputGrid` scans its spacing
GRID_BLOCK = 1 << 16


def input_degrees(values: np.ndarray) -> np.ndarray:
    """The input column of a revolute driver, deg: ``values`` (rad) in degrees, to 1e-10
    deg where that reads back as the same angle, else in full (17 digits)."""
    v = np.asarray(values, float)
    r = np.round(np.degrees(v), 10)
    return np.where(np.radians(r) == v, r, np.degrees(v))


def input_values(linkage, points: int, start: float | None = None
                 ) -> tuple[np.ndarray, bool, list]:
    """The sweep's input values: a full turn from ``start`` (default the reference
    angle) when the crank can turn fully, else the feasible interval of the assembled
    branch holding the reference value (on the Newton path, the traced branch between
    its limit positions), so the sweep ends near the limit positions."""
    grid, full, feas = input_grid(linkage, points, start)
    return grid.values(), full, feas


def input_grid(linkage, points: int, start: float | None = None
               ) -> tuple[InputGrid, bool, list]:
    """:func:`input_values` as an :class:`InputGrid` (values made block by block)."""
    v0 = linkage.mech.driver.value
    feas = linkage.feasible_ranges()
    rev = linkage.driver_is_revolute
    if rev and len(feas) == 1 and feas[0][1] - feas[0][0] >= 2 * math.pi * (1 - 1e-9):
        a = v0 if start is None else start
        return InputGrid("turn", a, a + 2 * math.pi, points, True), True, feas
    for lo, hi in feas:
        if lo <= v0 <= hi:
            # stay a hair inside the limit positions, where the Jacobian is singular:
            # 1e-6 of the range, more where that is still singular (a range of 1e-7 rad
            # of a linkage with a link 1e-6 of the others)
            for frac in (1e-6, 1e-5, 1e-4, 1e-3):
                pad = frac * (hi - lo)
                ends = InputGrid("linspace", lo + pad, hi - pad, points, False).at([0, -1])
                try:
                    kin = linkage.kinematics(ends, on_singular="flag", limits=False)
                except LinkageError:
                    continue
                if np.all(kin.condition < SINGULAR_CONDITION):
                    break
            # printable inputs (revolute), still half the pad inside
            return InputGrid("linspace", lo + pad, hi - pad, points, rev, lo + pad / 2,
                             hi - pad / 2), False, feas
    raise AssemblyError(f"mechanism {linkage.mech.name!r}: the reference input is not in a "
                        f"feasible range {feas}", v0, feas)


def range_values(linkage, input_range: tuple[float, float], points: int
                 ) -> np.ndarray:
    """``points`` input values (SI) from ``input_range[0]`` to ``input_range[1]``."""
    return range_grid(linkage, input_range, points).values()


def range_grid(linkage, input_range: tuple[float, float], points: int
               ) -> InputGrid:
    """:func:`range_values` as an :class:`InputGrid`."""
    return InputGrid("linspace", float(input_range[0]), float(input_range[1]), points,
                     linkage.driver_is_revolute)


def find_events(linkage, kin: Kinematics, periodic: bool,
                feasible: list | None = None, crossings: list | None = None,
                facts=None) -> pd.DataFrame:
    """Singular (dead-centre / change-point) and limit positions over a sweep.

    * ``singular``: the loop Jacobian's determinant changes sign (located on the solver
      by regula falsi, :func:`analytic.refine.sign_changes`) or its condition number
      exceeds :data:`SINGULAR_CONDITION` at a sample: the output cannot be driven
      there (dead centre) or the linkage may switch branch (change point);
    * ``change_point``: a singular position where two branches cross, passed on the
      branch named in the detail (``crossings``, see :mod:`analytic.branches`);
    * ``limit``: a body's angular velocity or a slider's velocity changes sign: the
      extreme (toggle) positions of rockers and the dead centres of sliders, located
      on the solver between the samples (:mod:`analytic.refine`, to 1e-12 rad or of
      the size); and, for
      a sweep of a limited range (``feasible``), the input's own limit positions at
      the ends of the range, beyond which the loops cannot close (located to 1e-9);
    * ``min_transmission``: the least transmission angle of each dyad (folded into
      0..90 deg) and its largest deviation from 90 deg, located on the solver
      (:func:`analytic.refine.least_transmission`).

    Inputs are in the frame's units (deg or m); a full cycle's are wrapped into one
    turn from its first value.  ``facts``: what is read of the series
    (:mod:`analytic.sweep_facts`; default :class:`ArrayFacts` of ``kin``'s arrays, a
    streamed sweep's gathered block by block).
    """
    rev = linkage.driver_is_revolute
    F = ArrayFacts(linkage, kin, None) if facts is None else facts
    conv = np.degrees if rev else (lambda v: v)
    rows = _singular_rows(F, periodic, conv)
    rows += _turning_rows(linkage, F, periodic, conv)
    if not periodic and feasible is not None and F.n:
        rows += _input_limit_rows(linkage, F, feasible, conv)
    rows += _change_point_rows(linkage, F, crossings, conv)
    for jn, least, at, raw in F.transmission(periodic):
        rows.append(("min_transmission", jn, float(conv(at)),
                     f"least transmission angle {least:.3f} deg (raw {raw:.3f} deg; "
                     f"largest deviation from 90 deg: {90.0 - least:.3f} deg)"))
    return _event_frame(rows, F, periodic and rev)


def _singular_rows(F, periodic: bool, conv) -> list[tuple]:
    """Events where the loop Jacobian's determinant changes sign or its condition
    number is past :data:`SINGULAR_CONDITION` at a sample."""
    rows = []
    for v in F.det_roots(periodic):
        rows.append(("singular", "loop Jacobian", float(conv(v)),
                     "determinant changes sign: dead centre or change point"))
    for xi, ci in F.singular():
        rows.append(("singular", "loop Jacobian", float(conv(xi)),
                     f"condition number {ci:.3g}"))
    return rows


def _turning_rows(linkage, F, periodic: bool, conv) -> list[tuple]:
    """Limit positions of the outputs: a rotation group's angular velocity or a
    slider's velocity changes sign (the driver's own bodies and joint excepted)."""
    # rates at a singular sample are not determined by the input: no limits from them
    # (analytic.refine.turning_points: the regular samples bracket, the solver locates)
    topo = linkage.topo
    turns = F.turns(periodic)
    rows = []
    djb = {linkage.mech.driver_joint.body_a, linkage.mech.driver_joint.body_b}
    for b, name in enumerate(topo.body_names):
        if topo.group_of[b] < 0 or name in djb:
            continue
        # one row per rotation group (bodies of a group share omega)
        if any(topo.group_of[o] == topo.group_of[b] for o in range(b)):
            continue
        for v in turns[("group", int(topo.group_of[b]))]:
            rows.append(("limit", name, float(conv(v)), "omega = 0 (extreme angle)"))
    for j in topo.prismatic:
        jn = topo.joint_names[j]
        if j == topo.driver_joint:
            continue
        for v in turns[("slider", jn)]:
            rows.append(("limit", jn, float(conv(v)), "slider velocity = 0 (dead centre)"))
    return rows


def _input_limit_rows(linkage, F, feasible: list, conv) -> list[tuple]:
    """The input's own limit positions at the ends of a limited sweep's range."""
    rows = []
    for lo, hi in feasible:
        for end in (lo, hi):
            if F.distance(end) <= 1e-3 * max(hi - lo, 1e-300) and \
                    is_input_limit(linkage, end):
                rows.append(("limit", linkage.mech.driver.joint, float(conv(end)),
                             "input limit position: the loops cannot close beyond it "
                             "on this branch (the drive effort grows without bound "
                             "toward it)"))
    return rows


def _change_point_rows(linkage, F, crossings: list | None, conv) -> list[tuple]:
    """The change points within the sweep: the branch crossings of the dyad plan
    (``crossings``) and those a traced (Newton-path) branch passes."""
    rev = linkage.driver_is_revolute
    n = F.n
    fmt = (lambda v: f"{math.degrees(v):.6g} deg") if rev else (lambda v: f"{v:.6g} m")
    eps = 1e-9 * (1.0 if rev else size_of(linkage.topo))  # an event at the end belongs to it
    xmin, xmax = F.bounds if n else (math.nan, math.nan)
    rows = []
    for c in crossings or []:
        if n and xmin - eps <= c.value <= xmax + eps:
            mode = parallelogram_mode(linkage, c.value + math.copysign(
                1e-3, c.value - linkage.mech.driver.value))
            rows.append(("change_point", ", ".join(c.joints), float(conv(c.value)),
                         c.describe(fmt).split(": ", 1)[1]
                         + (f"; beyond it the linkage is {mode}" if mode else "")))
    trace = linkage.positions.trace
    if trace is not None and n:
        for xc in trace.crossings:
            shifts = [0.0] if trace.period is None else \
                trace.period * np.arange(np.floor((xmin - xc) / trace.period),
                                         np.ceil((xmax - xc) / trace.period) + 1)
            for v in xc + np.asarray(shifts):
                if xmin - eps <= v <= xmax + eps:
                    rows.append(("change_point", "loop Jacobian", float(conv(v)),
                                 "the assembled branch passes this singular position "
                                 "continuously (continuation with a tangent predictor: "
                                 "the branch whose velocity is continuous)"))
    return rows


def _event_frame(rows: list[tuple], F, wrap: bool) -> pd.DataFrame:
    """The events table sorted by input; ``wrap``: a full turn's inputs wrapped into one
    turn from the sweep's first value (deg)."""
    ev = pd.DataFrame(rows, columns=["kind", "where", "input", "detail"])
    if wrap and len(ev) and F.n:
        a = float(np.degrees(F.x_at([0])[0]))
        ev["input"] = a + np.mod(ev["input"].to_numpy() - a, 360.0)
    if len(ev):
        ev["input"] = np.round(ev["input"].to_numpy(dtype=float), 9) + 0.0
    return ev.sort_values("input", kind="stable").reset_index(drop=True) if len(ev) else ev


def is_input_limit(linkage, end: float) -> bool:
    """Whether the end ``end`` (SI) of a feasible range is a limit position of the input
    (the loops cannot close beyond it), not merely the end of the interval searched
    (:func:`analytic.positions.input_span`: one turn, or +-2 sizes for a slider)."""
    trace = linkage.positions.trace
    if trace is not None:
        tol = 1e-9 * (1.0 if linkage.driver_is_revolute else size_of(linkage.topo))
        return any(abs(end - v) <= tol for v in trace.limits)
    lo, hi = input_span(linkage.topo)
    tol = 1e-9 * (hi - lo)
    if linkage.driver_is_revolute:  # a seam of the searched turn is no limit
        r = (end - lo) % (2 * math.pi)
        return tol < r < 2 * math.pi - tol
    return lo + tol < end < hi - tol


@dataclass(frozen=True)
class NearestEvent:
    """The event nearest an input value: its row and the distance (frame units)."""

    kind: str
    where: str
    input: float
    detail: str
    distance: float


def nearest_event(result: SweepResult, at: float, kinds=None) -> NearestEvent | None:
    """The singular position, change point or limit position nearest the input ``at``.

    ``at`` is in the sweep frame's input units (deg for a revolute input, m for a
    prismatic one), on any turn: for a full cycle the distance is taken modulo 360
    deg.  ``kinds`` defaults to ``("singular", "change_point", "limit")``; the
    pseudo-kind ``"input_limit"`` selects the ``limit`` rows of the input itself (the
    ends of a limited range), without the outputs' extreme angles, where nothing is
    singular.  Returns ``None`` when the sweep has no such event.  Use it to say whether
    a large error sits next to a position where the mechanism itself is singular:
    ``kinds=("singular", "change_point", "input_limit")``.
    """
    kinds = ("singular", "change_point", "limit") if kinds is None else tuple(kinds)
    e = result.events
    keep = e.kind.isin(kinds)
    if "input_limit" in kinds:
        keep |= (e.kind == "limit") & (e["where"] == result.kinematics.linkage.mech.driver.joint)
    ev = e[keep]
    if not len(ev):
        return None
    d = np.abs(ev["input"].to_numpy() - float(at))
    if result.full_cycle and result.kinematics.linkage.driver_is_revolute:
        d = np.mod(d, 360.0)
        d = np.minimum(d, 360.0 - d)
    k = int(np.argmin(d))
    r = ev.iloc[k]
    return NearestEvent(str(r["kind"]), str(r["where"]), float(r["input"]), str(r["detail"]),
                        float(d[k]))


def parallelogram_mode(linkage, value: float) -> str | None:
    """For a four-bar whose opposite links are equal (a change-point linkage of the
    parallelogram family): ``"a parallelogram"`` when, at the input ``value`` on the
    continued branch, each link is parallel to its opposite, ``"an anti-parallelogram"``
    otherwise; ``None`` for any other mechanism."""
    mech, topo = linkage.mech, linkage.topo
    if len(mech.bodies) != 4 or len(mech.joints) != 4 or \
            not all(isinstance(j, Revolute) for j in mech.joints):
        return None
    ends = {}
    for b, name in enumerate(topo.body_names):
        js = [k for k, j in enumerate(mech.joints) if name in j.bodies]
        ends[name] = (js, float(np.hypot(*(topo.attach(js[0], b) - topo.attach(js[1], b)))))
    names = list(ends)
    opposite = {n: next(m for m in names if m != n and not set(ends[n][0]) & set(ends[m][0]))
                for n in names}
    size = max(L for _, L in ends.values())
    if any(abs(ends[n][1] - ends[opposite[n]][1]) > 1e-9 * size for n in names):
        return None
    try:
        kin = linkage.kinematics_along(np.array([value]))
    except LinkageError:
        return None

    def direction(n):  # unit vector between the body's two joints, world frame
        b = topo.body_names.index(n)
        j0, j1 = ends[n][0]
        d = (topo.attach(j1, b) - topo.attach(j0, b)) / ends[n][1]
        return complex(*d) * kin.E[0, b]

    g = mech.ground
    crank = next(n for n in names if n != g and set(ends[n][0]) & set(ends[g][0]))
    c1, c2 = direction(crank), direction(opposite[crank])
    parallel = abs((c1.conjugate() * c2).imag) < 1e-6
    return "a parallelogram" if parallel else "an anti-parallelogram"


def grashof(linkage) -> str | None:
    """Grashof classification of a four-bar (four bodies, four revolute joints).

    Returns e.g. ``"Grashof crank-rocker"``, ``"Grashof double-crank"``,
    ``"Grashof double-rocker"``, ``"change point"`` or ``"non-Grashof triple-rocker"``;
    ``None`` for other mechanisms.  The driven link is the *input*; "crank" names
    the links that turn fully.
    """
    mech, topo = linkage.mech, linkage.topo
    if len(mech.bodies) != 4 or len(mech.joints) != 4 or \
            not all(isinstance(j, Revolute) for j in mech.joints):
        return None
    lengths = {}
    for b, name in enumerate(topo.body_names):
        js = [k for k, j in enumerate(mech.joints) if name in j.bodies]
        p, q = (topo.attach(js[0], b), topo.attach(js[1], b))
        lengths[name] = float(np.hypot(*(p - q)))
    L = sorted(lengths.values())
    s, p_, q_, l_ = L
    shortest = min(lengths, key=lengths.get)
    tol = 1e-9 * l_
    if abs((s + l_) - (p_ + q_)) <= tol:
        return "change point"
    if s + l_ > p_ + q_:
        return "non-Grashof triple-rocker"
    if shortest == mech.ground:
        return "Grashof double-crank"
    ground_links = [j.body_b if j.body_a == mech.ground else j.body_a
                    for j in mech.joints if mech.ground in j.bodies]
    if shortest in ground_links:
        dj = mech.driver_joint
        driven = dj.body_b if dj.body_a == mech.ground else dj.body_a
        role = "crank-rocker" if shortest == driven else "rocker-crank (input rocks)"
        return f"Grashof {role}"
    return "Grashof double-rocker"


def _wrap_deg(a: np.ndarray) -> np.ndarray:
    d = np.degrees(a)
    return 180.0 - np.mod(180.0 - d, 360.0)


def to_frame(linkage, kin: Kinematics, frc: Forces | None) -> pd.DataFrame:
    """The sweep table (columns in the module docstring)."""
    mech, topo = linkage.mech, linkage.topo
    rev = linkage.driver_is_revolute
    cols: dict[str, np.ndarray] = {
        # the value solved at: radians(input) is the row's input (exact_degrees)
        "input": input_degrees(kin.value) if rev else kin.value,
        "input_velocity": kin.velocity, "input_acceleration": kin.acceleration}
    for b, body in enumerate(mech.bodies):
        if b == topo.ground:
            continue
        cols[f"{body.name}.angle_deg"] = _wrap_deg(kin.theta[:, b])
        cols[f"{body.name}.omega"] = kin.omega[:, b]
        cols[f"{body.name}.alpha"] = kin.alpha[:, b]
        for pn in body.points:
            p, v, a = kin.point(body.name, pn)
            for k, arr in (("x", p[:, 0]), ("y", p[:, 1]), ("vx", v[:, 0]), ("vy", v[:, 1]),
                           ("ax", a[:, 0]), ("ay", a[:, 1])):
                cols[f"{body.name}.{pn}.{k}"] = arr
    for j in topo.prismatic:
        jn = topo.joint_names[j]
        s, v, a = kin.slider(jn)
        cols[f"{jn}.s"], cols[f"{jn}.v"], cols[f"{jn}.a"] = s, v, a
    if frc is not None:
        for jt in mech.joints:
            F = frc.joint_force[jt.name]
            cols[f"{jt.name}.fx"], cols[f"{jt.name}.fy"] = F[:, 0], F[:, 1]
            if isinstance(jt, Prismatic):
                cols[f"{jt.name}.normal"] = frc.normal[jt.name]
                cols[f"{jt.name}.moment"] = frc.moment[jt.name]
        cols["drive.torque" if rev else "drive.force"] = frc.effort
        cols["drive.power"] = frc.power
        cols["power_residual"] = frc.power_residual
    cols["jacobian_condition"] = kin.condition
    cols["jacobian_det"] = kin.determinant
    cols["singular"] = singular_status(kin, frc)
    for jn, tr in kin.transmission.items():
        cols[f"transmission_deg.{jn}"] = tr
    return pd.DataFrame(cols)


def singular_status(kin: Kinematics, frc: Forces | None) -> np.ndarray:
    """The ``singular`` column: 0 regular; at a singular sample 1 (every value is its
    limit along the branch), 2 (as 1, but some joint forces are unbounded there: empty
    cells), 3 (not passed through: rates and forces not determined, empty cells); see
    :mod:`analytic.singular`."""
    st = getattr(frc, "at_singular", None) if frc is not None else None
    if st is None:
        st = getattr(kin, "at_singular", None)
    if st is None:  # not processed (a path without the limits): say undetermined
        st = np.where(kin.condition < SINGULAR_CONDITION, REGULAR, UNDETERMINED)
    return np.asarray(st, np.int8)


def _unbounded(frc: Forces, i: int) -> list[str]:
    """The joints whose force (or couple) is NaN at sample ``i``."""
    out = [k for k, F in frc.joint_force.items() if not np.all(np.isfinite(F[i]))]
    return out + [k for k, m in frc.moment.items()
                  if not np.isfinite(m[i]) and k not in out]


def singular_records(kin: Kinematics, frc: Forces | None) -> list[tuple[float, int, list]]:
    """The singular samples of ``kin`` (condition number at least
    :data:`SINGULAR_CONDITION`): ``(input SI, singular status, joints whose force is
    unbounded there)`` each, in order (a streamed sweep gathers them block by block)."""
    singular = np.flatnonzero(~(kin.condition < SINGULAR_CONDITION))
    if not singular.size:
        return []
    st = singular_status(kin, frc)
    return [(float(kin.value[i]), int(st[i]),
             _unbounded(frc, i) if frc is not None and st[i] == UNBOUNDED_FORCES else [])
            for i in singular]


def singular_notes(linkage, records: list, forces: bool) -> list[str]:
    """What the sweep writes at its singular samples (:func:`singular_records`), one
    note per kind of sample."""
    if not records:
        return []
    conv = math.degrees if linkage.driver_is_revolute else float
    unit = "deg" if linkage.driver_is_revolute else "m"

    def at(rows):
        return ", ".join(f"{conv(r[0]):.6g}" for r in rows[:6]) + \
            (", ..." if len(rows) > 6 else "") + f" {unit}"
    notes = []
    lim = [r for r in records if r[1] == LIMIT]
    if lim:
        notes.append(f"{len(lim)} sample(s) at singular positions the linkage passes through "
                     f"({at(lim)}): every value there is its limit along the branch "
                     "(column singular = 1)")
    unb = [r for r in records if r[1] == UNBOUNDED_FORCES]
    if unb:
        joints = sorted({j for r in unb for j in r[2]})
        notes.append(f"{len(unb)} sample(s) at change points ({at(unb)}): the rates, drive "
                     "effort and power are their limits along the branch; the force at "
                     f"joint(s) {', '.join(joints)} is unbounded there (the links are "
                     "collinear and the load has a component in the motion they leave free: "
                     "the force grows as 1/distance, with opposite signs either side), its "
                     "cells left empty (column singular = 2)")
    und = [r for r in records if r[1] == UNDETERMINED]
    if und:
        notes.append(f"{len(und)} sample(s) at singular positions the linkage does not pass "
                     f"through smoothly ({at(und)}: a dead centre, a limit position, or a "
                     "change point where the branch followed has a kink, as when the "
                     "reference value sits on one): the rates"
                     + (" and forces" if forces else "") + " are not determined by "
                     "the input there, cells left empty (column singular = 3)")
    return notes


def unbounded_events(linkage, records: list, events: pd.DataFrame) -> pd.DataFrame:
    """``unbounded_force`` events at the samples whose joint forces have no limit
    (:func:`singular_records`)."""
    conv = math.degrees if linkage.driver_is_revolute else float
    rows = [("unbounded_force", ", ".join(r[2]), float(conv(r[0])),
             "joint force unbounded at this change point (grows as 1/distance, opposite "
             "signs either side); drive effort and power finite (their limits)")
            for r in records if r[1] == UNBOUNDED_FORCES]
    if not rows:
        return events
    ev = pd.concat([events, pd.DataFrame(rows, columns=["kind", "where", "input", "detail"])],
                   ignore_index=True) if len(events) else \
        pd.DataFrame(rows, columns=["kind", "where", "input", "detail"])
    return ev.sort_values("input", kind="stable").reset_index(drop=True)


def sweep(linkage, points: int = 360, forces: bool | None = None,
          values: np.ndarray | None = None, start: float | None = None,
          velocity: float | None = None, input_range: tuple[float, float] | None = None
          ) -> SweepResult:
    """Solve the mechanism over a full cycle (or its feasible input range).

    Parameters
    ----------
    points
        Number of input values (a full turn excludes its end, which equals its start).
    forces
        Compute kinetostatics; default: when every moving body has a mass.
    values
        Explicit input values (SI) instead of the automatic range.
    start
        Input value (SI) where a full-cycle sweep starts (default the reference
        value; ``0.0`` gives the 0-360 deg table engineers expect).
    velocity
        Input velocity (rad/s or m/s) instead of the description's.
    input_range
        ``(lo, hi)`` (SI): sweep ``points`` values from ``lo`` to ``hi`` inclusive.

    The driver's velocity and acceleration are the description's at every point
    (a constant-speed crank by default).  Singular points do not raise here:
    they are flagged in ``events`` and in ``jacobian_condition``.  The branch is the
    assembled one, continued through change points as the linkage moves (listed in
    ``crossings`` and as ``change_point`` events).
    """
    if points < 2:
        raise ValueError(f"a sweep needs at least 2 points, got {points}")
    full, auto = False, values is None and input_range is None
    if values is not None:
        values, feas = np.asarray(values, float), linkage.feasible_ranges()
    elif input_range is not None:
        values, feas = range_values(linkage, input_range, points), linkage.feasible_ranges()
    else:
        values, full, feas = input_values(linkage, points, start)
    kin = linkage.kinematics(values, velocity, on_singular="flag")
    if forces is None:
        forces = linkage.mech.has_mass
    # at singular samples the solver gives the limits along the branch, or NaN where
    # there is none (analytic.singular); the notes, the events and the rows say which
    frc = linkage.forces(kin) if forces else None
    records = singular_records(kin, frc)
    notes = singular_notes(linkage, records, frc is not None)
    if auto and not full and linkage.driver_is_revolute:
        notes.append("the input link cannot turn fully; the sweep covers the feasible range "
                     + ", ".join(f"[{math.degrees(a):.4f}, {math.degrees(b):.4f}] deg"
                                 for a, b in feas) + " on the assembled branch")
    crossings = linkage.branch_crossings(float(np.min(values)), float(np.max(values))) \
        if len(values) else []
    undecided = [c for c in crossings if c.rule.startswith("held: ")]
    if undecided:
        notes.append(f"{len(undecided)} change point(s) where continuity of velocity cannot "
                     "decide the branch: dyad signs held (Linkage(branch_rule='switch') or "
                     "xval sweep --branch-rule switch takes the other)")
    events = find_events(linkage, kin, full, None if full else feas, crossings)
    events = unbounded_events(linkage, records, events)
    res = SweepResult(kin, frc, to_frame(linkage, kin, frc), events,
                      full, feas, grashof(linkage), notes, crossings)
    res.summary = summarise(res, nearest_event)
    return res
