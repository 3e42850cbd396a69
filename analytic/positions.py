"""Position analysis: closed-form dyads where possible, Newton-Raphson otherwise.

The closed form follows the structure of the mechanism: the driven link is
placed from the input, then each dyad (two bodies, three joints, the outer two
on known bodies) from the bodies already placed; RRR, RRP, RPR and PRP dyads
have closed-form solutions with a branch sign each.  The signs are chosen once,
at the driver's reference value, as the combination nearest the assembly hints,
and kept over a sweep: the solution then changes continuously with the input and
never jumps branch.  A mechanism that does not decompose into these dyads is
solved by Newton-Raphson on the vector-loop equations, continued from the
previous input value.  Either way the result is checked against the loop
equations (residual below :data:`analytic.tolerances.LOOP_RESIDUAL` times the
mechanism's size).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from .errors import AssemblyError
from .loops import LoopEquations
from .mechanism import Revolute
from .tolerances import LOOP_RESIDUAL, NEWTON_MAX_ITER, TOGGLE_SNAP
from .topology import Topology


def rotate(theta: np.ndarray, c) -> np.ndarray:
    """``R(theta) c`` for a batch of angles ``(N,)`` and one or N vectors -> ``(N, 2)``."""
    c = np.asarray(c, float)
    ct, st = np.cos(theta), np.sin(theta)
    cx, cy = c[..., 0], c[..., 1]
    return np.stack([ct * cx - st * cy, st * cx + ct * cy], axis=-1)


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def size_of(topo: Topology) -> float:
    """A length scale of the mechanism (m): the largest point distance in any body."""
    s = 0.0
    for pts in topo.body_points:
        v = list(pts.values())
        for a, b in itertools.combinations(v, 2):
            s = max(s, float(np.hypot(*(a - b))))
    return s or 1.0


class ClosedForm:
    """Evaluate the dyad plan for a batch of input values and fixed branch signs."""

    def __init__(self, topo: Topology):
        self.topo = topo
        self.mech = topo.mech
        self.plan = topo.plan
        self.n_branch = sum(1 for st in self.plan if st.kind in ("RRR", "RRP", "RPR"))

    def _pt(self, theta, origin, b, c):
        return origin[:, b] + rotate(theta[:, b], c)

    def run(self, values: np.ndarray, signs):
        """Place every body.  Returns ``theta (N, B)``, ``origin (N, B, 2)``,
        ``disc (N, n_steps)`` (the discriminants: negative where the dyad cannot
        close) and ``internal`` (the dyads' data for transmission angles)."""
        topo, joints = self.topo, self.mech.joints
        N, B = len(values), len(topo.body_names)
        theta = np.zeros((N, B))
        origin = np.zeros((N, B, 2))
        discs = []
        trans = []
        si = iter(signs)
        for st in self.plan:
            if st.kind == "driven_revolute":
                (x,), (j,) = st.bodies, st.joints
                k = topo.other(j, x)
                sgn = 1.0 if topo.body_names[x] == joints[j].body_b else -1.0
                theta[:, x] = theta[:, k] + sgn * values
                P = self._pt(theta, origin, k, topo.attach(j, k))
                origin[:, x] = P - rotate(theta[:, x], topo.attach(j, x))
            elif st.kind == "driven_prismatic":
                (x,), (j,) = st.bodies, st.joints
                jt = joints[j]
                k = topo.other(j, x)
                ul = np.array([math.cos(jt.direction), math.sin(jt.direction)])
                if topo.body_names[x] == jt.slider:
                    theta[:, x] = theta[:, k] + jt.angle
                    Q = self._pt(theta, origin, k, topo.attach(j, k))
                    PS = Q + values[:, None] * rotate(theta[:, k], ul)
                    origin[:, x] = PS - rotate(theta[:, x], topo.attach(j, x))
                else:
                    theta[:, x] = theta[:, k] - jt.angle
                    PS = self._pt(theta, origin, k, topo.attach(j, k))
                    Q = PS - values[:, None] * rotate(theta[:, x], ul)
                    origin[:, x] = Q - rotate(theta[:, x], topo.attach(j, x))
            elif st.kind == "RRR":
                x1, x2 = st.bodies
                j1, j2, j3 = st.joints
                k1, k3 = topo.other(j1, x1), topo.other(j3, x2)
                P1 = self._pt(theta, origin, k1, topo.attach(j1, k1))
                P3 = self._pt(theta, origin, k3, topo.attach(j3, k3))
                c1 = topo.attach(j2, x1) - topo.attach(j1, x1)
                c2 = topo.attach(j3, x2) - topo.attach(j2, x2)
                L1s, L2s = c1 @ c1, c2 @ c2
                d = P3 - P1
                D2 = np.einsum("ni,ni->n", d, d)
                D = np.sqrt(D2)
                Dsafe = np.where(D > 0, D, 1.0)
                a = (L1s - L2s + D2) / (2 * Dsafe)
                h2 = L1s - a * a
                disc = np.where(D > 0, h2 / L1s, -1.0)
                discs.append(disc)
                h = np.where(disc > TOGGLE_SNAP, np.sqrt(np.maximum(h2, 0.0)), 0.0)
                sg = next(si)
                perp = np.stack([-d[:, 1], d[:, 0]], axis=1)
                P2 = P1 + (a[:, None] * d + sg * h[:, None] * perp) / Dsafe[:, None]
                e1, e2 = P2 - P1, P3 - P2
                theta[:, x1] = np.arctan2(e1[:, 1], e1[:, 0]) - math.atan2(c1[1], c1[0])
                theta[:, x2] = np.arctan2(e2[:, 1], e2[:, 0]) - math.atan2(c2[1], c2[0])
                origin[:, x1] = P1 - rotate(theta[:, x1], topo.attach(j1, x1))
                origin[:, x2] = P2 - rotate(theta[:, x2], topo.attach(j2, x2))
                trans.append((joints[j2].name, -e1, e2))
            elif st.kind == "RRP":
                x1, x2 = st.bodies
                j1, j2, j3 = st.joints
                jt = joints[j3]
                k1, k3 = topo.other(j1, x1), topo.other(j3, x2)
                P1 = self._pt(theta, origin, k1, topo.attach(j1, k1))
                c1 = topo.attach(j2, x1) - topo.attach(j1, x1)
                L1s = c1 @ c1
                ul = np.array([math.cos(jt.direction), math.sin(jt.direction)])
                slider = topo.body_names[x2] == jt.slider
                if slider:
                    theta[:, x2] = theta[:, k3] + jt.angle
                    u = rotate(theta[:, k3], ul)
                    base = (self._pt(theta, origin, k3, topo.attach(j3, k3))
                            + rotate(theta[:, x2], topo.attach(j2, x2) - topo.attach(j3, x2)))
                    ud = u
                else:
                    theta[:, x2] = theta[:, k3] - jt.angle
                    u = rotate(theta[:, x2], ul)
                    base = (self._pt(theta, origin, k3, topo.attach(j3, k3))
                            + rotate(theta[:, x2], topo.attach(j2, x2) - topo.attach(j3, x2)))
                    ud = -u
                e = base - P1
                eu = np.einsum("ni,ni->n", e, ud)
                h2 = eu * eu - np.einsum("ni,ni->n", e, e) + L1s
                discs.append(h2 / L1s)
                sg = next(si)
                t = -eu + sg * np.where(h2 / L1s > TOGGLE_SNAP, np.sqrt(np.maximum(h2, 0.0)), 0.0)
                P2 = base + t[:, None] * ud
                e1 = P2 - P1
                theta[:, x1] = np.arctan2(e1[:, 1], e1[:, 0]) - math.atan2(c1[1], c1[0])
                origin[:, x1] = P1 - rotate(theta[:, x1], topo.attach(j1, x1))
                origin[:, x2] = P2 - rotate(theta[:, x2], topo.attach(j2, x2))
                n = np.stack([-u[:, 1], u[:, 0]], axis=1)
                trans.append((joints[j2].name, -e1, n))
            elif st.kind == "RPR":
                x1, x2 = st.bodies
                j1, j2, j3 = st.joints
                jt = joints[j2]
                g = x1 if topo.body_names[x1] == jt.guide else x2
                s_ = x2 if g == x1 else x1
                jg, js = (j1, j3) if g == x1 else (j3, j1)
                kg, ks = topo.other(jg, g), topo.other(js, s_)
                PG = self._pt(theta, origin, kg, topo.attach(jg, kg))
                PSr = self._pt(theta, origin, ks, topo.attach(js, ks))
                aG, aS = topo.attach(jg, g), topo.attach(js, s_)
                nl = np.array([-math.sin(jt.direction), math.cos(jt.direction)])
                kconst = nl @ (_rot2(jt.angle) @ (topo.attach(j2, s_) - aS)
                               - (topo.attach(j2, g) - aG))
                d = PSr - PG
                D = np.hypot(d[:, 0], d[:, 1])
                Dsafe = np.where(D > 0, D, 1.0)
                ratio = -kconst / Dsafe
                disc = np.where(D > 0, 1.0 - ratio * ratio, -1.0)
                discs.append(disc)
                sg = next(si)
                psi = np.arctan2(d[:, 1], d[:, 0])
                acos = np.where(disc > TOGGLE_SNAP, np.arccos(np.clip(ratio, -1, 1)),
                                np.where(ratio > 0, 0.0, math.pi))
                th = psi - (jt.direction + math.pi / 2) + sg * acos
                theta[:, g] = th
                theta[:, s_] = th + jt.angle
                origin[:, g] = PG - rotate(th, aG)
                origin[:, s_] = PSr - rotate(theta[:, s_], aS)
                # no transmission angle: the slot's force is always normal to it
            elif st.kind == "PRP":
                x1, x2 = st.bodies
                j1, j2, j3 = st.joints
                bases, dirs = [], []
                for x, j in ((x1, j1), (x2, j3)):
                    jt = joints[j]
                    k = topo.other(j, x)
                    ul = np.array([math.cos(jt.direction), math.sin(jt.direction)])
                    if topo.body_names[x] == jt.slider:
                        theta[:, x] = theta[:, k] + jt.angle
                        u = rotate(theta[:, k], ul)
                    else:
                        theta[:, x] = theta[:, k] - jt.angle
                        u = rotate(theta[:, x], ul)
                    bases.append(self._pt(theta, origin, k, topo.attach(j, k))
                                 + rotate(theta[:, x], topo.attach(j2, x) - topo.attach(j, x)))
                    dirs.append(u)
                cr = _cross(dirs[0], dirs[1])
                discs.append(np.abs(cr) - 1e-12)
                t1 = _cross(bases[1] - bases[0], dirs[1]) / np.where(cr != 0, cr, 1.0)
                P2 = bases[0] + t1[:, None] * dirs[0]
                origin[:, x1] = P2 - rotate(theta[:, x1], topo.attach(j2, x1))
                origin[:, x2] = P2 - rotate(theta[:, x2], topo.attach(j2, x2))
        disc = np.stack(discs, axis=1) if discs else np.ones((N, 0))
        return theta, origin, disc, trans


def _rot2(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


def q_from_poses(topo: Topology, theta: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """Vector-loop unknowns ``q (N, nq)`` from body poses."""
    N = theta.shape[0]
    q = np.zeros((N, topo.nq))
    for b in range(len(topo.body_names)):
        g = topo.group_of[b]
        if g >= 0:
            q[:, g] = theta[:, b] - topo.offset[b]
    for j, i in topo.slider_index.items():
        jt = topo.mech.joints[j]
        gb = topo.body_names.index(jt.guide)
        sb = topo.body_names.index(jt.slider)
        Q = origin[:, gb] + rotate(theta[:, gb], topo.attach(j, gb))
        P = origin[:, sb] + rotate(theta[:, sb], topo.attach(j, sb))
        u = rotate(theta[:, gb], [math.cos(jt.direction), math.sin(jt.direction)])
        q[:, topo.n_groups + i] = np.einsum("ni,ni->n", P - Q, u)
    # keep group angles continuous in the sweep (no 2*pi jumps from arctan2)
    if N > 1 and topo.n_groups:
        q[:, :topo.n_groups] = np.unwrap(q[:, :topo.n_groups], axis=0)
    return q


def poses_from_q(topo: Topology, q: np.ndarray):
    """Body angles ``(N, B)`` and frame origins ``(N, B, 2)`` from ``q``, walking the
    spanning tree from ground (each tree joint places its child body)."""
    N, B = q.shape[0], len(topo.body_names)
    theta = np.zeros((N, B))
    for b in range(B):
        g = topo.group_of[b]
        theta[:, b] = topo.offset[b] + (q[:, g] if g >= 0 else 0.0)
    origin = np.zeros((N, B, 2))
    for c in topo.order[1:]:
        p, j = topo.parent[c]
        jt = topo.mech.joints[j]
        if isinstance(jt, Revolute):
            P = origin[:, p] + rotate(theta[:, p], topo.attach(j, p))
            origin[:, c] = P - rotate(theta[:, c], topo.attach(j, c))
        else:
            s = q[:, topo.n_groups + topo.slider_index[j]]
            gb = topo.body_names.index(jt.guide)
            u = rotate(theta[:, gb], [math.cos(jt.direction), math.sin(jt.direction)])
            if c == topo.body_names.index(jt.slider):
                Q = origin[:, p] + rotate(theta[:, p], topo.attach(j, p))
                origin[:, c] = Q + s[:, None] * u - rotate(theta[:, c], topo.attach(j, c))
            else:
                PS = origin[:, p] + rotate(theta[:, p], topo.attach(j, p))
                origin[:, c] = PS - s[:, None] * u - rotate(theta[:, c], topo.attach(j, c))
    return theta, origin


def _hint_score(topo: Topology, theta, origin) -> float:
    """Squared distance of a single pose to the assembly hints (m^2, rad^2 * size^2)."""
    hints = topo.mech.assembly
    scale = size_of(topo)
    score = 0.0
    for key, xy in hints.points.items():
        bn, _, pn = key.partition(".")
        b = topo.body_names.index(bn)
        P = origin[0, b] + rotate(theta[:1, b], topo.body_points[b][pn])[0]
        score += float(np.sum((P - np.asarray(xy)) ** 2))
    for bn, ang in hints.angles.items():
        b = topo.body_names.index(bn)
        dth = (theta[0, b] - ang + math.pi) % (2 * math.pi) - math.pi
        score += float(dth * dth) * scale * scale
    return score


def choose_branches(topo: Topology, cf: ClosedForm, value: float) -> tuple[int, ...]:
    """The dyad branch signs whose pose at ``value`` lies nearest the hints.

    Without hints the all-(+1) combination is taken when it closes.
    """
    best, best_score = None, math.inf
    for signs in itertools.product((1, -1), repeat=cf.n_branch):
        th, org, disc, _ = cf.run(np.array([value]), signs)
        if disc.size and np.any(disc < -TOGGLE_SNAP):
            continue
        sc = _hint_score(topo, th, org)
        if sc < best_score - 1e-15:
            best, best_score = signs, sc
    if best is None:
        raise _infeasible(topo, value)
    return best


def _fmt_value(topo: Topology, v: float) -> str:
    if isinstance(topo.mech.driver_joint, Revolute):
        return f"{math.degrees(v):.6g} deg"
    return f"{v:.6g} m"


def _infeasible(topo: Topology, value: float, feasible=None) -> AssemblyError:
    if feasible is None:
        feasible = feasible_ranges(topo)
    j = topo.mech.driver.joint
    if feasible:
        rng = ", ".join(f"[{_fmt_value(topo, a)}, {_fmt_value(topo, b)}]" for a, b in feasible)
        msg = (f"mechanism {topo.mech.name!r}: the loops cannot close at driver {j!r} = "
               f"{_fmt_value(topo, value)}; feasible input range(s): {rng}")
    else:
        msg = (f"mechanism {topo.mech.name!r}: the loops cannot close at driver {j!r} = "
               f"{_fmt_value(topo, value)}, nor at any input value tried")
    return AssemblyError(msg, value, feasible)


def input_span(topo: Topology) -> tuple[float, float]:
    """The input interval searched for feasibility: one turn from the reference
    angle for a revolute driver; +-2 mechanism sizes around it for a slider."""
    v0 = topo.mech.driver.value
    if isinstance(topo.mech.driver_joint, Revolute):
        return v0 - math.pi, v0 + math.pi
    L = size_of(topo)
    return v0 - 2 * L, v0 + 2 * L


def feasible_ranges(topo: Topology, n: int = 3601, signs=None) -> list[tuple[float, float]]:
    """Input intervals (SI) where every dyad closes, on :func:`input_span`.

    ``signs`` restricts the test to one branch combination (default: any).  The
    intervals are found on ``n`` samples, then each end is refined by bisection to
    1e-12 of the span.  A mechanism without a closed form reports the whole span.
    """
    lo, hi = input_span(topo)
    if topo.plan is None:
        return [(lo, hi)]
    cf = ClosedForm(topo)
    combos = [tuple(signs)] if signs is not None else \
        list(itertools.product((1, -1), repeat=cf.n_branch))

    def ok(x):
        out = np.zeros(len(x), bool)
        for sg in combos:
            _, _, disc, _ = cf.run(x, sg)
            out |= np.all(disc >= -TOGGLE_SNAP, axis=1) if disc.size else True
        return out

    x = np.linspace(lo, hi, n)
    good = ok(x)

    def refine(a, b):  # a feasible, b not: bisect to the boundary (feasible side)
        for _ in range(60):
            m = 0.5 * (a + b)
            if ok(np.array([m]))[0]:
                a = m
            else:
                b = m
            if abs(b - a) < 1e-12 * (hi - lo):
                break
        return a

    out = []
    i = 0
    while i < n:
        if good[i]:
            k = i
            while k + 1 < n and good[k + 1]:
                k += 1
            a = refine(x[i], x[i - 1]) if i > 0 else x[i]
            b = refine(x[k], x[k + 1]) if k < n - 1 else x[k]
            out.append((float(a), float(b)))
            i = k + 1
        else:
            i += 1
    return out


def newton(eqs: LoopEquations, q0: np.ndarray, values: np.ndarray, tol: float):
    """Damped Newton-Raphson on the loop equations plus the driver row, batched.

    Returns ``(q, converged)``; ``converged`` is a bool array ``(N,)``.
    """
    topo = eqs.topo
    q = q0.copy()
    c = topo.driver_row
    for _ in range(NEWTON_MAX_ITER):
        f = eqs.residual(q)
        fd = q @ c - topo.driver_const - values
        F = np.concatenate([f, fd[:, None]], axis=1)
        err = np.max(np.abs(F), axis=1)
        if np.all(err < tol):
            return q, err < tol
        J = eqs.jacobian(q)
        A = np.concatenate([J, np.broadcast_to(c, (len(q), 1, eqs.nq))], axis=1)
        try:
            dq = np.linalg.lstsq(A[0], -F[0], rcond=None)[0][None] if len(q) == 1 else \
                np.linalg.solve(A, -F[..., None])[..., 0]
        except np.linalg.LinAlgError:
            return q, np.zeros(len(q), bool)
        # limit angle steps to 0.5 rad so a far start does not jump branch wildly
        step = np.max(np.abs(dq), axis=1, keepdims=True)
        q = q + dq * np.minimum(1.0, 0.5 / np.maximum(step, 1e-300))
    f = eqs.residual(q)
    fd = q @ c - topo.driver_const - values
    err = np.maximum(np.max(np.abs(f), axis=1), np.abs(fd))
    return q, err < tol


def initial_guess(topo: Topology) -> np.ndarray:
    """Newton start from the assembly hints: hinted body angles, 0 elsewhere."""
    q = np.zeros((1, topo.nq))
    for bn, ang in topo.mech.assembly.angles.items():
        b = topo.body_names.index(bn)
        if topo.group_of[b] >= 0:
            q[0, topo.group_of[b]] = ang - topo.offset[b]
    return q


class PositionSolver:
    """Solve positions for any input values; remembers the branch choice."""

    def __init__(self, topo: Topology, eqs: LoopEquations):
        self.topo, self.eqs = topo, eqs
        self.size = size_of(topo)
        self.tol = LOOP_RESIDUAL * self.size
        self.cf = ClosedForm(topo) if topo.plan is not None else None
        v0 = topo.mech.driver.value
        if self.cf is not None:
            self.signs = choose_branches(topo, self.cf, v0)
        else:
            q, ok = newton(eqs, initial_guess(topo), np.array([v0]), self.tol)
            if not ok[0]:
                raise AssemblyError(
                    f"mechanism {topo.mech.name!r}: Newton-Raphson did not assemble the "
                    f"loops at driver {topo.mech.driver.joint!r} = {_fmt_value(topo, v0)} "
                    "from the assembly hints; give approximate body angles in [assembly]",
                    v0)
            self.q_ref = q

    def solve(self, values: np.ndarray):
        """``q (N, nq)`` and the dyad transmission data for sorted or unsorted values.

        Raises
        ------
        AssemblyError
            At the first value where a loop cannot close, with the feasible ranges.
        """
        values = np.asarray(values, float)
        trans = []
        if self.cf is not None:
            theta, origin, disc, trans = self.cf.run(values, self.signs)
            if disc.size:
                bad = np.flatnonzero(np.any(disc < -TOGGLE_SNAP, axis=1))
                if bad.size:
                    raise _infeasible(self.topo, float(values[bad[0]]))
            q = q_from_poses(self.topo, theta, origin)
        else:
            q = self._continue(values)
        res = np.max(np.abs(self.eqs.residual(q)), axis=1) if self.eqs.L else np.zeros(len(q))
        worst = int(np.argmax(res)) if len(res) else 0
        if len(res) and res[worst] > self.tol:
            raise AssemblyError(
                f"mechanism {self.topo.mech.name!r}: loop residual {res[worst]:.3g} m at "
                f"driver = {_fmt_value(self.topo, float(values[worst]))} exceeds "
                f"{self.tol:.3g} m", float(values[worst]))
        return q, trans

    def _continue(self, values):
        """Sequential Newton continuation from the reference pose, in input order
        outward from the reference value (first-order predictor)."""
        v0 = self.topo.mech.driver.value
        out = np.zeros((len(values), self.topo.nq))
        order = np.argsort(np.abs(values - v0))
        prev_v, prev_q = v0, self.q_ref[0]
        # continue outward in both directions from v0
        for direction in (1, -1):
            pv, pq = prev_v, prev_q
            pqd = None
            idx = [i for i in order if (values[i] - v0) * direction >= 0]
            idx.sort(key=lambda i: abs(values[i] - v0))
            for i in idx:
                v = values[i]
                guess = pq.copy()
                if pqd is not None:
                    guess = guess + pqd * (v - pv)
                q, ok = newton(self.eqs, guess[None], np.array([v]), self.tol)
                if not ok[0]:
                    raise _infeasible(self.topo, float(v), feasible=[])
                J = self.eqs.jacobian(q)
                pqd = self.eqs.solve_rates(J, np.zeros((1, 2 * self.eqs.L)), np.ones(1))[0]
                out[i], pv, pq = q[0], v, q[0]
        return out
