"""The notes' vector polygons of a linkage, and its unknowns loop by loop.

The solver's loops (:mod:`analytic.topology`) are rewritten the way the notes
draw them: links are numbered with the ground 1 and the moving bodies 2, 3, ...
in the solver's tree order (the driven link first), each loop vector ``r_k`` is
named after the link it lies in (a slider's variable vector after the slider),
the loop is walked so that the lowest-numbered moving link points away from
the joint that carries it, and it starts at the lowest-numbered vector: the
notes' ``r1 + r2 + r3 + r4 = 0`` for the four-bar, ``r2 + r3 + r4 = 0`` for the
slider-crank with ``r4`` the variable distance from the slider back to the crank
pivot.

A vector is ``r_k mu(theta_k)`` with ``theta_k = q_g + beta_k`` (``q_g`` the angle
of its rotation group, 0 for the ground) and ``r_k`` constant inside a body or
the slider displacement ``s`` across a prismatic joint.  Angles are rad and
lengths m here; :mod:`reports.explain.doc` converts to the file's units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from analytic.mechanism import Prismatic

TWO_PI = 2.0 * math.pi
PARALLEL_TOL = 1e-9
"""Two vector angles of one rotation group are parallel when their constant
difference is a multiple of pi to this many rad (they come from the same
rotation, so the difference is exact up to rounding of the description)."""


@dataclass(frozen=True)
class Var:
    """A vector-loop unknown: a rotation group's angle (``kind == 'g'``) or a
    prismatic joint's displacement (``kind == 's'``); ``q`` is its index in the
    solver's ``q``."""

    kind: str
    index: int
    q: int


@dataclass(frozen=True)
class LoopVector:
    """One vector of a loop polygon.

    ``label`` names it (``"3"`` -> ``r_3``); ``group``/``beta`` give its angle
    ``q_group + beta`` (``group == -1``: the ground); ``length`` is its constant
    length (m) or, for a slider vector (``slider >= 0``), unused (the length is
    the displacement).  ``tail``/``head`` name its end points, ``tail_at`` is
    ``(body index, point name)`` of its tail for the drawing.
    """

    label: str
    kind: str
    body: int
    group: int
    beta: float
    length: float
    slider: int
    tail: str
    head: str
    tail_at: tuple[int, str]

    @property
    def var_angle(self) -> bool:
        return self.group >= 0

    @property
    def var_length(self) -> bool:
        return self.slider >= 0


@dataclass
class Loop:
    """One loop polygon, its variables and the two unknowns it is solved for."""

    index: int             # the solver's loop index
    vectors: list[LoopVector]
    unknowns: list[Var]    # empty when the loop cannot be solved on its own
    rate_label: dict[int, str]  # group -> label of its first vector (theta-dot name)

    def group_vectors(self, g: int) -> list[LoopVector]:
        return [v for v in self.vectors if v.group == g]

    def slider_vectors(self, s: int) -> list[LoopVector]:
        return [v for v in self.vectors if v.slider == s]


@dataclass
class Polygons:
    """All loops of a linkage in the notes' form, in solving order."""

    numbers: dict[int, int]  # body index -> link number (ground 1)
    loops: list[Loop]
    coupled: list[int]       # solver loop indices that no 2-unknown order reaches
    driven: Var | None
    variables: list[Var]


def link_numbers(topo) -> dict[int, int]:
    """Ground 1, the moving bodies 2, 3, ... in the solver's tree order."""
    return {b: i + 1 for i, b in enumerate(topo.order)}


def variables(topo) -> list[Var]:
    out = [Var("g", g, g) for g in range(topo.n_groups)]
    out += [Var("s", i, topo.n_groups + i) for i in range(len(topo.prismatic))]
    return out


def _point_name(jt, body_name: str) -> str:
    return jt.point_a if jt.body_a == body_name else jt.point_b


def _raw_loop(topo, seq):
    """The solver's walk of one loop as ``(kind, body, angle offset, length, slider,
    tail, head, tail_at)`` items, in the solver's orientation."""
    mech = topo.mech
    out = []
    for body, jin, jout in seq:
        name = topo.body_names[body]
        c = topo.attach(jout, body) - topo.attach(jin, body)
        rr = float(np.hypot(*c))
        if rr > 0:
            beta = float(topo.offset[body]) + math.atan2(c[1], c[0])
            p_in = _point_name(mech.joints[jin], name)
            p_out = _point_name(mech.joints[jout], name)
            out.append(("body", body, beta, rr, -1, p_in, p_out, (body, p_in), (body, p_out)))
        jt = mech.joints[jout]
        if isinstance(jt, Prismatic):
            gb = topo.body_names.index(jt.guide)
            sb = topo.body_names.index(jt.slider)
            beta = float(topo.offset[gb]) + jt.direction
            si = topo.slider_index[jout]
            # guide origin -> slider point is +s u; walked from the slider side it is -s u
            if body == gb:
                out.append(("slider", sb, beta, 0.0, si, jt.origin, jt.point,
                            (gb, jt.origin), (sb, jt.point)))
            else:
                out.append(("slider", sb, beta + math.pi, 0.0, si, jt.point, jt.origin,
                            (sb, jt.point), (gb, jt.origin)))
    return out


def _orient(topo, seq, numbers):
    """True when the solver's walk is the notes' orientation: the lowest-numbered
    moving link in the loop is left by the joint that is not its tree parent."""
    cands = [(numbers[b], b, jin) for b, jin, jout in seq
             if b != topo.ground and float(np.hypot(*(topo.attach(jout, b)
                                                      - topo.attach(jin, b)))) > 0]
    if not cands:
        return True
    _, b, jin = min(cands)
    return topo.parent[b][1] == jin


def build_loop_vectors(topo, seq, numbers) -> list[LoopVector]:
    raw = _raw_loop(topo, seq)
    if not _orient(topo, seq, numbers):
        raw = [(k, b, beta + math.pi, rr, si, head, tail, hat, tat)
               for k, b, beta, rr, si, tail, head, tat, hat in reversed(raw)]
    used: dict[str, int] = {}
    vecs = []
    for kind, b, beta, rr, si, tail, head, tat, _ in raw:
        base = str(numbers[b])
        n = used.get(base, 0)
        used[base] = n + 1
        lab = base if n == 0 else base + "abcdefgh"[n]
        if kind == "slider":
            gb = topo.body_names.index(topo.mech.joints[topo.prismatic[si]].guide)
            group = int(topo.group_of[gb])
        else:
            group = int(topo.group_of[b])
        vecs.append(LoopVector(lab, kind, b, group, beta % TWO_PI, rr, si, tail, head, tat))
    # start at the lowest-numbered vector (the ground's r1 when there is one)
    k0 = min(range(len(vecs)), key=lambda i: (int("".join(c for c in vecs[i].label
                                                         if c.isdigit())), vecs[i].label))
    return vecs[k0:] + vecs[:k0]


def loop_vars(topo, vecs) -> list[Var]:
    out = []
    for v in vecs:
        if v.group >= 0:
            var = Var("g", v.group, v.group)
            if var not in out:
                out.append(var)
        if v.slider >= 0:
            var = Var("s", v.slider, topo.n_groups + v.slider)
            if var not in out:
                out.append(var)
    return out


def build_polygons(topo) -> Polygons:
    """Every loop in the notes' form, ordered so that each has two unknowns once
    the driver and the loops before it are known (the solver's order where that
    works)."""
    numbers = link_numbers(topo)
    allv = variables(topo)
    driven = allv[topo.driven_var] if topo.driven_var is not None else None
    known = {driven} if driven is not None else set()
    pending = list(range(topo.n_loops))
    built = {i: build_loop_vectors(topo, topo.loops[i], numbers) for i in pending}
    loops = []
    while pending:
        for i in pending:
            unk = [v for v in loop_vars(topo, built[i]) if v not in known]
            if len(unk) == 2:
                break
        else:
            break
        pending.remove(i)
        vecs = built[i]
        rates = {}
        for v in vecs:
            if v.group >= 0:
                rates.setdefault(v.group, v.label)
        loops.append(Loop(i, vecs, unk, rates))
        known.update(unk)
    for i in pending:
        vecs = built[i]
        rates = {}
        for v in vecs:
            if v.group >= 0:
                rates.setdefault(v.group, v.label)
        loops.append(Loop(i, vecs, [], rates))
    return Polygons(numbers, loops, pending, driven, allv)


# -- numbers of a configuration ----------------------------------------------------

def angle(v: LoopVector, q) -> float:
    """World angle of a vector, rad, in [0, 2 pi)."""
    return ((q[v.group] if v.group >= 0 else 0.0) + v.beta) % TWO_PI


def length(v: LoopVector, q, ng: int) -> float:
    """Length (m): constant, or the slider's displacement."""
    return float(q[ng + v.slider]) if v.slider >= 0 else v.length


def closure(loop: Loop, q, ng: int) -> complex:
    """The loop's residual ``sum r mu(theta)`` (m, complex)."""
    return sum(length(v, q, ng) * complex(math.cos(angle(v, q)), math.sin(angle(v, q)))
               for v in loop.vectors)


def parallel(a: float, b: float) -> bool:
    d = (a - b) % math.pi
    return min(d, math.pi - d) < PARALLEL_TOL
