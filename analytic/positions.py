"""Position analysis: closed-form dyads where possible, Newton-Raphson otherwise.

The closed form follows the structure of the mechanism: the driven link is
placed from the input, then each dyad (two bodies, three joints, the outer two
on known bodies) from the bodies already placed; RRR, RRP, RPR and PRP dyads
have closed-form solutions with a branch sign each.  The signs are chosen at the
driver's reference value as the combination nearest the assembly hints
(:func:`choose_branches`), and then followed along the input
(:mod:`analytic.branches`): held, except at a change point, where the branch
whose velocity is continuous is taken.  A mechanism that does not decompose into
these dyads is assembled by Newton-Raphson nearest the hints (:func:`assemble`)
and its branch traced along the input (:mod:`analytic.continuation`).  Either
way the assembly must lie within :data:`HINT_DISTANCE` of the hints
(:func:`check_hints`) and the result is checked against the loop equations
(residual below :data:`analytic.tolerances.LOOP_RESIDUAL` times the mechanism's
size).  Every threshold is relative to the mechanism's size (:func:`size_of`).
"""

from __future__ import annotations

import cmath
import itertools
import math

import numpy as np

from .errors import AssemblyError
from .loops import LoopEquations
from .mechanism import Revolute, mechanism_size
from .planar import cplx, cross
from .tolerances import (
    ASSEMBLY_STARTS,
    HINT_DISTANCE,
    LOOP_RESIDUAL,
    NEWTON_MAX_ITER,
    NEWTON_MAX_STEP,
    TOGGLE_SNAP,
)
from .topology import BRANCHING, WITH_DISCRIMINANT, Topology


def size_of(topo: Topology) -> float:
    """A length scale of the mechanism (m): the largest point distance in any body
    (:func:`analytic.mechanism.mechanism_size`, which validation uses too), 1 m when the
    description has no two points on one body."""
    return mechanism_size(topo.mech.bodies) or 1.0


def rrr_disc_factor(c1: complex, c2: complex) -> float:
    """The factor that makes an RRR dyad's ``h^2`` (m^2, the squared distance of the
    inner joint from the line of the outer joints) its relative discriminant
    ``h^2 (L1 + L2) / (L1 L2 max(L1, L2))``.  Placing the inner joint on that line
    (h = 0, the toggle) shortens the links' reach by ``h^2 (1/L1 + 1/L2) / 2``, which
    is ``disc * max(L1, L2) / 2``: a discriminant below :data:`TOGGLE_SNAP` is snapped
    with a loop gap below half of :data:`LOOP_RESIDUAL` of the mechanism's size, for
    any ratio of the two links (``h^2 / L1^2`` alone left a gap of ``L1 / (2 L2)`` times
    that: 1.3e-12 of the size for a parallelogram with L1 = 12 L2, an assembly refused)."""
    L1, L2 = abs(c1), abs(c2)
    return (L1 + L2) / (L1 * L2 * max(L1, L2))


class Placement:
    """The poses :meth:`ClosedForm.run` builds, step by step: angles ``theta (N, B)``,
    ``E = exp(i theta)`` and origins ``O`` (complex ``(N, B)``), the dyads'
    discriminants and the transmission data, in the plan's order."""

    def __init__(self, N: int, B: int):
        self.theta = np.zeros((N, B))
        self.E = np.ones((N, B), complex)
        self.O = np.zeros((N, B), complex)
        self.discs: list[np.ndarray] = []
        self.trans: list[tuple] = []

    def pt(self, b, c):
        """World point of the body-frame point ``c`` of body ``b``."""
        return self.O[:, b] + self.E[:, b] * c

    def place(self, b, th, e=None):
        """Set body ``b``'s angle ``th`` and ``E`` (``exp(i th)`` unless given)."""
        self.theta[:, b] = th
        self.E[:, b] = np.exp(1j * th) if e is None else e


class ClosedForm:
    """Evaluate the dyad plan for a batch of input values and fixed branch signs.

    Planar vectors are complex numbers here (x + iy): a body frame's rotation is
    ``E = exp(i theta)``, a body point is ``O + E c``.  One solver per step kind
    (:meth:`_driven_revolute`, :meth:`_driven_prismatic`, :meth:`_rrr`, :meth:`_rrp`,
    :meth:`_rpr`, :meth:`_prp`, :meth:`_driven_rrr`), as :mod:`analytic.kernels.codegen`
    generates them.
    """

    def __init__(self, topo: Topology):
        self.topo = topo
        self.mech = topo.mech
        self.plan = topo.plan
        self.n_branch = sum(1 for st in self.plan if st.kind in BRANCHING)
        self.at = {}  # (joint, body) -> complex attachment point, body frame
        for j, jt in enumerate(self.mech.joints):
            for bn in jt.bodies:
                b = topo.body_names.index(bn)
                self.at[j, b] = cplx(topo.attach(j, b))

    def run(self, values: np.ndarray, signs, steps: int | None = None):
        """Place every body (or those of the plan's first ``steps`` steps: the rest
        stay at the origin, unrotated).

        ``signs``: one branch sign per branching dyad, or per dyad an ``(N,)`` array
        of signs (each input value with its own).  Returns ``theta (N, B)``, ``E =
        exp(i theta) (N, B)``, origins ``O (N, B)`` (complex), ``disc (N, n_steps)``
        (the dyads' relative discriminants: negative where a dyad cannot close) and
        the transmission data ``[(joint name, vector 1, vector 2)]``.
        """
        N, B = len(values), len(self.topo.body_names)
        p = Placement(N, B)
        self.place(p, values, iter(signs), self.plan[:steps])
        disc = np.stack(p.discs, axis=1) if p.discs else np.ones((N, 0))
        return p.theta, p.E, p.O, disc, p.trans

    def place(self, p: Placement, values: np.ndarray, si, steps) -> None:
        """Carry out the plan's ``steps`` on the placement ``p`` (the bodies of the steps
        before them placed already), branching dyads taking their signs from the
        iterator ``si``."""
        for st in steps:
            if st.kind == "driven_revolute":
                self._driven_revolute(p, st, values)
            elif st.kind == "driven_prismatic":
                self._driven_prismatic(p, st, values)
            elif st.kind == "RRR":
                self._rrr(p, st, si)
            elif st.kind == "driven_RRR":
                self._driven_rrr(p, st, values, si)
            elif st.kind == "RRP":
                self._rrp(p, st, si)
            elif st.kind == "RPR":
                self._rpr(p, st, si)
            elif st.kind == "PRP":
                self._prp(p, st)

    def _on_slide(self, p: Placement, x: int, j: int):
        """Orient body ``x``, one of prismatic joint ``j``'s bodies, from the other one
        ``k`` (the joint's fixed angle); returns ``k``, the line's direction in the world
        and whether ``x`` is the slider."""
        jt = self.mech.joints[j]
        k = self.topo.other(j, x)
        if self.topo.body_names[x] == jt.slider:
            p.place(x, p.theta[:, k] + jt.angle, p.E[:, k] * cmath.exp(1j * jt.angle))
            return k, p.E[:, k] * cmath.exp(1j * jt.direction), True
        p.place(x, p.theta[:, k] - jt.angle, p.E[:, k] * cmath.exp(-1j * jt.angle))
        return k, p.E[:, x] * cmath.exp(1j * jt.direction), False

    def _driven_revolute(self, p: Placement, st, values):
        """The driven link of a revolute driver: its angle is the input from the body
        it turns on."""
        topo, at = self.topo, self.at
        (x,), (j,) = st.bodies, st.joints
        k = topo.other(j, x)
        sgn = 1.0 if topo.body_names[x] == self.mech.joints[j].body_b else -1.0
        p.place(x, p.theta[:, k] + sgn * values)
        p.O[:, x] = p.pt(k, at[j, k]) - p.E[:, x] * at[j, x]

    def _driven_prismatic(self, p: Placement, st, values):
        """The driven body of a prismatic driver: the input is the slider's
        displacement along the line."""
        at = self.at
        (x,), (j,) = st.bodies, st.joints
        k, u, slider = self._on_slide(p, x, j)
        if slider:
            PS = p.pt(k, at[j, k]) + values * u
            p.O[:, x] = PS - p.E[:, x] * at[j, x]
        else:
            Q = p.pt(k, at[j, k]) - values * u
            p.O[:, x] = Q - p.E[:, x] * at[j, x]

    def _rrr(self, p: Placement, st, si):
        """An RRR dyad: the inner joint at an intersection of two circles."""
        topo, at = self.topo, self.at
        x1, x2 = st.bodies
        j1, j2, j3 = st.joints
        k1, k3 = topo.other(j1, x1), topo.other(j3, x2)
        P1, P3 = p.pt(k1, at[j1, k1]), p.pt(k3, at[j3, k3])
        c1 = at[j2, x1] - at[j1, x1]
        c2 = at[j3, x2] - at[j2, x2]
        L1s, L2s = abs(c1) ** 2, abs(c2) ** 2
        d = P3 - P1
        D2 = d.real * d.real + d.imag * d.imag
        D = np.sqrt(D2)
        Dsafe = np.where(D > 0, D, 1.0)
        a = (L1s - L2s + D2) / (2 * Dsafe)
        h2 = L1s - a * a
        disc = np.where(D > 0, h2 * rrr_disc_factor(c1, c2), -1.0)
        p.discs.append(disc)
        h = np.where(disc > TOGGLE_SNAP, np.sqrt(np.maximum(h2, 0.0)), 0.0)
        sg = next(si)
        P2 = P1 + d * (a + 1j * sg * h) / Dsafe
        e1, e2 = P2 - P1, P3 - P2
        # exp(i theta) of each link straight from geometry: no trigonometry
        u1 = e1 / np.abs(e1) * (c1 / abs(c1)).conjugate()
        u2 = e2 / np.abs(e2) * (c2 / abs(c2)).conjugate()
        p.place(x1, np.angle(u1), u1)
        p.place(x2, np.angle(u2), u2)
        p.O[:, x1] = P1 - u1 * at[j1, x1]
        p.O[:, x2] = P2 - u2 * at[j2, x2]
        p.trans.append((self.mech.joints[j2].name, -e1, e2))

    def _driven_rrr(self, p: Placement, st, values, si):
        """A revolute driver between two moving bodies ``u`` and ``v`` (a ``driven_RRR``
        step, see :class:`analytic.topology.DyadStep`): at the driver's angle ``u`` and
        ``v`` are one rigid body, whose joints ``j1`` (on a known body) and ``j2`` (to
        ``w``) are a virtual link of length ``|c1|``; ``j2`` is at an intersection of
        the circle of that radius about ``j1`` with the circle of ``w``'s link about
        ``j3`` (:meth:`_rrr`'s operations with ``c1`` per value), then ``v`` turns on
        ``u`` by the driver's angle."""
        topo, at = self.topo, self.at
        u, w, v = st.bodies
        j1, j2, j3, jd = st.joints
        k1, k3 = topo.other(j1, u), topo.other(j3, w)
        P1, P3 = p.pt(k1, at[j1, k1]), p.pt(k3, at[j3, k3])
        sgn = 1.0 if topo.body_names[v] == self.mech.joints[jd].body_b else -1.0
        R = np.exp(1j * (sgn * values))  # v's frame in u's
        # the virtual link in u's frame: j1 -> driver -> j2
        c1 = at[jd, u] - at[j1, u] + R * (at[j2, v] - at[jd, v])
        c2 = at[j3, w] - at[j2, w]
        L1 = np.abs(c1)
        L1s, L2s, L2 = L1 * L1, abs(c2) ** 2, abs(c2)
        d = P3 - P1
        D2 = d.real * d.real + d.imag * d.imag
        D = np.sqrt(D2)
        ok = (D > 0) & (L1 > 0)
        Dsafe = np.where(D > 0, D, 1.0)
        L1safe = np.where(L1 > 0, L1, 1.0)
        a = (L1s - L2s + D2) / (2 * Dsafe)
        h2 = L1s - a * a
        disc = np.where(ok, h2 * (L1safe + L2) / (L1safe * L2 * np.maximum(L1safe, L2)), -1.0)
        p.discs.append(disc)
        h = np.where(disc > TOGGLE_SNAP, np.sqrt(np.maximum(h2, 0.0)), 0.0)
        sg = next(si)
        P2 = P1 + d * (a + 1j * sg * h) / Dsafe
        e1, e2 = P2 - P1, P3 - P2
        eu = e1 / np.abs(e1) * (c1 / L1safe).conjugate()
        ew = e2 / np.abs(e2) * (c2 / L2).conjugate()
        p.place(u, np.angle(eu), eu)
        p.place(w, np.angle(ew), ew)
        p.place(v, p.theta[:, u] + sgn * values, eu * R)
        p.O[:, u] = P1 - eu * at[j1, u]
        p.O[:, w] = P2 - ew * at[j2, w]
        p.O[:, v] = P2 - p.E[:, v] * at[j2, v]
        PD = p.pt(u, at[jd, u])  # the driver joint
        p.trans.append((self.mech.joints[j2].name, PD - P2, e2))

    def _rrp(self, p: Placement, st, si):
        """An RRP dyad: the inner joint where a circle meets the slider's line."""
        topo, at = self.topo, self.at
        x1, x2 = st.bodies
        j1, j2, j3 = st.joints
        k1 = topo.other(j1, x1)
        P1 = p.pt(k1, at[j1, k1])
        c1 = at[j2, x1] - at[j1, x1]
        L1s = abs(c1) ** 2
        k3, u, slider = self._on_slide(p, x2, j3)
        ud = u if slider else -u
        base = p.pt(k3, at[j3, k3]) + p.E[:, x2] * (at[j2, x2] - at[j3, x2])
        e = base - P1
        eu = e.real * ud.real + e.imag * ud.imag
        h2 = eu * eu - (e.real * e.real + e.imag * e.imag) + L1s
        p.discs.append(h2 / L1s)
        sg = next(si)
        t = -eu + sg * np.where(h2 / L1s > TOGGLE_SNAP, np.sqrt(np.maximum(h2, 0.0)),
                                0.0)
        P2 = base + t * ud
        e1 = P2 - P1
        u1 = e1 / np.abs(e1) * (c1 / abs(c1)).conjugate()
        p.place(x1, np.angle(u1), u1)
        p.O[:, x1] = P1 - u1 * at[j1, x1]
        p.O[:, x2] = P2 - p.E[:, x2] * at[j2, x2]
        p.trans.append((self.mech.joints[j2].name, -e1, 1j * u))

    def _rpr(self, p: Placement, st, si):
        """An RPR dyad: the slot's angle from the distance of its two pins (no
        transmission angle: the slot's force is always normal to it)."""
        topo, at = self.topo, self.at
        x1, x2 = st.bodies
        j1, j2, j3 = st.joints
        jt = self.mech.joints[j2]
        g = x1 if topo.body_names[x1] == jt.guide else x2
        s_ = x2 if g == x1 else x1
        jg, js = (j1, j3) if g == x1 else (j3, j1)
        kg, ks = topo.other(jg, g), topo.other(js, s_)
        PG, PSr = p.pt(kg, at[jg, kg]), p.pt(ks, at[js, ks])
        aG, aS = at[jg, g], at[js, s_]
        nl = 1j * cmath.exp(1j * jt.direction)
        kconst = (nl.conjugate() * (cmath.exp(1j * jt.angle) * (at[j2, s_] - aS)
                                    - (at[j2, g] - aG))).real
        d = PSr - PG
        D = np.abs(d)
        Dsafe = np.where(D > 0, D, 1.0)
        ratio = -kconst / Dsafe
        disc = np.where(D > 0, 1.0 - ratio * ratio, -1.0)
        p.discs.append(disc)
        sg = next(si)
        psi = np.angle(d)
        acos = np.where(disc > TOGGLE_SNAP, np.arccos(np.clip(ratio, -1, 1)),
                        np.where(ratio > 0, 0.0, math.pi))
        th = psi - (jt.direction + math.pi / 2) + sg * acos
        p.place(g, th)
        p.place(s_, th + jt.angle, p.E[:, g] * cmath.exp(1j * jt.angle))
        p.O[:, g] = PG - p.E[:, g] * aG
        p.O[:, s_] = PSr - p.E[:, s_] * aS

    def _prp(self, p: Placement, st):
        """A PRP dyad: the inner joint where the two sliders' lines cross (no branch)."""
        at = self.at
        x1, x2 = st.bodies
        j1, j2, j3 = st.joints
        bases, dirs = [], []
        for x, j in ((x1, j1), (x2, j3)):
            k, u, _ = self._on_slide(p, x, j)
            bases.append(p.pt(k, at[j, k]) + p.E[:, x] * (at[j2, x] - at[j, x]))
            dirs.append(u)
        cr = cross(dirs[0], dirs[1])
        p.discs.append(np.abs(cr) - 1e-12)
        t1 = cross(bases[1] - bases[0], dirs[1]) / np.where(cr != 0, cr, 1.0)
        P2 = bases[0] + t1 * dirs[0]
        p.O[:, x1] = P2 - p.E[:, x1] * at[j2, x1]
        p.O[:, x2] = P2 - p.E[:, x2] * at[j2, x2]


def q_from_poses(topo: Topology, theta: np.ndarray, E: np.ndarray, O: np.ndarray) -> np.ndarray:
    """Vector-loop unknowns ``q (N, nq)`` from body poses (``O``, ``E`` complex)."""
    N = theta.shape[0]
    q = np.empty((N, topo.nq))
    for g, b in enumerate(topo.group_leader):
        q[:, g] = theta[:, b] - topo.offset[b]
    for j, i in topo.slider_index.items():
        jt = topo.mech.joints[j]
        gb = topo.body_names.index(jt.guide)
        sb = topo.body_names.index(jt.slider)
        dPQ = (O[:, sb] + E[:, sb] * cplx(topo.attach(j, sb))
               - O[:, gb] - E[:, gb] * cplx(topo.attach(j, gb)))
        u = E[:, gb] * cmath.exp(1j * jt.direction)
        q[:, topo.n_groups + i] = dPQ.real * u.real + dPQ.imag * u.imag
    # keep group angles continuous in the sweep (no 2*pi jumps from the arctan)
    if N > 1 and topo.n_groups:
        th = q[:, :topo.n_groups]
        turns = np.cumsum(np.round(np.diff(th, axis=0) * (0.5 / math.pi)), axis=0)
        th[1:] -= (2 * math.pi) * turns
    return q


def poses_from_q(topo: Topology, q: np.ndarray):
    """Body angles ``(N, B)``, ``E = exp(i theta)`` and frame origins ``O`` (complex,
    ``(N, B)``) from ``q``, walking the spanning tree from ground (each tree joint
    places its child body)."""
    N, B = q.shape[0], len(topo.body_names)
    theta = np.zeros((N, B))
    for b in range(B):
        g = topo.group_of[b]
        theta[:, b] = topo.offset[b] + (q[:, g] if g >= 0 else 0.0)
    E = np.exp(1j * theta)
    O = np.zeros((N, B), complex)
    for c in topo.order[1:]:
        p, j = topo.parent[c]
        jt = topo.mech.joints[j]
        cp, cc = cplx(topo.attach(j, p)), cplx(topo.attach(j, c))
        if isinstance(jt, Revolute):
            O[:, c] = O[:, p] + E[:, p] * cp - E[:, c] * cc
        else:
            s = q[:, topo.n_groups + topo.slider_index[j]]
            gb = topo.body_names.index(jt.guide)
            u = E[:, gb] * cmath.exp(1j * jt.direction)
            sgn = 1.0 if c == topo.body_names.index(jt.slider) else -1.0
            O[:, c] = O[:, p] + E[:, p] * cp + sgn * s * u - E[:, c] * cc
    return theta, E, O


def hint_distances(topo: Topology, theta, E, O) -> tuple[list[str], np.ndarray]:
    """Distance of each pose to each assembly hint, relative to the mechanism's size.

    Returns the hints' labels (``"body.point"`` or ``"body angle"``) and an array
    ``(N, H)``: a point hint's distance (m) divided by :func:`size_of`, an angle hint's
    wrapped angle error (rad), i.e. the arc it moves a point one size from the pivot.
    """
    hints = topo.mech.assembly
    scale = size_of(topo)
    labels, cols = [], []
    for key, xy in hints.points.items():
        bn, _, pn = key.partition(".")
        b = topo.body_names.index(bn)
        P = O[:, b] + E[:, b] * cplx(topo.body_points[b][pn])
        labels.append(key)
        cols.append(np.abs(P - cplx(xy)) / scale)
    for bn, ang in hints.angles.items():
        b = topo.body_names.index(bn)
        labels.append(f"{bn} angle")
        cols.append(np.abs((theta[:, b] - ang + math.pi) % (2 * math.pi) - math.pi))
    N = theta.shape[0]
    return labels, (np.stack(cols, axis=1) if cols else np.zeros((N, 0)))


def _hint_score(topo: Topology, theta, E, O) -> np.ndarray:
    """Sum of squared relative hint distances of each pose ``(N,)`` (0 without hints)."""
    return np.sum(hint_distances(topo, theta, E, O)[1] ** 2, axis=1)


def check_hints(topo: Topology, theta, E, O, value: float) -> None:
    """Raise :class:`AssemblyError` when the solved pose (first row) lies farther from
    any hint than :data:`HINT_DISTANCE` of the mechanism's size, naming the hint and
    the distance."""
    labels, d = hint_distances(topo, theta[:1], E[:1], O[:1])
    if not labels:
        return
    k = int(np.argmax(d[0]))
    if d[0, k] <= HINT_DISTANCE:
        return
    scale = size_of(topo)
    if labels[k].endswith(" angle"):
        ang = math.degrees(topo.mech.assembly.angles[labels[k][:-6]])
        what = (f"hint {labels[k]!r} = {ang:.6g} deg is {math.degrees(d[0, k]):.4g} deg "
                "from the nearest assembly")
    else:
        xy = topo.mech.assembly.points[labels[k]]
        what = (f"point hint {labels[k]!r} = ({xy[0]:.6g}, {xy[1]:.6g}) m is "
                f"{d[0, k] * scale:.4g} m from the nearest assembly")
    raise AssemblyError(
        f"mechanism {topo.mech.name!r}: at driver {topo.mech.driver.joint!r} = "
        f"{_fmt_value(topo, value)} no assembly lies near the hints: {what} "
        f"({d[0, k]:.3g} of the linkage's size {scale:.4g} m; at most {HINT_DISTANCE} "
        "is accepted); correct the [assembly] hints or the geometry", value)


def choose_branches(topo: Topology, cf: ClosedForm, value: float) -> tuple[int, ...]:
    """The dyad branch signs whose pose at ``value`` lies nearest the hints.

    Without hints the all-(+1) combination is taken when it closes.  Scores are
    relative to the mechanism's size, so the choice is the same at any scale.  With
    more than :data:`_JOINT_CHOICE` dyads (2^n combinations) the signs are chosen one
    dyad at a time in the plan's order, each nearest the hints on the two bodies it
    places (a dyad places its bodies from bodies placed before it, so this is the
    same choice wherever each dyad's bodies carry hints).
    """
    if cf.n_branch > _JOINT_CHOICE:
        return _choose_one_by_one(topo, cf, value)
    best, best_score = None, math.inf
    for signs in itertools.product((1, -1), repeat=cf.n_branch):
        th, E, O, disc, _ = cf.run(np.array([value]), signs)
        if disc.size and np.any(disc < -TOGGLE_SNAP):
            continue
        sc = float(_hint_score(topo, th, E, O)[0])
        # relative scores: a tie (no hints) keeps the first combination
        if sc < best_score - 1e-12:
            best, best_score = signs, sc
    if best is None:
        raise _infeasible(topo, value)
    return best


#: Most dyads whose sign combinations :func:`choose_branches` enumerates jointly.
_JOINT_CHOICE = 12


def branching_steps(topo: Topology) -> list:
    """The plan's steps that carry a branch sign (:data:`BRANCHING`), in sign order."""
    return [st for st in topo.plan if st.kind in BRANCHING]


def _choose_one_by_one(topo: Topology, cf: ClosedForm, value: float) -> tuple[int, ...]:
    """Dyad signs chosen in plan order, each by the hints on its own two bodies."""
    signs = [1] * cf.n_branch
    v = np.array([value, value])
    disc_steps = [st for st in topo.plan if st.kind in WITH_DISCRIMINANT]
    for k, st in enumerate(branching_steps(topo)):
        col = disc_steps.index(st)
        names = {topo.body_names[b] for b in st.bodies}
        # both signs of dyad k at once (one per value), through the plan's steps up to
        # dyad k's: the bodies it places depend on no later step
        sg = np.repeat(np.array(signs, float)[:, None], 2, axis=1)
        sg[k] = (1.0, -1.0)
        th, E, O, disc, _ = cf.run(v, sg, topo.plan.index(st) + 1)
        labels, d = hint_distances(topo, th, E, O)
        mine = [i for i, lab in enumerate(labels)
                if lab.partition(".")[0].removesuffix(" angle") in names]
        scores = [float(np.sum(d[r, mine] ** 2)) if not disc[r, col] < -TOGGLE_SNAP
                  else math.inf for r in (0, 1)]
        if not math.isfinite(min(scores)):
            raise _infeasible(topo, value)
        signs[k] = 1 if scores[0] <= scores[1] + 1e-12 else -1
    return tuple(signs)


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
    1e-16 of the span (the last bits).  A mechanism without a closed form reports the whole span.
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
            disc = cf.run(x, sg)[3]
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
            # to the last bits: the feasible end must lie within TOGGLE_SNAP of the toggle
            # (snapped, exactly singular), and an RRR discriminant's slope there grows
            # with the links' ratio
            if abs(b - a) < 1e-16 * (hi - lo):
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
    if isinstance(topo.mech.driver_joint, Revolute) and len(out) > 1 and \
            out[0][0] == lo and out[-1][1] == hi:
        # one interval across the span's seam (the span is one turn): join its halves,
        # on the turn that holds the reference value (the span's centre) when one half
        # does, so that the interval of the assembled branch contains it
        v0 = topo.mech.driver.value
        joined = ((out[-1][0], out[0][1] + 2 * math.pi) if v0 >= out[-1][0] else
                  (out[-1][0] - 2 * math.pi, out[0][1]))
        out = [joined] + out[1:-1]
        out.sort()
    return out


def step_limits(topo: Topology) -> np.ndarray:
    """Largest Newton step per unknown ``(nq,)``: rad for angles, m for sliders."""
    lim = np.full(topo.nq, NEWTON_MAX_STEP)
    lim[topo.n_groups:] *= size_of(topo)
    return lim


def newton(eqs: LoopEquations, q0: np.ndarray, values: np.ndarray, tol: float,
           max_iter: int = NEWTON_MAX_ITER):
    """Damped Newton-Raphson on the loop equations plus the driver row, batched.

    ``tol`` bounds the loop residual (m); the driver row (rad or m) is held to
    :data:`LOOP_RESIDUAL` of its own scale, so that the test does not depend on the
    mechanism's size.  Each start is iterated until it converges (a singular or
    diverging start simply fails).  Returns ``(q, converged)``; ``converged`` is a bool
    array ``(N,)``.
    """
    topo = eqs.topo
    q = np.array(q0, float, copy=True)
    values = np.broadcast_to(np.asarray(values, float), (len(q),))
    c = topo.driver_row
    lim = step_limits(topo)
    tol_d = LOOP_RESIDUAL * (np.maximum(1.0, np.abs(values)) if topo.driven_var is None
                             or topo.driven_var < topo.n_groups else size_of(topo))

    def errors(q_, v_, td):
        f = eqs.residual(q_)
        fd = q_ @ c - topo.driver_const - v_
        err = np.maximum(np.max(np.abs(f), axis=1, initial=0.0) / tol, np.abs(fd) / td)
        return np.concatenate([f, fd[:, None]], axis=1), np.where(np.isfinite(err), err, np.inf)

    tol_d = np.broadcast_to(tol_d, (len(q),))
    active = np.ones(len(q), bool)
    for _ in range(max_iter):
        idx = np.flatnonzero(active)
        F, err = errors(q[idx], values[idx], tol_d[idx])
        done = err < 1.0
        active[idx[done]] = False
        idx, F = idx[~done], F[~done]
        if not idx.size:
            break
        J = eqs.jacobian(q[idx])
        A = np.concatenate([J, np.broadcast_to(c, (len(idx), 1, eqs.nq))], axis=1)
        with np.errstate(all="ignore"):
            try:  # square for one degree of freedom; least squares where singular
                dq = np.linalg.solve(A, -F[..., None])[..., 0]
            except np.linalg.LinAlgError:
                try:
                    dq = (np.linalg.pinv(A) @ -F[..., None])[..., 0]
                except np.linalg.LinAlgError:  # non-finite entries: those starts fail
                    active[idx] = False
                    break
        ratio = np.max(np.abs(dq) / lim, axis=1, keepdims=True)
        dq = dq * np.minimum(1.0, 1.0 / np.where(ratio > 0, ratio, 1.0))
        bad = ~np.all(np.isfinite(dq), axis=1)
        active[idx[bad]] = False
        q[idx[~bad]] += dq[~bad]
    _, err = errors(q, values, tol_d)
    return q, err < 1.0


def initial_guess(topo: Topology) -> np.ndarray:
    """Newton start from the assembly hints: hinted body angles, 0 elsewhere."""
    q = np.zeros((1, topo.nq))
    for bn, ang in topo.mech.assembly.angles.items():
        b = topo.body_names.index(bn)
        if topo.group_of[b] >= 0:
            q[0, topo.group_of[b]] = ang - topo.offset[b]
    return q


def _driven(topo: Topology, q: np.ndarray, value: float) -> np.ndarray:
    """Set the driven variable of each row of ``q`` so that the driver row holds."""
    k = topo.driven_var
    if k is not None:
        q[:, k] = (value + topo.driver_const
                   - q @ topo.driver_row + q[:, k] * topo.driver_row[k]) / topo.driver_row[k]
    return q


def fit_to_hints(topo: Topology, eqs: LoopEquations, value: float, q0: np.ndarray,
                 weights=(1.0, 0.1, 1e-2, 1e-3)) -> np.ndarray:
    """A configuration near the hints: Levenberg-Marquardt on the loop residual (in
    sizes) plus ``w`` times the hint residuals, for decreasing ``w``.  The result is a
    Newton start nearest the hints, not an assembly."""
    hints = topo.mech.assembly
    scale = size_of(topo)
    q = _driven(topo, np.array(q0, float, copy=True), value)[0]
    free = [i for i in range(topo.nq) if i != topo.driven_var]
    pts = [(topo.body_names.index(k.partition(".")[0]),
            cplx(topo.body_points[topo.body_names.index(k.partition(".")[0])][k.partition(".")[2]]),
            cplx(xy)) for k, xy in hints.points.items()]
    angs = [(topo.body_names.index(bn), a) for bn, a in hints.angles.items()]

    def resid(qs, w):  # qs (M, nq) -> (M, R)
        th, E, O = poses_from_q(topo, qs)
        parts = [eqs.residual(qs) / scale]
        for b, c_, xy in pts:
            d = (O[:, b] + E[:, b] * c_ - xy) / scale
            parts += [w * d.real[:, None], w * d.imag[:, None]]
        for b, a in angs:
            parts.append(w * ((th[:, b] - a + math.pi) % (2 * math.pi) - math.pi)[:, None])
        return np.concatenate(parts, axis=1)

    h = 1e-7
    lim = step_limits(topo)
    for w in weights:
        lam = 1e-3
        for _ in range(40):
            r0 = resid(q[None], w)[0]
            Q = np.repeat(q[None], len(free), axis=0)
            for n, i in enumerate(free):
                Q[n, i] += h * (scale if i >= topo.n_groups else 1.0)
            Jr = ((resid(Q, w) - r0) / h).T  # (R, n_free), per unit step
            g = Jr.T @ r0
            H = Jr.T @ Jr
            step = -np.linalg.solve(H + lam * np.diag(np.diag(H) + 1e-12), g)
            dq = np.zeros(topo.nq)
            for n, i in enumerate(free):
                dq[i] = step[n] * (scale if i >= topo.n_groups else 1.0)
            ratio = float(np.max(np.abs(dq) / lim))
            if ratio > 1:
                dq /= ratio
            qn = q + dq
            if np.sum(resid(qn[None], w) ** 2) < np.sum(r0 ** 2):
                q, lam = qn, lam * 0.3
                if np.max(np.abs(dq) / lim) < 1e-10:
                    break
            else:
                lam *= 10.0
                if lam > 1e8:
                    break
    return q[None]


def _distinct(topo: Topology, q: np.ndarray) -> np.ndarray:
    """Rows of ``q`` that are different assemblies (angles compared modulo 2 pi)."""
    out = []
    scale = size_of(topo)
    for row in q:
        key = row.copy()
        for r in out:
            d = key - r
            d[:topo.n_groups] = (d[:topo.n_groups] + math.pi) % (2 * math.pi) - math.pi
            d[topo.n_groups:] /= scale
            if np.max(np.abs(d)) < 1e-6:
                break
        else:
            out.append(key)
    return np.array(out).reshape(-1, topo.nq)


def assemble(topo: Topology, eqs: LoopEquations, value: float, tol: float) -> np.ndarray:
    """The assembly ``(1, nq)`` at ``value`` nearest the hints, by Newton-Raphson.

    Newton runs from the hinted angles (0 elsewhere), from a configuration fitted to
    all hints (:func:`fit_to_hints`) and from :data:`ASSEMBLY_STARTS` seeded random
    starts; of the distinct assemblies found, the one nearest the hints (in the
    relative distance of :func:`hint_distances`) is returned.  Without hints, the
    assembly reached from the plain start (or else the first found) is returned.
    """
    hints = topo.mech.assembly
    q_plain = _driven(topo, initial_guess(topo), value)
    if not hints.points and not hints.angles:
        q, ok = newton(eqs, q_plain, np.array([value]), tol)
        if ok[0]:
            return q
    starts = [q_plain]
    if hints.points or hints.angles:
        try:
            starts.append(fit_to_hints(topo, eqs, value, q_plain))
        except np.linalg.LinAlgError:
            pass
    rng = np.random.default_rng(8)
    R = np.empty((ASSEMBLY_STARTS, topo.nq))
    R[:, :topo.n_groups] = rng.uniform(-math.pi, math.pi, (ASSEMBLY_STARTS, topo.n_groups))
    R[:, topo.n_groups:] = rng.uniform(-2, 2, (ASSEMBLY_STARTS, topo.nq - topo.n_groups)) \
        * size_of(topo)
    starts.append(_driven(topo, R, value))
    q, ok = newton(eqs, np.concatenate(starts), np.array([value]), tol)
    cands = _distinct(topo, q[ok])
    if not len(cands):
        raise AssemblyError(
            f"mechanism {topo.mech.name!r}: Newton-Raphson did not assemble the loops at "
            f"driver {topo.mech.driver.joint!r} = {_fmt_value(topo, value)} from the hints "
            f"nor from {ASSEMBLY_STARTS} other starts: the loops cannot close there", value)
    th, E, O = poses_from_q(topo, cands)
    return cands[[int(np.argmin(_hint_score(topo, th, E, O)))]]
