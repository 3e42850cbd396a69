"""The free trajectory: a typed object sampled at any time, and its events.

:class:`FreeTrajectory` holds the integrated segments (:mod:`.integrate`) and answers,
at any times in ``[0, duration]``, with :class:`FreeSamples`: every joint's coordinate,
rate and acceleration (whatever coordinate was integrated), the solver's
:class:`analytic.Kinematics` (bodies, points, sliders) and kinetostatics (joint
reactions, with the springs, dampers and motors applied as loads), the motors' efforts
and power, and the energies.  Events: coordinate switches, singular positions crossed
(the loop Jacobian's normalised determinant changes sign), limit positions of a joint
(its coefficient changes sign: the joint reverses while the motion goes on), and
turning points of the motion (the integrated rate changes sign).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import brentq as _brentq

from ..kinetostatics import solve_forces
from ..mechanism import Load, Revolute
from ..singular import singular_samples
from .clock import SAMPLE_CHUNK
from .dynamics import coefficients, element_forces, terms, unwrap_to
from .integrate import Segment


@dataclass(frozen=True)
class Event:
    """Something met along the run: ``kind`` is ``switch``, ``singular``, ``limit``,
    ``turn`` or ``stop`` (released at rest where nothing moves it, e.g. a dead centre:
    the motion stops); ``t`` s; ``joint`` the joint concerned; ``detail`` in words."""

    t: float
    kind: str
    joint: str
    detail: str


@dataclass
class FreeSamples:
    """The trajectory at N times (SI, world frame; see :mod:`analytic.mechanism`).

    ``x, xd, xdd`` ``(N, J)``: joint coordinates (rad: ``theta_b - theta_a``
    continuous over turns; m: slider displacement) and their rates, in the order of
    ``joints``.  ``kinematics`` and ``forces``: the solver's, one per segment met (use
    :meth:`body_angles`, :meth:`point`).  ``kinetic, potential`` J; ``work_motor``,
    ``work_loads``, ``dissipated`` J since t = 0; ``energy_residual`` J: ``kinetic +
    potential - E0 - work_motor - work_loads + dissipated`` (zero for the exact motion).
    ``motor_effort`` dict joint -> (N,) N m or N; ``motor_power`` (N,) W.
    ``reactions`` dict joint -> (N, 2) N (by body_a on body_b); ``drive_residual``
    (N,): the effort the kinetostatics still asks at the integrated joint once every
    force element is applied (zero for the exact motion; N m or N).
    """

    t: np.ndarray
    joints: list[str]
    coordinate: list[str]
    x: np.ndarray
    xd: np.ndarray
    xdd: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    work_motor: np.ndarray
    work_loads: np.ndarray
    dissipated: np.ndarray
    energy_residual: np.ndarray
    motor_effort: dict[str, np.ndarray]
    motor_power: np.ndarray
    reactions: dict[str, np.ndarray] = field(default_factory=dict)
    drive_residual: np.ndarray | None = None
    points: dict[str, np.ndarray] = field(default_factory=dict)

    def joint(self, name: str) -> np.ndarray:
        """``(N, 3)``: a joint's coordinate, rate and acceleration."""
        k = self.joints.index(name)
        return np.stack([self.x[:, k], self.xd[:, k], self.xdd[:, k]], axis=1)


class FreeTrajectory:
    """A released linkage's motion, to the integrator's tolerance, at any time."""

    def __init__(self, mech, segments: list[Segment], switches, rtol: float, method: str):
        self.mech = mech
        self.segments = segments
        self.switches = switches
        self.rtol = rtol
        self.method = method
        self.duration = segments[-1].t1
        self.joints = [j.name for j in mech.joints]
        self._rev = np.array([isinstance(j, Revolute) for j in mech.joints])
        s0 = self.at(np.array([0.0]), forces=False)
        self.e0 = float(s0.kinetic[0] + s0.potential[0])

    @property
    def nfev(self) -> int:
        return sum(s.nfev for s in self.segments)

    @property
    def switch_defect(self) -> float | None:
        """The self-check of the coordinate switches (:mod:`.switch_check`): the largest
        difference, at the first step after a switch, between the new coordinate's
        solution and the old coordinate integrated on past the switch (coordinate: rad
        or fraction of the size; rate: fraction of its scale).  Of the order of the
        integration's tolerance when no state is lost at a switch; None without a
        checked switch."""
        got = [s.check for s in self.segments if s.check is not None]
        return max(got) if got else None

    @property
    def switches_checked(self) -> int:
        """How many of the switches :attr:`switch_defect` covers."""
        return sum(s.check is not None for s in self.segments)

    def _segment_of(self, t: np.ndarray) -> np.ndarray:
        starts = np.array([s.t0 for s in self.segments])
        return np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(starts) - 1)

    def state(self, t) -> tuple[np.ndarray, np.ndarray]:
        """``(N, 5)`` integrated states and the segment index of each time."""
        t = np.atleast_1d(np.asarray(t, float))
        si = self._segment_of(t)
        y = np.empty((len(t), 5))
        for k in np.unique(si):
            m = si == k
            y[m] = self.segments[k].sol(t[m]).T
        return y, si

    def at(self, times, forces: bool = True, clock=None) -> FreeSamples:
        """The trajectory at ``times`` (s, within [0, duration]), reconstructed in chunks
        of :data:`~.clock.SAMPLE_CHUNK` samples (the working arrays stay that size);
        ``clock``: a :class:`~.clock.WallClock` checked before each chunk
        (:class:`~.clock.WallLimitError` past its limit, with the samples done)."""
        t = np.atleast_1d(np.asarray(times, float))
        if t.size and (t.min() < 0 or t.max() > self.duration * (1 + 1e-12)):
            raise ValueError(f"times must lie in [0, {self.duration:g}] s")
        N, J = len(t), len(self.joints)
        y, si = np.empty((N, 5)), np.empty(N, int)
        out = {k: np.empty((N, J)) for k in ("x", "xd", "xdd")}
        body = {k: np.empty((N, len(self.mech.bodies))) for k in ("theta", "omega", "alpha")}
        en = {k: np.empty(N) for k in ("kinetic", "potential", "motor_power")}
        reactions = {j: np.full((N, 2), np.nan) for j in self.joints} if forces else {}
        drive = np.full(N, np.nan)
        efforts = {mo.joint: np.empty(N) for mo in self._motors()}
        for c0 in range(0, N, SAMPLE_CHUNK):
            if clock is not None:
                clock.check_samples(c0, N)
            c = slice(c0, min(N, c0 + SAMPLE_CHUNK))
            y[c], si[c] = self.state(t[c])
            for k in np.unique(si[c]):
                idx = c0 + np.flatnonzero(si[c] == k)
                self._fill(self.segments[k], idx, t[idx], y[idx], out, body, en, efforts,
                           reactions if forces else None, drive)
        return FreeSamples(
            t, self.joints, [self.segments[k].joint for k in si], out["x"], out["xd"],
            out["xdd"], body["theta"], body["omega"], body["alpha"], en["kinetic"],
            en["potential"], y[:, 2], y[:, 3], y[:, 4],
            en["kinetic"] + en["potential"] - getattr(self, "e0", 0.0) - y[:, 2] - y[:, 3]
            + y[:, 4], efforts, en["motor_power"], reactions if forces else {},
            drive if forces else None)

    def _motors(self):
        return self.mech.motion.motors if self.mech.motion else ()

    def _fill(self, seg: Segment, idx, t, y, out, body, en, efforts, reactions, drive):
        lk = seg.lk
        co = coefficients(lk, y[:, 0])
        # revolute angles: whole turns from the step nearest each time
        near = np.clip(np.searchsorted(seg.ts, t), 0, len(seg.ts) - 1)
        x = unwrap_to(co.x, seg.xs[near], self._rev)
        qd = y[:, 1]
        tm = terms(lk, co, x, qd, t)
        qdd = (tm.Q - tm.C * qd ** 2) / tm.M
        out["x"][idx] = x
        out["xd"][idx] = co.x_q * qd[:, None]
        out["xdd"][idx] = co.x_q * qdd[:, None] + co.x_qq * (qd ** 2)[:, None]
        # the rates are linear in q' and q'': scaled from the unit-rate coefficients (the
        # same numbers as the solver at (q', q''), and for a parallelogram chain its exact
        # identities instead of the solver's near-singular rates at a change point)
        u = co.kin
        body["theta"][idx] = continued_angles(lk, u.theta, x)
        body["omega"][idx] = u.omega * qd[:, None]
        body["alpha"][idx] = u.omega * qdd[:, None] + u.alpha * (qd ** 2)[:, None]
        en["kinetic"][idx], en["potential"][idx] = tm.kinetic, tm.potential
        en["motor_power"][idx] = tm.motor_power
        for mo in self._motors():
            efforts[mo.joint][idx] = [mo.at(ti) for ti in t]
        if reactions is None:
            return
        self._forces(lk, co, x, y[:, 0], qd, qdd, t, idx, reactions, drive)

    def _forces(self, lk, co, x, q, qd, qdd, t, idx, reactions, drive):
        """The solver's kinetostatics at a segment's samples, all at once, with the
        force elements applied as loads.  The reactions and the drive effort are linear
        in the loads at a given motion: each element load's share is the solver's answer
        with one load of the scale of that element's added, less the answer without it,
        times its value at each sample (rounding: ~1e-16 of the larger of the two).  A
        sample at a singular position (its forces are limits along the branch, decided
        per output) is solved with its own loads (:meth:`_forces_at`)."""
        kin = lk.kinematics(q, qd, qdd, on_singular="flag")
        base = solve_forces(lk, kin)
        rx = {j: f.copy() for j, f in base.joint_force.items()}
        eff = base.effort.copy()
        loads = element_forces(lk, co, x, qd, t) if lk.mech.motion else []
        for ld in loads:
            for unit, val in ((1.0, ld.force.real), (1j, ld.force.imag), (None, ld.torque)):
                scale = float(np.max(np.abs(val))) if len(val) else 0.0
                if not scale > 0:
                    continue
                extra = (Load(ld.body, ld.point, (0.0, 0.0), scale) if unit is None else
                         Load(ld.body, ld.point, ((unit * scale).real, (unit * scale).imag)))
                one = solve_forces(_Shadow(lk, replace(lk.mech, loads=lk.mech.loads
                                                       + (extra,))), kin)
                share = val / scale
                for j, f in one.joint_force.items():
                    rx[j] += share[:, None] * (f - base.joint_force[j])
                eff += share * (one.effort - base.effort)
        for j, f in rx.items():
            reactions[j][idx] = f
        drive[idx] = eff
        if loads:
            for i in singular_samples(kin):
                self._forces_at(lk, x, int(i), idx[i], q[i], qd[i], t[i], reactions, drive)

    def _forces_at(self, lk, x, i, n, qi, qdi, ti, reactions, drive):
        """The solver's kinetostatics at one sample, force elements applied as loads."""
        co1 = coefficients(lk, float(qi))
        loads = element_forces(lk, co1, x[i:i + 1], float(qdi), float(ti))
        tm = terms(lk, co1, x[i:i + 1], qdi, ti)
        qdd = float((tm.Q[0] - tm.C[0] * qdi ** 2) / tm.M[0])
        kin = lk.kinematics(np.array([qi]), float(qdi), qdd, on_singular="flag")
        shadow = _Shadow(lk, replace(lk.mech, loads=lk.mech.loads + tuple(
            Load(ld.body, ld.point, (float(ld.force[0].real), float(ld.force[0].imag)),
                 float(ld.torque[0])) for ld in loads)))
        frc = solve_forces(shadow, kin)
        for j, f in frc.joint_force.items():
            reactions[j][n] = f[0]
        drive[n] = frc.effort[0]


class _Shadow:
    """A linkage seen by :func:`analytic.kinetostatics.solve_forces` with other loads."""

    def __init__(self, lk, mech):
        self.mech, self.topo, self._lk = mech, lk.topo, lk

    def __getattr__(self, name):
        return getattr(self._lk, name)


#: A run whose integrated rate stays below this (rad/s, or m/s per mechanism size)
#: from a release at rest has stopped: nothing moves it (rounding-level forces at an
#: unstable equilibrium move it by less than this over the run).
STOP_RATE = 1e-12


def _stopped(traj: FreeTrajectory) -> Event | None:
    """A ``stop`` event at t = 0 when the linkage, released at rest, never moves: an
    equilibrium, or a dead centre no force moves it from (then the released joint's
    coordinate is singular there and the run starts in another one)."""
    from ..mechanism import mechanism_size
    size = mechanism_size(traj.mech.bodies) or 1.0
    peak = 0.0
    for seg in traj.segments:
        rev = isinstance(seg.lk.mech.driver_joint, Revolute)
        peak = max(peak, float(np.max(np.abs(seg.sol(seg.ts)[1]))) / (1.0 if rev else size))
    if not peak <= STOP_RATE:
        return None
    fm = traj.mech.motion
    where = (f"at a dead centre of joint {fm.joint!r} (its coordinate is singular there)"
             if traj.switches and traj.switches[0][0] == 0.0 else "in equilibrium")
    if traj.segments[0].held:
        where += (" (its generalized force is rounding noise: held there, as an unstable "
                  "equilibrium would amplify that noise into a fall)")
    return Event(0.0, "stop", fm.joint, f"released at rest {where}: the motion stops "
                 f"(rates stay below {STOP_RATE:g} over {traj.duration:g} s)")


def brentq(f, a: float, b: float, clock=None, xtol: float = 1e-14) -> float:
    """A root of ``f`` bracketed in ``[a, b]``: SciPy's brentq without its exception
    when the iteration cap is met (a function that is rounding noise near its root, as
    a loop determinant that touches zero: the bracket is then already below the
    noise's width, and its best point is the answer).  The wall clock is checked first."""
    if clock is not None:
        clock.check()
    return float(_brentq(f, a, b, xtol=xtol, maxiter=200, disp=False))


def _change_points(seg: Segment, q: np.ndarray, clock=None) -> list[tuple[float, str]]:
    """The solver's change points (:meth:`analytic.Linkage.branch_crossings`: where
    dyads meet, including those where the loop Jacobian's determinant touches zero
    without changing sign, as the N four-bar's 40 windows at once) crossed by the
    integrated coordinate between the segment's steps: ``[(t, detail)]``."""
    out = []
    ts = seg.ts
    lo, hi = float(np.min(q)), float(np.max(q))
    for c in seg.lk.branch_crossings(lo, hi):
        v = c.value
        for i in np.flatnonzero((q[:-1] - v) * (q[1:] - v) <= 0):
            if q[i] == q[i + 1]:
                continue
            tc = brentq(lambda t, v=v: float(seg.sol(t)[0]) - v, ts[i], ts[i + 1],
                        clock)
            if not any(abs(tc - t) < 1e-12 for t, _ in out):
                out.append((tc, f"change point at {seg.joint!r} = {v:.12g} crossed "
                                f"({len(c.joints)} dyads meet: {', '.join(c.joints[:4])}"
                                f"{', ...' if len(c.joints) > 4 else ''})"))
    return out


def find_events(traj: FreeTrajectory, clock=None) -> list[Event]:
    """Switches, singular crossings, joint limit positions and turning points, located
    to ~1e-13 s by root-finding on the dense output between the integrator's steps
    (``clock``: a :class:`~.clock.WallClock` checked at each segment and root)."""
    events = [Event(t, "switch", b, f"integrated coordinate {a!r} -> {b!r}")
              for t, a, b in traj.switches]
    names = traj.joints
    stop = _stopped(traj)
    if stop is not None:
        return events + [stop]
    for seg in traj.segments:
        ts = seg.ts
        if clock is not None:
            clock.check()
        if len(ts) < 2:
            continue
        q = seg.sol(ts)
        co = coefficients(seg.lk, q[0])
        det = co.kin.determinant
        k_int = names.index(seg.joint)

        def g_det(t, seg=seg):
            return float(coefficients(seg.lk, seg.sol(t)[0]).kin.determinant[0])

        crossed = _change_points(seg, q[0], clock)
        for tc, detail in crossed:
            events.append(Event(tc, "singular", seg.joint, detail))
        for i in np.flatnonzero(np.sign(det[:-1]) * np.sign(det[1:]) < 0):
            if any(ts[i] <= t <= ts[i + 1] for t, _ in crossed):
                # the same change point, listed with its dyads (at a stretched pass the
                # determinant touches zero flatly: its root is only good to ~1e-7 s)
                continue
            tc = brentq(g_det, ts[i], ts[i + 1], clock)
            events.append(Event(tc, "singular", seg.joint, "loop Jacobian singular "
                                "(dead centre or change point) crossed"))
        for j in range(len(names)):
            if j == k_int:
                continue
            c = co.x_q[:, j]
            for i in np.flatnonzero(np.sign(c[:-1]) * np.sign(c[1:]) < 0):
                def g(t, seg=seg, j=j):
                    return float(coefficients(seg.lk, seg.sol(t)[0]).x_q[0, j])
                tc = brentq(g, ts[i], ts[i + 1], clock)
                events.append(Event(tc, "limit", names[j], f"joint {names[j]!r} reverses "
                                    "(limit position of its coordinate)"))
        qd = q[1]
        for i in np.flatnonzero(np.sign(qd[:-1]) * np.sign(qd[1:]) < 0):
            tc = brentq(lambda t, seg=seg: float(seg.sol(t)[1]), ts[i], ts[i + 1], clock)
            events.append(Event(tc, "turn", seg.joint, "the motion reverses (rate of "
                                f"{seg.joint!r} is zero)"))
    return sorted(events, key=lambda e: e.t)


def continued_angles(lk, theta: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Body angles ``theta (N, B)`` (rad; a closed form gives them within one turn)
    moved by whole turns onto the angles the unwrapped joint coordinates ``x (N, J)``
    give along the spanning tree from the ground: continuous over the run and across
    coordinate switches (a coupler joint's segment places its bodies by a closed form
    since issue 34; its Newton trace had continued them)."""
    topo = lk.topo
    out = np.array(theta, float)
    tree = np.zeros_like(out)
    two_pi = 2.0 * np.pi
    for b in topo.order[1:]:
        p, j = topo.parent[b]
        jt = lk.mech.joints[j]
        if isinstance(jt, Revolute):
            rel = x[:, j] if topo.body_names[b] == jt.body_b else -x[:, j]
        else:  # a slider keeps its angle to the guide
            rel = theta[:, b] - theta[:, p]
        tree[:, b] = tree[:, p] + rel
        out[:, b] += np.round((tree[:, b] - out[:, b]) / two_pi) * two_pi
    return out

