"""Structure of a mechanism: unknowns, spanning tree, vector loops, dyad plan.

Everything here depends only on the description, never on the input value, so
it is computed once and reused for every crank angle.

Unknowns of the vector-loop method
----------------------------------
Bodies joined by a prismatic joint rotate together (the slider keeps a constant
angle to its guide), so bodies fall into *rotation groups*; a body's angle is
``theta_b = theta_g + offset_b`` with ``theta_g`` its group's angle.  The ground
group's angle is 0.  The kinematic unknowns ``q`` are the angles of the moving
groups followed by the displacements ``s`` of the prismatic joints.

Vector loops
------------
Each independent loop (one per joint outside a spanning tree of the joint
graph, or as given by the user) is a closed polygon of vectors: inside a body,
the vector from the joint it is entered by to the joint it is left by,
``r mu(theta_g + beta)``; across a prismatic joint, ``+-s mu(theta_guide +
direction)``; across a revolute joint, nothing.  The loop equation is the sum of
the vectors = 0, two scalar equations per loop.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .errors import DescriptionError
from .mechanism import Mechanism, Prismatic, Revolute
from .planar import rotation


@dataclass(frozen=True)
class LoopTerms:
    """The vectors of all loops as flat arrays (one entry per vector, T in all).

    A vector is ``m mu(phi)`` with ``phi = theta[group] + beta`` and
    ``m = r + sign * s[slider]``; ``group == -1`` means ground (theta = 0),
    ``slider == -1`` means a constant-length vector (then ``sign`` is 0).
    """

    loop: np.ndarray    # (T,) loop index
    group: np.ndarray   # (T,) group variable index or -1
    beta: np.ndarray    # (T,) rad
    r: np.ndarray       # (T,) m
    slider: np.ndarray  # (T,) prismatic index or -1
    sign: np.ndarray    # (T,) +1/-1 for slider vectors, 0 otherwise


#: Plan steps with two assemblies (a branch sign each, in the plan's order).
BRANCHING = ("RRR", "RRP", "RPR", "driven_RRR")
#: Plan steps whose closed form reports a discriminant (:meth:`ClosedForm.run`'s
#: columns, in the plan's order): the branching ones and PRP (its two guides must cross).
WITH_DISCRIMINANT = (*BRANCHING, "PRP")


@dataclass(frozen=True)
class DyadStep:
    """One closed-form step: bodies whose poses follow from already known ones.

    ``kind`` is one of ``driven_revolute``, ``driven_prismatic``, ``RRR``,
    ``RRP``, ``RPR``, ``PRP`` (the dyad types, named by their joints from the
    first known body to the second), or ``driven_RRR``.  ``bodies`` are the one or
    two bodies placed; ``joints`` the joints used, in order along the chain.

    ``driven_RRR`` is a revolute driver between two moving bodies (a coupler joint of
    a four-bar loop): bodies ``(u, w, v)`` and joints ``(j1, j2, j3, jd)``, where
    ``u`` turns on a known body at ``j1``, ``w`` on a known body at ``j3``, ``v``
    joins ``u`` at the driver ``jd`` and ``w`` at ``j2``.  With the driver's angle
    known, ``u`` and ``v`` are one rigid body, a virtual link from ``j1`` to ``j2``:
    an RRR dyad with ``w`` (one branch sign; ``j2`` its inner joint).
    """

    kind: str
    bodies: tuple[int, ...]
    joints: tuple[int, ...]


@dataclass
class Topology:
    """Index tables derived from a :class:`Mechanism` (see module docstring)."""

    mech: Mechanism
    body_names: list[str]
    ground: int
    joint_names: list[str]
    group_of: np.ndarray          # (B,) group variable index, -1 for ground group
    offset: np.ndarray            # (B,) theta_b - theta_group, rad
    n_groups: int
    prismatic: list[int]          # joint indices of the prismatic joints
    slider_index: dict[int, int]  # joint index -> index in s
    tree: list[int]               # joint indices of the spanning tree
    chords: list[int]             # joint indices closing the loops
    parent: dict[int, tuple[int, int]]  # body -> (parent body, tree joint)
    order: list[int]              # bodies in tree order, ground first
    subtree: np.ndarray           # (n_tree, B) bool: body in child side of tree joint
    tree_child: list[int]         # child body of each tree joint
    loops: list[list[tuple[int, int, int]]]  # per loop: (body, joint_in, joint_out)
    terms: LoopTerms
    driver_joint: int
    driver_row: np.ndarray        # (nq,) coefficients c with c.q = value + driver_const
    driver_const: float
    driven_var: int | None        # variable fixed by the driver when it is a unit row
    plan: list[DyadStep] | None   # closed-form position plan, None when not decomposable
    body_points: list[dict[str, np.ndarray]] = field(default_factory=list)

    @cached_property
    def group_leader(self) -> list[int]:
        """One body index per moving rotation group, in group order."""
        return [int(np.flatnonzero(self.group_of == g)[0]) for g in range(self.n_groups)]

    @property
    def nq(self) -> int:
        return self.n_groups + len(self.prismatic)

    @property
    def n_loops(self) -> int:
        return len(self.loops)

    def attach(self, j: int, b: int) -> np.ndarray:
        """Body-frame point (m) where joint ``j`` attaches to body ``b``."""
        jt = self.mech.joints[j]
        name = self.body_names[b]
        pn = jt.point_a if jt.body_a == name else jt.point_b
        return self.body_points[b][pn]

    def other(self, j: int, b: int) -> int:
        jt = self.mech.joints[j]
        a, c = self.body_names.index(jt.body_a), self.body_names.index(jt.body_b)
        return c if b == a else a


def spanning_tree(mech: Mechanism, priority: list[int]):
    """A spanning tree of the joint graph, taking joints in ``priority`` order
    (Kruskal): the joints that would close a cycle are the chords.

    Returns ``(tree, chords, parent, order)``: tree and chord joint indices, ``parent``
    mapping each moving body to ``(parent body, tree joint)`` and ``order`` the bodies
    breadth-first from ground (children in ``priority`` order).
    """
    names = [b.name for b in mech.bodies]
    idx = {n: i for i, n in enumerate(names)}
    g0 = idx[mech.ground]
    joints = mech.joints
    uf = list(range(len(names)))

    def root(b):
        while uf[b] != b:
            uf[b] = uf[uf[b]]
            b = uf[b]
        return b

    tree, chords = [], []
    for k in priority:
        a, b = idx[joints[k].body_a], idx[joints[k].body_b]
        ra, rb = root(a), root(b)
        if ra == rb:
            chords.append(k)
        else:
            uf[ra] = rb
            tree.append(k)
    rank = {k: i for i, k in enumerate(priority)}
    adj = {b: [] for b in range(len(names))}
    for k in sorted(tree, key=rank.get):
        a, b = idx[joints[k].body_a], idx[joints[k].body_b]
        adj[a].append((b, k))
        adj[b].append((a, k))
    parent, order, queue = {}, [g0], [g0]
    while queue:
        p = queue.pop(0)
        for c, k in adj[p]:
            if c not in parent and c != g0:
                parent[c] = (p, k)
                order.append(c)
                queue.append(c)
    return tree, chords, parent, order


def build_topology(mech: Mechanism) -> Topology:
    """Derive groups, unknowns, spanning tree, loops and the dyad plan (in that order,
    one phase each; the driver's row last, after the loop terms)."""
    names = [b.name for b in mech.bodies]
    idx = {n: i for i, n in enumerate(names)}
    g0 = idx[mech.ground]
    B = len(names)
    joints = mech.joints
    jidx = {j.name: k for k, j in enumerate(joints)}
    body_points = [{k: np.asarray(v, float) for k, v in b.points.items()} for b in mech.bodies]
    group_of, offset, n_groups = _rotation_groups(mech, idx)
    prismatic = [k for k, j in enumerate(joints) if isinstance(j, Prismatic)]
    slider_index = {k: i for i, k in enumerate(prismatic)}
    nq = n_groups + len(prismatic)
    # spanning tree (driver joint first)
    dj = jidx[mech.driver.joint]
    tree, chords, parent, order = spanning_tree(
        mech, [dj] + [k for k in range(len(joints)) if k != dj])
    tree = [parent[b][1] for b in order[1:]]  # tree joints in tree order
    tree_child = order[1:]
    subtree = _subtrees(tree_child, parent, B, g0)
    loops = _loops(mech, idx, jidx, chords, parent, g0)
    topo = Topology(
        mech=mech, body_names=names, ground=g0, joint_names=[j.name for j in joints],
        group_of=group_of, offset=offset, n_groups=n_groups, prismatic=prismatic,
        slider_index=slider_index, tree=tree, chords=chords, parent=parent, order=order,
        subtree=subtree, tree_child=tree_child, loops=loops, terms=None,  # type: ignore
        driver_joint=dj, driver_row=np.zeros(nq), driver_const=0.0, driven_var=None,
        plan=None, body_points=body_points)
    topo.terms = _loop_terms(topo)
    topo.driver_row, topo.driver_const = _driver_row(topo, idx, nq)
    nz = np.flatnonzero(topo.driver_row)
    if len(nz) == 1:
        topo.driven_var = int(nz[0])
    topo.plan = _dyad_plan(topo)
    return topo


def _rotation_groups(mech: Mechanism, idx: dict[str, int]):
    """Bodies that cannot rotate relative to each other (joined by prismatic joints) form
    a rotation group (union-find with angle offsets): ``group_of`` (B,) the group's
    unknown (-1: the ground's group), ``offset`` (B,) rad with theta_b = theta_group +
    offset_b, and the number of groups."""
    B = len(mech.bodies)
    g0 = idx[mech.ground]
    leader = list(range(B))
    off = [0.0] * B  # theta_b = theta_leader + off_b

    def find(b):
        if leader[b] == b:
            return b, 0.0
        r, o = find(leader[b])
        leader[b], off[b] = r, off[b] + o
        return r, off[b]

    for j in mech.joints:
        if isinstance(j, Prismatic):
            ga, oa = find(idx[j.guide])
            gb, ob = find(idx[j.slider])
            if ga == gb:
                raise DescriptionError(
                    f"prismatic joint {j.name!r} joins bodies that already cannot rotate "
                    "relative to each other (a loop of prismatic joints)", mech.source)
            # theta_slider = theta_guide + angle  ->  attach slider's root to guide's root;
            # keep the ground's group as root.
            if gb == find(g0)[0]:
                leader[ga], off[ga] = gb, ob - j.angle - oa
            else:
                leader[gb], off[gb] = ga, oa + j.angle - ob
    roots = {}
    group_of = np.full(B, -1)
    offset = np.zeros(B)
    groot = find(g0)[0]
    for b in range(B):
        r, o = find(b)
        offset[b] = o - (find(g0)[1] if r == groot else 0.0)
        if r == groot:
            group_of[b] = -1
        else:
            group_of[b] = roots.setdefault(r, len(roots))
    return group_of, offset, len(roots)


def _subtrees(tree_child, parent, B: int, g0: int) -> np.ndarray:
    """(tree joints, B) bool: the bodies on the child's side of each tree joint."""
    subtree = np.zeros((len(tree_child), B), bool)
    for t, c in enumerate(tree_child):
        for b in range(B):
            x = b
            while x != g0:
                if x == c:
                    subtree[t, b] = True
                    break
                x = parent[x][0]
    return subtree


def _loops(mech: Mechanism, idx, jidx, chords, parent, g0: int):
    """The loops as closed walks ``[(body, joint in, joint out), ...]``: the
    description's own (checked against the joint graph's count), else one per chord
    through the tree."""
    joints = mech.joints
    loops: list[list[tuple[int, int, int]]] = []
    if mech.loops is not None:
        for lp in mech.loops:
            loops.append(_user_loop(mech, lp, idx, jidx))
        if len(loops) != len(chords):
            raise DescriptionError(
                f"{len(loops)} loops given but the joint graph has {len(chords)} independent "
                "loops (joints - bodies + 1)", mech.source)
        return loops

    def path_to_root(b):
        out = [b]
        while b != g0:
            b = parent[b][0]
            out.append(b)
        return out

    for k in chords:
        a, b = idx[joints[k].body_a], idx[joints[k].body_b]
        pa, pb = path_to_root(a), path_to_root(b)
        common = next(x for x in pa if x in pb)
        # chain of bodies: b -> ... -> common -> ... -> a, then chord a -> b.
        chain = pb[:pb.index(common) + 1] + list(reversed(pa[:pa.index(common)]))
        jchain = []
        for u, v in itertools.pairwise(chain):
            jchain.append(parent[u][1] if parent.get(u, (None,))[0] == v else parent[v][1])
        # closed walk: body chain[i] entered by jin, left by jout
        seq = []
        n = len(chain)
        for i, body in enumerate(chain):
            jin = k if i == 0 else jchain[i - 1]
            jout = k if i == n - 1 else jchain[i]
            seq.append((body, jin, jout))
        loops.append(seq)
    return loops


def _driver_row(topo: Topology, idx, nq: int):
    """The driver's equation over the unknowns q: ``row . q = value + const``."""
    dj_ = topo.mech.joints[topo.driver_joint]
    group_of, offset = topo.group_of, topo.offset
    row = np.zeros(nq)
    const = 0.0
    if isinstance(dj_, Revolute):
        a, b = idx[dj_.body_a], idx[dj_.body_b]
        if group_of[a] == group_of[b]:
            raise DescriptionError(
                f"driver joint {dj_.name!r} joins bodies that cannot rotate relative to each "
                "other", topo.mech.source)
        # theta_b - theta_a = value  ->  q_gb - q_ga = value + off_a - off_b
        if group_of[b] >= 0:
            row[group_of[b]] += 1.0
        if group_of[a] >= 0:
            row[group_of[a]] -= 1.0
        const = offset[a] - offset[b]
    else:
        row[topo.n_groups + topo.slider_index[topo.driver_joint]] = 1.0
    return row, const


def _user_loop(mech, lp, idx, jidx):
    where = f"{mech.source}: loop {list(lp)}" if mech.source else f"loop {list(lp)}"
    if len(lp) < 2:
        raise DescriptionError("a loop needs at least two joints", where)
    for n in lp:
        if n not in jidx:
            raise DescriptionError(f"unknown joint {n!r}", where)
    js = [mech.joints[jidx[n]] for n in lp]
    seq = []
    for i, jt in enumerate(js):
        nxt = js[(i + 1) % len(js)]
        shared = set(jt.bodies) & set(nxt.bodies)
        if len(shared) != 1:
            raise DescriptionError(f"joints {jt.name!r} and {nxt.name!r} do not share exactly "
                                   "one body", where)
        seq.append((idx[shared.pop()], jidx[jt.name], jidx[nxt.name]))
    return seq


def _loop_terms(topo: Topology) -> LoopTerms:
    joints = topo.mech.joints
    L, G, BETA, R, S, SG = [], [], [], [], [], []
    for li, seq in enumerate(topo.loops):
        for body, jin, jout in seq:
            # vector inside the body, from the joint entered by to the joint left by
            c = topo.attach(jout, body) - topo.attach(jin, body)
            c = rotation(topo.offset[body]) @ c
            r = float(np.hypot(*c))
            if r > 0:
                L.append(li)
                G.append(topo.group_of[body])
                BETA.append(math.atan2(c[1], c[0]))
                R.append(r)
                S.append(-1)
                SG.append(0.0)
            # across the joint left by, if prismatic: guide origin -> slider point = +s u
            jt = joints[jout]
            if isinstance(jt, Prismatic):
                gb = topo.body_names.index(jt.guide)
                sign = 1.0 if body == gb else -1.0
                L.append(li)
                G.append(topo.group_of[gb])
                BETA.append(topo.offset[gb] + jt.direction)
                R.append(0.0)
                S.append(topo.slider_index[jout])
                SG.append(sign)
    return LoopTerms(np.array(L, int), np.array(G, int), np.array(BETA), np.array(R),
                     np.array(S, int), np.array(SG))


def _dyad_plan(topo: Topology) -> list[DyadStep] | None:
    """Order the bodies into closed-form steps (driven link, then dyads)."""
    mech = topo.mech
    joints = mech.joints
    names = topo.body_names
    B = len(names)
    known = {topo.ground}
    steps: list[DyadStep] = []
    body_joints = {x: [k for k, j in enumerate(joints) if names[x] in j.bodies]
                   for x in range(B)}
    first = _driven_first(topo, known, body_joints)
    if first is None:
        return None
    steps.append(first)
    known.update(first.bodies)
    used = set(first.joints)

    def jtype(k):
        return "R" if isinstance(joints[k], Revolute) else "P"

    while len(known) < B:
        found = None
        for j2, jt in enumerate(joints):
            if j2 in used:
                continue
            b1, b2 = names.index(jt.body_a), names.index(jt.body_b)
            if b1 in known or b2 in known:
                continue
            for x1, x2 in ((b1, b2), (b2, b1)):
                j1s = [k for k in body_joints[x1] if k != j2 and k not in used
                       and topo.other(k, x1) in known]
                j3s = [k for k in body_joints[x2] if k != j2 and k not in used
                       and topo.other(k, x2) in known]
                for j1 in j1s:
                    for j3 in j3s:
                        if j1 == j3:
                            continue
                        kind = jtype(j1) + jtype(j2) + jtype(j3)
                        if kind == "PRR":  # mirror to RRP
                            x1, x2, j1, j3 = x2, x1, j3, j1
                            kind = "RRP"
                        if kind in ("RRR", "RRP", "RPR", "PRP"):
                            found = DyadStep(kind, (x1, x2), (j1, j2, j3))
                            break
                    if found:
                        break
                if found:
                    break
            if found:
                break
        if found is None:
            return None
        steps.append(found)
        known.update(found.bodies)
        used.update(found.joints)
    return steps


def _driven_first(topo: Topology, known: set, body_joints) -> DyadStep | None:
    """The plan's first step: the driven link (a driver on a known body), else a
    ``driven_RRR`` (a revolute driver between two moving bodies that close a four-bar
    loop with the ground: see :class:`DyadStep`), else None (no closed form)."""
    joints, names = topo.mech.joints, topo.body_names
    dj = topo.driver_joint
    a, b = names.index(joints[dj].body_a), names.index(joints[dj].body_b)
    if a in known or b in known:
        if topo.driven_var is None:
            return None
        kind = "driven_revolute" if isinstance(joints[dj], Revolute) else "driven_prismatic"
        return DyadStep(kind, (b if a in known else a,), (dj,))
    if not isinstance(joints[dj], Revolute):
        return None

    def pins(x, to):  # revolute joints of body x (not the driver) whose other body is ``to``
        return [k for k in body_joints[x] if k != dj and isinstance(joints[k], Revolute)
                and to(topo.other(k, x))]

    for u, v in ((a, b), (b, a)):
        for j1 in pins(u, known.__contains__):
            for j2 in pins(v, lambda o, u=u: o not in known and o != u):
                w = topo.other(j2, v)
                for j3 in pins(w, known.__contains__):
                    if j3 != j2:
                        return DyadStep("driven_RRR", (u, w, v), (j1, j2, j3, dj))
    return None
