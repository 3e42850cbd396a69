"""Which dyad signs hold at which input: branches continued through change points.

A dyad's two assemblies are its branch signs.  Where its relative discriminant
``h^2 / L^2`` touches zero without going negative (a Grashof-boundary linkage's flat
positions), the two branches meet and cross: this is a *change point*.  Holding the
sign through it puts a kink in the motion (the velocity of the dyad's links flips), so
the moving linkage -- and an engine simulating it -- continues on the branch whose
velocity is continuous, which takes the other sign past the change point.  A
parallelogram four-bar then stays a parallelogram; holding the sign would turn it into
the anti-parallelogram.

:class:`BranchSchedule` walks the input axis from the reference value in both
directions and decides at each change point met which signs follow
(:meth:`BranchSchedule.decide`): by continuity of velocity (``branch_rule
"continuous"``; where continuity cannot decide, the signs are held and the crossing
says so), or as the user says (``"hold"`` or ``"switch"``).  An input value is a point
on that axis, reached by moving the input continuously from the reference: 0 and
2 pi differ after a change point, and values over several turns (an engine's run) get
the branch the linkage is on by then.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .mechanism import Revolute
from .positions import ClosedForm, Placement, input_span, size_of
from .tolerances import CHANGE_POINT_DISC, CONTINUITY_RATIO, TOGGLE_SNAP
from .topology import BRANCHING, WITH_DISCRIMINANT, Topology

#: Samples per turn (or span) searched for the discriminants' minima.
_SAMPLES = 3600
#: Most dyads touching at one change point whose sign combinations :meth:`decide`
#: compares jointly (2^n); beyond, one dyad at a time.
_JOINT_DECISION = 8


@dataclass(frozen=True)
class Crossing:
    """A change point passed on the way from the reference input.

    ``value`` (SI, on the input axis), ``joints`` the inner joints of the dyads at
    their toggle there, ``before`` and ``after`` the dyad signs, ``rule`` how the
    signs after were chosen: ``"velocity"`` (continuity of velocity),
    ``"held: continuity cannot decide"``, ``"hold"`` or ``"switch"`` (the
    ``branch_rule`` option), and ``jump`` the jump in d(pose)/d(input) that holding
    the signs would have caused (relative; 0 when held by velocity).
    """

    value: float
    joints: tuple[str, ...]
    before: tuple[int, ...]
    after: tuple[int, ...]
    rule: str
    jump: float

    @property
    def switched(self) -> bool:
        return self.before != self.after

    def describe(self, fmt=str) -> str:
        if self.switched:
            what = (f"dyad sign at {', '.join(self.joints)} switched "
                    f"{_signs(self.before)} -> {_signs(self.after)}")
        else:
            what = f"dyad signs held {_signs(self.before)}"
        how = {"velocity": "the branch whose velocity is continuous (the linkage's own motion)",
               "hold": "branch_rule 'hold'", "switch": "branch_rule 'switch'"}.get(
                   self.rule, "continuity of velocity cannot decide here; signs held "
                              "(branch_rule 'switch' takes the other branch)")
        return f"change point at {fmt(self.value)}: {what}; {how}"


def _keep(p: Placement, rows: tuple[int, int]) -> None:
    """The placement's two samples ``rows`` (a dyad's chosen sign) copied over all four,
    for the next dyad's two signs."""
    src = [rows[0], rows[1], rows[0], rows[1]]
    for a in (p.theta, p.E, p.O):
        a[:] = a[src]
    for c in p.discs:
        c[:] = c[src]


def _signs(s) -> str:
    return "(" + ", ".join("+1" if v > 0 else "-1" for v in s) + ")"


class BranchSchedule:
    """Dyad signs along the input axis, continued from the reference through change
    points (see the module docstring)."""

    def __init__(self, topo: Topology, cf: ClosedForm, signs0: tuple[int, ...],
                 reference: float, rule: str = "continuous"):
        self.topo, self.cf, self.signs0 = topo, cf, tuple(signs0)
        self.reference, self.rule = reference, rule
        self.revolute = isinstance(topo.mech.driver_joint, Revolute)
        self.size = size_of(topo)
        self.period = 2 * math.pi if self.revolute else None
        self._touch_memo: dict = {}
        self._decide_memo: dict = {}
        # the inner joint of each branching dyad (the order of the signs)
        self.dyad_joints = [topo.joint_names[st.joints[1]] for st in topo.plan
                            if st.kind in BRANCHING]
        # the closed form's discriminant columns of those dyads: it has one per dyad
        # with a discriminant, a PRP's too (its guides' crossing), which has no branch
        # sign; the signs and every column read here are the branching dyads'
        with_disc = [st.kind for st in topo.plan if st.kind in WITH_DISCRIMINANT]
        self._branch_cols = [c for c, kind in enumerate(with_disc) if kind in BRANCHING]

    # --- change points ------------------------------------------------------------
    def touches(self, signs) -> list[tuple[float, tuple[int, ...]]]:
        """Change points of the branch ``signs`` on one period from the reference (or
        the input span of a slider): ``[(value, dyads touching zero)]``."""
        signs = tuple(signs)
        if signs in self._touch_memo:
            return self._touch_memo[signs]
        if self.period is not None:
            lo, hi = self.reference, self.reference + self.period
        else:
            lo, hi = input_span(self.topo)
        x = np.linspace(lo, hi, _SAMPLES + 1)
        disc = self._touch(x, signs)
        found = []
        for k in range(disc.shape[1]):
            d = disc[:, k]
            if self.period:  # periodic: the last sample repeats the first
                prev, nxt = np.roll(d[:-1], 1), np.roll(d[:-1], -1)
                d = d[:-1]
            else:
                prev = np.concatenate([[np.inf], d[:-1]])
                nxt = np.concatenate([d[1:], [np.inf]])
            # candidate minima near zero; the refined minimum decides.  A double root's
            # sampled minimum is up to curvature * (spacing / 2)^2 ~ 1e-6 curvature; 0.1
            # admits curvatures to 1e5 (an RRR discriminant's grows with L1 / L2)
            # strict on one side: a dyad flat at zero over a stretch (a rhombus window
            # folded onto its base, on a held branch past a change point) is no minimum
            strict = (d < prev) | (d < nxt)
            found += [(float(x[i]), k) for i in np.flatnonzero(
                (d <= prev) & (d <= nxt) & strict & (np.abs(d) < 1e-1))]
        found = self._refined(found, x[1] - x[0], signs)
        out: dict[float, set] = {}
        for xm, k in sorted(found):
            key = next((v for v in out if abs(v - xm) < 1e-7 * (1 if self.revolute
                                                                  else self.size)), xm)
            out.setdefault(key, set()).add(k)
        res = [(v, tuple(sorted(ks))) for v, ks in sorted(out.items())]
        self._touch_memo[signs] = res
        return res

    def _touch(self, x: np.ndarray, signs) -> np.ndarray:
        """``(N, K)``: per dyad, the quantity whose touching zero is a change point: its
        relative discriminant (a toggle), and for an RRR dyad of two equal links also
        its squared base length relative to ``(L1 + L2)^2``: where the base shrinks to
        zero the two links fold onto each other and the two assemblies meet (a rhombus
        window of the IFToMM N four-bar at the horizontal)."""
        th, E, O, disc, _ = self.cf.run(x, signs)
        disc = disc.copy()
        for k, (P1, P3, scale) in self._equal_rrr(E, O):
            d = P3 - P1
            base2 = (d.real ** 2 + d.imag ** 2) / scale
            disc[:, k] = np.where(base2 == 0.0, 0.0, np.minimum(disc[:, k], base2))
        return disc[:, self._branch_cols]

    @cached_property
    def _has_equal_rrr(self) -> bool:
        """Whether an RRR dyad has two equal links (a rhombus window can fold at zero
        base: its change points are decided one dyad at a time, see :meth:`_touch`)."""
        th, E, O, _, _ = self.cf.run(np.array([self.reference]), self.signs0)
        return any(True for _ in self._equal_rrr(E, O))

    def _equal_rrr(self, E, O):
        """``(column, P1, P3, (L1 + L2)^2)`` of each RRR dyad of equal links."""
        topo, cf = self.topo, self.cf
        col = -1
        for st in topo.plan:
            if st.kind not in WITH_DISCRIMINANT:
                continue
            col += 1
            if st.kind != "RRR":
                continue
            (x1, x2), (j1, j2, j3) = st.bodies, st.joints
            L1, L2 = abs(cf.at[j2, x1] - cf.at[j1, x1]), abs(cf.at[j3, x2] - cf.at[j2, x2])
            if abs(L1 - L2) > 1e-12 * (L1 + L2):
                continue
            k1, k3 = topo.other(j1, x1), topo.other(j3, x2)
            P1 = O[:, k1] + E[:, k1] * cf.at[j1, k1]
            P3 = O[:, k3] + E[:, k3] * cf.at[j3, k3]
            yield col, (P1, P3, (L1 + L2) ** 2)

    def _refined(self, cands, dx: float, signs) -> list[tuple[float, int]]:
        """The candidate minima ``[(x0, dyad k)]`` refined (:meth:`_refine_min`), those
        whose discriminant there is zero to :data:`CHANGE_POINT_DISC`: ``[(x, k)]``.
        Every candidate in one closed-form evaluation per stage (the same numbers as
        one at a time: the closed form is elementwise in the inputs; A02 has 80
        candidates a branch, 1.3 s one at a time)."""
        if not cands:
            return []
        x = np.array([c[0] for c in cands])
        k = np.array([c[1] for c in cands])
        rows = np.arange(len(cands))
        for h in (dx, 1e-3 * dx, 1e-5 * dx):
            pts = np.stack([x - h, x, x + h], axis=1).ravel()
            y = self._touch(pts, signs).reshape(len(cands), 3, -1)[rows, :, k]
            x = self._vertex(x, h, y)
        dm = self._touch(x, signs)[rows, k]
        return [(float(xm), int(kk)) for xm, kk, d in zip(x, k, dm, strict=True)
                if abs(d) <= CHANGE_POINT_DISC]

    @staticmethod
    def _vertex(x: np.ndarray, h: float, y: np.ndarray) -> np.ndarray:
        """Per row, the vertex of the parabola through ``y (n, 3)`` at ``x - h, x,
        x + h`` (``x`` kept where the three do not curve upward)."""
        den = y[:, 0] - 2 * y[:, 1] + y[:, 2]
        up = den > 0
        step = 0.5 * h * (y[:, 0] - y[:, 2]) / np.where(up, den, 1.0)
        return np.where(up, x + step, x)

    def _refine_min(self, x0: float, dx: float, signs, k: int) -> float:
        """The minimum of dyad ``k``'s discriminant near ``x0``: vertex of a parabola
        through three samples, twice, with a shrinking spacing (a double root's
        minimum is located to ~1e-11 where sampling the values alone gives 1e-8)."""
        x = x0
        for h in (dx, 1e-3 * dx, 1e-5 * dx):
            y = self._touch(np.array([x - h, x, x + h]), signs)[:, k]
            den = y[0] - 2 * y[1] + y[2]
            if den > 0:
                x = x + 0.5 * h * (y[0] - y[2]) / den
        return float(x)

    @cached_property
    def constant(self) -> bool:
        """True when the reference branch meets no change point (signs never change)."""
        return not self.touches(self.signs0)

    # --- decisions ----------------------------------------------------------------
    def _pose(self, x, signs, steps: int | None = None):
        th, E, O, disc, _ = self.cf.run(np.asarray(x, float), signs, steps)
        v = np.concatenate([th, O.real / self.size, O.imag / self.size], axis=1)
        # a part of the plan (``steps``) has the columns of its dyads only
        return v, disc[:, [c for c in self._branch_cols if c < disc.shape[1]]]

    def decide(self, t: float, signs, dyads, d: int) -> Crossing:
        """The signs after the change point ``t`` met moving in direction ``d``."""
        signs = tuple(signs)
        # a revolute input's closed form is periodic in it: the same change point one
        # turn on is decided alike (a rotating crank meets each one every turn)
        tk = t if self.period is None else math.fmod(t - self.reference, self.period)
        key = (round(tk + (self.period if tk < 0 else 0.0) if self.period else tk, 9),
               signs, d)
        if key in self._decide_memo:
            c = self._decide_memo[key]
            return Crossing(t, c.joints, c.before, c.after, c.rule, c.jump)
        joints = tuple(self.dyad_joints[k] for k in dyads)
        if self.rule == "continuous" and (len(dyads) > _JOINT_DECISION
                                          or self._has_equal_rrr):
            c = self._decide_one_by_one(t, signs, dyads, d, joints)
            self._decide_memo[key] = c
            return c
        cands = []
        for flip in itertools.product((False, True), repeat=len(dyads)):
            s = list(signs)
            for k, f in zip(dyads, flip, strict=True):
                if f:
                    s[k] = -s[k]
            cands.append(tuple(s))
        switch = tuple(-s if k in dyads else s for k, s in enumerate(signs))
        # a step clear of the +-sqrt(TOGGLE_SNAP / curvature) where the closed form snaps
        # the dyad to its toggle (both candidates would look alike there)
        unit = 1.0 if self.revolute else self.size
        for h in unit * np.array([1e-4, 1e-3, 1e-2]):
            left, dl = self._pose(t - d * np.array([2 * h, h]), signs)
            if np.all(np.abs(dl[:, list(dyads)]) > 1e3 * TOGGLE_SNAP):
                break
        slope_l = (left[1] - left[0]) / h
        # the pose angles may wrap by 2 pi between the two samples: compare them unwrapped
        jumps = {}
        for c in cands:
            right, disc = self._pose(t + d * np.array([h, 2 * h]), c)
            if disc.size and np.any(disc < -TOGGLE_SNAP):
                continue
            dr = right[1] - right[0]
            dr[:len(self.topo.body_names)] = (dr[:len(self.topo.body_names)] + math.pi) \
                % (2 * math.pi) - math.pi
            jumps[c] = float(np.max(np.abs(dr / h - slope_l)))
        scale = max(float(np.max(np.abs(slope_l))), 1e-300)
        held_jump = jumps.get(signs, math.inf) / scale
        if self.rule == "hold" or not jumps:
            after, rule = signs, "hold"
        elif self.rule == "switch":
            after, rule = (switch if switch in jumps else signs), "switch"
        else:
            order = sorted(jumps, key=jumps.get)
            best = order[0]
            second = jumps[order[1]] if len(order) > 1 else math.inf
            if jumps[best] <= CONTINUITY_RATIO * second:
                after, rule = best, "velocity"
            else:
                after, rule = signs, "held: continuity cannot decide"
        c = Crossing(t, joints, signs, after, rule, 0.0 if after == signs else held_jump)
        self._decide_memo[key] = c
        return c

    def _decide_one_by_one(self, t: float, signs, dyads, d: int, joints) -> Crossing:
        """:meth:`decide` for many dyads touching at once (2^n combinations): each dyad,
        in the plan's order, takes the sign whose two bodies' poses continue with the
        velocity they had (a dyad places its bodies from bodies placed before it)."""
        B = len(self.topo.body_names)
        steps = [st for st in self.topo.plan if st.kind in BRANCHING]
        unit = 1.0 if self.revolute else self.size
        for h in unit * np.array([1e-4, 1e-3, 1e-2]):
            left, dl = self._pose(t - d * np.array([2 * h, h]), signs)
            if np.all(np.abs(dl[:, list(dyads)]) > 1e3 * TOGGLE_SNAP):
                break
        slope_l = (left[1] - left[0]) / h
        s = list(signs)
        rules = []
        # both signs of dyad k at once (samples 0, 1 held; 2, 3 the other), placed on
        # the bodies the dyads before it placed with their decided signs (its bodies'
        # poses depend on no later dyad): each step of the plan evaluated once
        right4 = t + d * np.array([h, 2 * h, h, 2 * h])
        p = Placement(4, B)
        plan = self.topo.plan
        ends = [i + 1 for i, st in enumerate(plan) if st.kind in BRANCHING]
        done = 0
        # every dyad, not only those found touching: past a change point the held
        # branch of a later dyad is not the linkage's (a folded rhombus window may sit
        # at zero base all along it), so its own touches say nothing
        for k in range(len(steps)):
            self.cf.place(p, right4, iter([np.array([1, 1, -1, -1]) * s[k]]),
                          plan[done:ends[k]])
            done = ends[k]
            cols = [c for b in steps[k].bodies for c in (b, B + b, 2 * B + b)]
            right = np.concatenate([p.theta, p.O.real / self.size, p.O.imag / self.size],
                                   axis=1)
            disc = p.discs[self._branch_cols[k]]
            jumps = []
            for r in (slice(0, 2), slice(2, 4)):
                dr = right[r][1] - right[r][0]
                dr[:B] = (dr[:B] + math.pi) % (2 * math.pi) - math.pi
                bad = np.any(disc[r] < -TOGGLE_SNAP)
                jumps.append(math.inf if bad else
                             float(np.max(np.abs(dr[cols] / h - slope_l[cols]))))
            flip = jumps[1] < CONTINUITY_RATIO * jumps[0]
            _keep(p, (2, 3) if flip else (0, 1))
            if flip:
                s[k], rule = -s[k], "velocity"
            else:
                rule = "velocity" if jumps[0] <= CONTINUITY_RATIO * jumps[1] else \
                    "held: continuity cannot decide"
            if k in dyads or s[k] != signs[k]:
                rules.append(rule)
        rule = "velocity" if all(r == "velocity" for r in rules) else \
            "held: continuity cannot decide"
        jump = 0.0
        if tuple(s) != tuple(signs):  # what holding every sign would have cost
            right, _ = self._pose(t + d * np.array([h, 2 * h]), signs)
            dr = right[1] - right[0]
            dr[:B] = (dr[:B] + math.pi) % (2 * math.pi) - math.pi
            scale = max(float(np.max(np.abs(slope_l))), 1e-300)
            jump = float(np.max(np.abs(dr / h - slope_l))) / scale
        # the dyads met here: those found touching, and those whose sign the continuity
        # switched (a later window of the N four-bar, flat at the same input but found
        # ~1e-3 away on the held signs, where it folds onto its base)
        joints = tuple(self.dyad_joints[k] for k in range(len(steps))
                       if k in dyads or s[k] != signs[k])
        return Crossing(t, joints, tuple(signs), tuple(s), rule, jump)

    # --- the walk -----------------------------------------------------------------
    def _next(self, x: float, signs, d: int):
        """The next change point of branch ``signs`` strictly beyond ``x`` in
        direction ``d``: ``(value, dyads)`` or ``None``."""
        tp = self.touches(signs)
        if not tp:
            return None
        eps = 1e-9 * (1.0 if self.revolute else self.size)
        if self.period is None:
            c = [(v, k) for v, k in tp if (v - x) * d > eps]
            return (min(c, key=lambda t: abs(t[0] - x))) if c else None
        P = self.period
        best = None
        for v, k in tp:
            n = math.floor((x - v) / P) + (1 if d > 0 else 0)
            for m in (n - 1, n, n + 1):
                w = v + m * P
                if (w - x) * d > eps and (best is None or abs(w - x) < abs(best[0] - x)):
                    best = (w, k)
        return best

    def walk(self, lo: float, hi: float):
        """Segments ``[(a, b, signs)]`` covering ``[min(lo, ref), max(hi, ref)]`` in
        increasing order, and the change points crossed (:class:`Crossing`, in the
        order met going outward from the reference)."""
        segs_up, segs_dn, crossings = [], [], []
        for d, end, segs in ((1, hi, segs_up), (-1, lo, segs_dn)):
            x, s = self.reference, self.signs0
            guard = 0
            # a reference on a change point: the signs are the assembly's going up; going
            # down the change point at the reference itself is decided like any other, so
            # the branch is smooth through the reference (not kinked there)
            eps = 1e-9 * (1.0 if self.revolute else self.size)
            while (end - x) * d > 0:
                probe = x + 2 * eps if (d < 0 and guard == 0) else x
                nx = self._next(probe, s, d)
                if nx is None or (nx[0] - end) * d >= 0:
                    segs.append((x, end, s))
                    break
                c = self.decide(nx[0], s, nx[1], d)
                crossings.append(c)
                segs.append((x, nx[0], s))
                x, s = nx[0], c.after
                guard += 1
                if guard > 100000:
                    raise RuntimeError("branch schedule: too many change points")
        out = [(min(a, b), max(a, b), s) for a, b, s in segs_dn[::-1]] + \
            [(a, b, s) for a, b, s in segs_up]
        if not out:
            out = [(self.reference, self.reference, self.signs0)]
        return out, crossings

    def signs_for(self, values: np.ndarray):
        """The dyad signs at each input value: ``(combos, index (N,))``."""
        values = np.asarray(values, float)
        if self.constant:
            return [self.signs0], np.zeros(len(values), int)
        segs, _ = self.walk(float(np.min(values)), float(np.max(values)))
        starts = np.array([a for a, _, _ in segs])
        k = np.clip(np.searchsorted(starts, values, side="right") - 1, 0, len(segs) - 1)
        combos, idx = [], np.empty(len(values), int)
        for i, seg in enumerate(segs):
            sel = k == i
            if not sel.any():
                continue
            if seg[2] not in combos:
                combos.append(seg[2])
            idx[sel] = combos.index(seg[2])
        return combos, idx

    def crossings(self, lo: float, hi: float) -> list[Crossing]:
        """The change points passed moving from the reference to ``lo`` and to ``hi``."""
        if self.constant:
            return []
        return self.walk(lo, hi)[1]
