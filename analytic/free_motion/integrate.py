"""Integrating the equation of motion, switching coordinates where one fails.

The state is ``y = (q, q', W_motor, W_loads, D)``: the integrated joint coordinate, its
rate, the work done so far by the motors and by the constant loads, and the energy the
dampers dissipated (J).  SciPy's DOP853 (explicit Runge-Kutta of order 8 with dense
output of order 7) integrates it to :data:`RTOL`.

Coordinate partitioning (Wehage and Haug): the integrated coordinate is the driver
joint of the :class:`analytic.Linkage` the segment uses.  When the rate of another
joint's coordinate, per unit rate of the integrated one (its kinematic coefficient,
angles in rad, displacements in mechanism sizes), exceeds :data:`SWITCH_RATIO`, the
integrated coordinate is near a limit position (its coefficients go to infinity there)
and the joint with the largest coefficient takes over: a new linkage driven at that
joint, assembled on the branch nearest the current pose, continues from the same state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.integrate import solve_ivp

from ..errors import AssemblyError, LinkageError
from ..kinematics import Linkage
from ..mechanism import Assembly, Driver, Revolute, mechanism_size
from ..motion_spec import unreachable
from . import dop853
from .clock import WallClock
from .compiled import fast_eom
from .dynamics import check_masses, coefficients, terms, unwrap_to
from .equilibrium import held
from .stiffness import check_stiffness
from .switch_check import Overlap, event_state

#: Relative tolerance of DOP853 (a few units of double rounding above 1e-16 so that
#: the step-size control stays meaningful; the runs reach ~1e-12, see the tests).
RTOL = 1e-13
#: A coordinate is replaced when another moves this many times faster (per unit of its
#: rate); its coefficients are then still finite (a factor 4 from the best), far from
#: the limit position where they blow up.
SWITCH_RATIO = 4.0
#: Most coordinate switches in one run: a runaway guard (A rocker swinging for 1e4 s
#: with a 0.1 s period switches 4e5 times; more means something is wrong).
MAX_SWITCHES = 1_000_000
#: Agreement of the pose after a switch with the pose before (fraction of the size).
SWITCH_POSE = 1e-9


@dataclass
class Segment:
    """One stretch of the run integrated in one joint's coordinate."""

    lk: Linkage
    joint: str
    t0: float
    t1: float
    sol: object          # scipy OdeSolution: y(t) = (q, q', W_motor, W_loads, D)
    ts: np.ndarray       # the integrator's step times
    xs: np.ndarray       # (len(ts), J) unwrapped joint coordinates at those times
    nfev: int
    #: the switch defect at this segment's start (:mod:`.switch_check`); None for the
    #: first segment, or where the old coordinate could not be continued past the switch
    check: float | None = None
    #: the run held at an equilibrium it was released in at rest (:mod:`.equilibrium`)
    held: bool = False


class NoInertiaError(LinkageError):
    """The generalized inertia of the moving coordinate is zero or negative."""


class _System:
    """The right-hand side of one segment, with the last evaluation cached (the
    switching event asks for the same state as the step)."""

    def __init__(self, lk: Linkage, x_ref: np.ndarray, scale: np.ndarray, clock=None):
        self.lk = lk
        self.clock = clock
        self.rev = np.array([isinstance(j, Revolute) for j in lk.mech.joints])
        self.last = np.array(x_ref, float)
        self.k = [j.name for j in lk.mech.joints].index(lk.mech.driver.joint)
        self.scale = scale / scale[self.k]
        self._key = None
        self.nfev = 0
        self.fast = fast_eom(lk)  # the compiled evaluation, or None (numpy path)

    def coeffs(self, q: float):
        if self._key != q:
            co = coefficients(self.lk, q)
            x = unwrap_to(co.x[0], self.last, self.rev)
            self._key, self._co, self._x = q, co, x
            self.last = x
        return self._co, self._x

    def _fast(self, q: float, qd: float, t: float):
        """``(x, x_q, terms)`` from the compiled path (:mod:`.compiled`), or None."""
        got = self.fast.evaluate(q, qd, t, self.last) if self.fast is not None else None
        if got is not None and self.fast.new:
            self.last = got[0].copy()
        return got

    def __call__(self, t, y):
        self.nfev += 1
        if self.clock is not None:
            self.clock.check(t)
        got = self._fast(float(y[0]), float(y[1]), t)
        if got is not None and math.isfinite(got[2][8]):  # else the numpy path says why
            out = got[2]
            if not out[0] > 0:
                raise NoInertiaError(_no_inertia(self.lk, float(y[0])))
            return [y[1], out[8], out[3], out[4], out[5]]
        try:
            with np.errstate(invalid="ignore", divide="ignore"):  # a stage past the limit
                co, x = self.coeffs(float(y[0]))
        except AssemblyError:
            # a trial stage past the coordinate's limit position (a fast motion steps
            # over the switch's margin): NaN rejects the step and DOP853 retries a fifth
            # as long, until the switch event catches the coordinate before its limit
            return [math.nan] * 5
        tm = terms(self.lk, co, x[None], y[1], t)
        M = float(tm.M[0])
        if not M > 0:
            raise NoInertiaError(_no_inertia(self.lk, float(y[0])))
        qdd = (float(tm.Q[0]) - float(tm.C[0]) * y[1] ** 2) / M
        return [y[1], qdd, float(tm.motor_power[0]), float(tm.load_power[0]),
                float(tm.damper_power[0])]

    def ratios(self, q: float) -> np.ndarray:
        got = self._fast(q, 0.0, 0.0)
        if got is not None:
            return np.abs(got[1]) * self.scale
        co, _ = self.coeffs(q)
        return np.abs(co.x_q[0]) * self.scale

    def switch(self, t, y):
        return float(np.max(self.ratios(float(y[0])))) - SWITCH_RATIO

    switch.terminal = True
    switch.direction = 1.0


def _no_inertia(lk, q: float, t: float | None = None, ratio: float | None = None) -> str:
    """The one line of a zero generalized inertia: the file, the joint and its value (deg
    or m), and the bodies (with mass: they all stand still there; massless)."""
    mech = lk.mech
    rev = isinstance(mech.driver_joint, Revolute)
    shown = f"{math.degrees(q):.6g} deg" if rev else f"{q:.6g} m"
    massive = [b.name for b in mech.moving_bodies if b.mass]
    massless = [b.name for b in mech.moving_bodies if not b.mass]
    how = "is 0" if ratio is None else (f"falls to {ratio:.2g} of its value where this "
                                        "coordinate took over (the integration stalls)")
    return (f"{mech.source + ': ' if mech.source else ''}mechanism {mech.name!r}: no inertia "
            f"in the moving coordinate at joint {mech.driver.joint!r} = {shown}"
            f"{'' if t is None else f' (t = {t:.6g} s)'}: the generalized inertia M(q) {how}; "
            + (f"the bodies with mass {massive} stand still there, massless bodies: "
               f"{massless}" if massive else f"no moving body has mass: {massless}")
            + "; free motion needs inertia all along the motion")


def joint_scale(mech) -> np.ndarray:
    """Per joint: 1 for an angle (rad), 1/size for a displacement (m), so coefficients
    compare in rad per rad."""
    size = mechanism_size(mech.bodies) or 1.0
    return np.array([1.0 if isinstance(j, Revolute) else 1.0 / size for j in mech.joints])


def rebased(mech, joint: str, value: float, kin) -> object:
    """``mech`` driven at ``joint`` from ``value``, assembled on the branch of the pose
    in ``kin`` (sample 0): every point and body angle given as a hint."""
    pts, angs = {}, {}
    for b, body in enumerate(mech.bodies):
        if body.name == mech.ground:
            continue
        angs[body.name] = float(kin.theta[0, b])
        for p in body.points:
            z = kin.point_c(b, p)[0][0]
            pts[f"{body.name}.{p}"] = (float(z.real), float(z.imag))
    return replace(mech, driver=Driver(joint, float(value), 0.0), assembly=Assembly(pts, angs))


def _pose_gap(kin_a, kin_b, size: float) -> float:
    return float(np.max(np.abs(kin_a.zO[0] - kin_b.zO[0]))) / size


def integrate(mech, duration: float | None = None, rtol: float = RTOL,
              method: str = "DOP853", clock: WallClock | None = None,
              ) -> tuple[list[Segment], list[tuple[float, str, str]]]:
    """Integrate ``mech.motion`` over ``duration`` (s; default the description's),
    within ``clock``'s wall-clock limit (:mod:`.clock`).

    Returns the segments and the coordinate switches ``(t, from joint, to joint)``.
    """
    check_masses(mech)
    fm = mech.motion
    T = fm.duration if duration is None else float(duration)
    size = mechanism_size(mech.bodies) or 1.0
    scale = joint_scale(mech)
    m0 = replace(mech, driver=Driver(fm.joint, fm.value, fm.rate))
    try:
        lk = Linkage(m0)
        with np.errstate(invalid="ignore", divide="ignore"):  # a dead centre: checked below
            co = coefficients(lk, fm.value)
    except AssemblyError as e:  # said as the [motion] table, not as a driver
        raise unreachable(mech, e, isinstance(
            next(j for j in mech.joints if j.name == fm.joint), Revolute)) from None
    x0 = co.x[0]
    y = np.array([fm.value, fm.rate, 0.0, 0.0, 0.0])
    t, segs, switches = 0.0, [], []
    closed = _LazyClosed(mech)  # a topology per joint: built only if a switch is needed
    if not np.all(np.isfinite(co.x_q)):  # released at a singular position of its joint
        lk, y, co = _start_elsewhere(lk, co, y, scale, closed, size, switches)
        x0 = co.x[0]
    tm0 = terms(lk, co, x0[None], y[1], 0.0)
    if not tm0.M[0] > 0:
        raise NoInertiaError(_no_inertia(lk, float(y[0])))
    check_stiffness(lk, co, float(tm0.M[0]), T)  # one line, not an endless run
    if held(mech, lk, co, float(tm0.Q[0])):  # at rest in an equilibrium: it stays
        return [_held_segment(lk, y, T, x0)], switches
    e_scale = _energy_scale(mech, tm0, size)
    stops = kinks(fm.motors, T)
    x_ref = x0
    pending = None  # the overlap check of the last switch (:mod:`.switch_check`)
    while True:
        sysm = _System(lk, x_ref, scale, clock)
        if clock is not None:
            clock.switches = len(switches)
        r = sysm.ratios(float(y[0]))
        if np.max(r) > SWITCH_RATIO:  # the coordinate fails here: switch before moving
            pending = None
            lk, y, x_ref = _switch(lk, sysm, y, _pick(r, closed), size, switches, t)
            continue
        qs = (1.0 if isinstance(lk.mech.driver_joint, Revolute) else size)
        co_s, x_s = sysm.coeffs(float(y[0]))
        M_s = float(terms(lk, co_s, x_s[None], y[1], t).M[0])
        rate_scale = max(abs(y[1]), math.sqrt(2 * e_scale / M_s))
        atol = rtol * np.array([qs, rate_scale, e_scale, e_scale, e_scale])
        # a motor table's kinks end a segment: a high-order step across one loses its order
        t_end = next((b for b in stops if b > t), T)
        if method == "DOP853":  # SciPy's steps, taken in compiled code where it can
            sol = dop853.solve(sysm, (t, t_end), y, rtol, atol, SWITCH_RATIO)
        else:
            sol = solve_ivp(sysm, (t, t_end), y, method=method, rtol=rtol, atol=atol,
                            dense_output=True, events=[sysm.switch])
        if sol.status < 0:
            raise _failed(mech, sysm, sol, float(y[0]))
        xs = _unwrapped_track(lk, sol.t, sol.y[0], x_ref)
        segs.append(Segment(lk, lk.mech.driver.joint, t, float(sol.t[-1]), sol.sol, sol.t,
                            xs, sysm.nfev,
                            pending.defect(sysm, sol) if pending is not None else None))
        pending = None
        if sol.status == 0 and t_end >= T:
            return segs, switches
        if sol.status == 0:  # at a table breakpoint: go on in the same coordinate
            t, y, x_ref = t_end, sol.y[:, -1].copy(), xs[-1]
            continue
        if len(switches) >= MAX_SWITCHES:
            raise LinkageError(f"mechanism {mech.name!r}: more than {MAX_SWITCHES} "
                               "coordinate switches")
        # the state at the switch from a step of the integrator, not from its dense
        # output (order 7: 1.5e-10 rad/s off on free01, carried into the new coordinate)
        t = float(sol.t[-1])
        y = event_state(sysm, sol, method, rtol, atol)
        x_ref = xs[-1]
        sysm.last = x_ref
        r = sysm.ratios(float(y[0]))
        pending = Overlap(sysm, float(sol.t[-2]), sol.y[:, -2].copy(), method, rtol, atol)
        lk, y, x_ref = _switch(lk, sysm, y, _pick(r, closed), size, switches, t)


def _held_segment(lk, y, T: float, x0) -> Segment:
    """The whole run at the state ``y`` (:mod:`.equilibrium`)."""
    sol = solve_ivp(lambda t, y: np.zeros_like(y), (0.0, T), y, dense_output=True)
    xs = np.repeat(np.asarray(x0, float)[None], len(sol.t), axis=0)
    return Segment(lk, lk.mech.driver.joint, 0.0, T, sol.sol, sol.t, xs, 0, held=True)


#: A motor table's breakpoint restarts the integration where the effort's slope changes
#: by more than this fraction of the table's effort range per run duration (a sharp
#: kink: a high-order step across it would lose its order).  A dense table sampling a
#: smooth effort changes slope by far less at each row (f'' dt: 4e-3 of it for a sine of
#: three periods in 100,000 rows), and the step-size control resolves such gentle kinks
#: as it resolves any curvature; restarting at each of 100,000 rows took hours.
KINK_REL = 1e-2


def kinks(motors, T: float) -> list[float]:
    """The breakpoints inside ``(0, T)`` where a motor table's slope changes sharply."""
    out = set()
    for mo in motors:
        if len(mo.times) < 3:
            continue
        ts, es = (np.asarray(v, float) for v in (mo.times, mo.efforts))
        slope = np.diff(es) / np.diff(ts)
        jump = np.abs(np.diff(slope))
        span = (float(np.ptp(es)) or abs(float(es[0])) or 1.0) / T
        inside = (ts[1:-1] > 0.0) & (ts[1:-1] < T)
        out.update(ts[1:-1][inside & (jump > KINK_REL * span)].tolist())
    return sorted(out)


def _start_elsewhere(lk, co, y, scale, closed, size, switches):
    """The initial joint's coordinate is singular at the initial pose (a slider at a
    dead centre: the other joints' rates per unit of its rate are infinite).  At rest
    the motion starts in the best-conditioned other joint's coordinate (a switch at
    t = 0); moving, the state is impossible (the joint cannot move there)."""
    mech = lk.mech
    jn0 = mech.driver.joint
    if y[1] != 0.0:
        rev = isinstance(mech.driver_joint, Revolute)
        k, u = (math.degrees(1.0), "deg") if rev else (1.0, "m")
        raise LinkageError(f"{mech.source + ': ' if mech.source else ''}mechanism "
                           f"{mech.name!r}: [motion] joint {jn0!r} = {y[0] * k:.6g} {u} is a "
                           "singular position of its coordinate (a dead centre or a limit "
                           "position: no motion passes there with the joint moving), so its "
                           f"rate must be 0, got {y[1] * k:.6g} {u}/s")
    best = None
    for j, jt in enumerate(mech.joints):
        if jt.name == jn0:
            continue
        try:
            new = Linkage(rebased(mech, jt.name, co.x[0, j], co.kin))
            co2 = coefficients(new, co.x[0, j])
        except LinkageError:
            continue
        r = np.abs(co2.x_q[0]) * scale / scale[j]
        if not np.all(np.isfinite(r)) or _pose_gap(co.kin, co2.kin, size) > SWITCH_POSE:
            continue
        key = (not closed[j], float(np.max(r)))
        if best is None or key < best[0]:
            best = (key, new, co2, jt.name, co.x[0, j])
    if best is None:
        raise LinkageError(f"mechanism {mech.name!r}: no joint's coordinate is regular at the "
                           f"initial pose ({jn0!r} = {y[0]:.6g})")
    _, new, co2, jn, v = best
    switches.append((0.0, jn0, jn))
    return new, np.array([v, 0.0, 0.0, 0.0, 0.0]), co2


def _closed_form_joints(mech) -> np.ndarray:
    """Per joint: whether the solver has a closed form with that joint driven as one
    unknown (a ground joint; else a coupler joint's driven_RRR or Newton's method)."""
    from ..topology import build_topology
    out = []
    for j in mech.joints:
        try:
            topo = build_topology(replace(mech, driver=Driver(j.name, 0.0, 0.0)))
            # a coupler joint's closed form (a driven_RRR plan, no single driven
            # variable) is not preferred: the choice, and so every run's switch
            # sequence, stays as before it existed (issue 34)
            out.append(topo.plan is not None and topo.driven_var is not None)
        except LinkageError:
            out.append(False)
    return np.array(out)


class _LazyClosed:
    """:func:`_closed_form_joints`, computed on first use (it builds one topology per
    joint: 1.7 s for the 121 joints of A02, N = 40, which never switches)."""

    def __init__(self, mech):
        self.mech, self._v = mech, None

    def __getitem__(self, k):
        if self._v is None:
            self._v = _closed_form_joints(self.mech)
        return self._v[k]


def _pick(r: np.ndarray, closed) -> int:
    """The new coordinate: among the joints moving at least half as fast as the fastest
    (relative to it every other coefficient is then at most 2 < SWITCH_RATIO, so it
    does not switch back at once), a closed-form one if any, the fastest of them."""
    ok = r >= 0.5 * np.max(r)
    pref = ok & closed[:]
    pool = pref if pref.any() else ok
    return int(np.argmax(np.where(pool, r, -1.0)))


def _switch(lk, sysm, y, j: int, size, switches, t):
    """Continue from state ``y`` in joint ``j``'s coordinate."""
    co, x = sysm.coeffs(float(y[0]))
    jn = lk.mech.joints[j].name
    new = Linkage(rebased(lk.mech, jn, x[j], co.kin))
    co2 = coefficients(new, x[j])
    gap = _pose_gap(co.kin, co2.kin, size)
    if not gap <= SWITCH_POSE:
        raise LinkageError(f"mechanism {lk.mech.name!r}: switching the coordinate from joint "
                           f"{lk.mech.driver.joint!r} to {jn!r} at t = {t:.6g} s moved the "
                           f"pose by {gap:.3g} of the size (branch lost)")
    switches.append((t, lk.mech.driver.joint, jn))
    y2 = y.copy()
    y2[0], y2[1] = x[j], co.x_q[0, j] * y[1]
    return new, y2, x


def _unwrapped_track(lk, ts, qs, x_ref) -> np.ndarray:
    """Joint coordinates at the step times, each revolute angle continued from the last."""
    co = coefficients(lk, qs)
    rev = np.array([isinstance(j, Revolute) for j in lk.mech.joints])
    out = np.empty_like(co.x)
    last = np.asarray(x_ref, float)
    for i in range(len(ts)):
        last = unwrap_to(co.x[i], last, rev)
        out[i] = last
    return out


def _energy_scale(mech, tm0, size: float) -> float:
    """A scale of the run's energies (J): the initial kinetic energy, gravity's work over
    one size of height, the springs' energy at one size of stretch, a motor's work over
    one radian or size, each load's work over one size."""
    g = math.hypot(*mech.gravity)
    e = float(tm0.kinetic[0]) + sum((b.mass or 0.0) * g * size for b in mech.moving_bodies)
    fm = mech.motion
    for s in fm.springs:
        e += s.stiffness * (size if hasattr(s, "body_a") else 1.0) ** 2
    for mo in fm.motors:
        e += max(abs(mo.effort), *(abs(v) for v in mo.efforts)) if mo.efforts else abs(mo.effort)
    for ld in mech.loads:
        e += math.hypot(*ld.force) * size + abs(ld.torque)
    return e or 1.0


#: Where the integrator gives up with the generalized inertia below this fraction of its
#: value at the segment's start, M(q) meets zero there (it vanishes quadratically: the
#: step size underflows ~1e-6 rad from the zero, where M is ~1e-12 of its scale).
NO_INERTIA = 1e-8


def _failed(mech, sysm, sol, q0: float) -> LinkageError:
    """Why the integrator stopped (one line): a zero of M(q) (:func:`_no_inertia`, the
    bodies named), else the integrator's own message, with the file and the time."""
    t, q, qd = float(sol.t[-1]), float(sol.y[0, -1]), float(sol.y[1, -1])
    m = []
    for v in (q0, q):
        co, x = sysm.coeffs(v)
        m.append(float(terms(sysm.lk, co, x[None], qd, t).M[0]))
    if m[0] > 0 and m[1] < NO_INERTIA * m[0]:
        return NoInertiaError(_no_inertia(sysm.lk, q, t, m[1] / m[0]))
    where = f"{mech.source}: " if mech.source else ""
    return LinkageError(f"{where}mechanism {mech.name!r}: the integration failed at t = "
                        f"{t:.6g} s: {sol.message}")
