"""The simulation tree shared by the MJCF and URDF builders and the engine drivers.

Both engines need a kinematic *tree* rooted at the ground plus loop-closing
constraints.  The tree is a spanning tree of the joint graph chosen like the
analytic one (:func:`analytic.topology.build_topology`: the driver joint first,
then the joints in description order, union-find, breadth-first from ground)
with two changes:

1. **prismatic joints are taken before revolute ones**, so that every loop is
   closed at a revolute joint (a point-to-point constraint, which both engines
   support).  A prismatic joint can only end up a chord when a loop consists of
   the driver and prismatic joints alone, which Gruebler's count rules out for a
   one-dof linkage; :class:`UnsupportedClosureError` names it should it happen.
2. with ``chords="moving"`` (the default) revolute joints on the ground are
   taken before the others, so loops close between two moving bodies where
   possible.  MuJoCo does not care (1e-7 of peak either way); PyBullet's loop
   forces do: at dt 1e-4 the seed four-bar closed at O4 (ground) gives pin
   forces 5e-4 and torque 1.5e-3 of peak, closed at B 4.5e-6 and 2.1e-6
   (six-bar 1.8e-3 vs 1.6e-4).  It is not universal: the inverted slider-crank
   and the quick-return are better closed at O4 (2e-4 vs 1.4e-3 at dt 1e-4).
   ``chords="analytic"`` keeps the analytic order (change 1 only).

Coordinates
-----------
Every body frame is placed at its pose in the *reference configuration* (the
analytic solution at the driver's reference value), so all joint coordinates
are 0 there.  Tree joint coordinates are relative:

* hinge ``q = (theta_child - theta_parent) - (its reference value)``;
* slide ``q = sigma (s - s_ref)`` with ``sigma = +1`` when the child is the
  slider and ``-1`` when the child is the guide.

The driver's coordinate is ``q_d = sigma_d (value - value_ref)`` with
``sigma_d = +1`` when the tree child of the driver joint is ``body_b``
(revolute) / the slider (prismatic).

Mass properties
---------------
Engines cannot integrate massless moving bodies.  A body with ``mass = 0`` gets
``MASS_FLOOR`` (1e-6) times the largest body mass and 1e-6 times the largest
inertia, at its stated centre of mass.  The extra inertia loads it adds,
``m_tiny |a_G|`` and ``I_tiny |alpha|``, are 1e-6 of those of a heavy body at the
same acceleration (zero for the seed slider-crank's crank, whose centre of mass
is on its fixed pivot and which turns at constant speed); they are below the
1e-4 agreement asked of the engines.  When a description has no masses at all
(kinematics-only cases), every moving body gets placeholder properties: 1 kg,
centre of mass at the centroid of its points, the inertia of a uniform rod as
long as the body's largest point distance (or of 1/10 of the mechanism's size
for a single-point body); forces are then engine-internal and not comparable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from analytic import Linkage, Mechanism, Prismatic, Revolute
from analytic.errors import LinkageError
from analytic.topology import spanning_tree

#: Mass of a massless body relative to the largest body mass (see module docstring).
MASS_FLOOR = 1e-6


class SimModelError(LinkageError):
    """A mechanism cannot be turned into an engine model."""


class UnsupportedClosureError(SimModelError):
    """A loop would have to be closed at a joint type the builders cannot close."""


def _rot(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


def _perp(v: np.ndarray) -> np.ndarray:
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


def wrap(a):
    """Angle(s) wrapped to (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(a, float), 2 * np.pi)


@dataclass(frozen=True)
class TreeJoint:
    """One joint of the simulation tree (all vectors in m, body frames)."""

    joint: int                 # index in mech.joints
    name: str
    kind: str                  # "hinge" or "slide"
    parent: int                # body index
    child: int                 # body index
    sigma: float               # +1: child is body_b / the slider, -1 otherwise
    anchor_parent: np.ndarray  # joint point in the parent frame (revolute) / parent's point
    anchor_child: np.ndarray   # joint point in the child frame
    axis_child: np.ndarray     # slide: unit axis in the child frame; hinge: (0, 0)
    rel_pos: np.ndarray        # child frame origin in the parent frame at the reference
    rel_angle: float           # theta_child - theta_parent at the reference, rad
    q_ref: float               # hinge: rel_angle; slide: s at the reference


@dataclass(frozen=True)
class Chord:
    """A loop-closing revolute joint: its point on body_a and on body_b."""

    joint: int
    name: str
    body_a: int
    body_b: int
    point_a: np.ndarray
    point_b: np.ndarray


class SimTree:
    """Tree, chords, reference poses and engine mass properties of a mechanism.

    Attributes
    ----------
    linkage : the analytic :class:`Linkage` (kinematics at the reference value)
    order : bodies, ground first, parents before children
    joints : :class:`TreeJoint` in ``order[1:]`` order (``joints[i].child == order[i+1]``)
    chords : :class:`Chord` list
    theta_ref, origin_ref : (B,), (B, 2) reference poses
    mass, com, inertia : (B,) kg, (B, 2) m, (B,) kg m^2 as given to the engines
    has_mass : whether the description gives masses (else placeholders)
    driver_tree : index into ``joints`` of the driven joint
    """

    def __init__(self, mech: Mechanism, linkage: Linkage | None = None,
                 chords: str = "moving"):
        if linkage is not None and linkage.mech is not mech:
            # the compiled Linkage travels with every run made from this tree: it must
            # be the one of this very description, not of another (or an equal copy)
            raise SimModelError(f"the Linkage given for {mech.name!r} was built from "
                                f"another description ({linkage.mech.name!r})")
        self.mech = mech
        self.linkage = linkage or Linkage(mech)
        self.chords_mode = chords
        self.body_names = [b.name for b in mech.bodies]
        self.ground = self.body_names.index(mech.ground)
        dj = [j.name for j in mech.joints].index(mech.driver.joint)
        self._spanning_tree(dj, chords)
        # reference poses
        kin = self.linkage.kinematics()
        self.kin_ref = kin
        self.theta_ref, self.origin_ref = kin.theta[0].copy(), kin.origin[0].copy()
        self.joints: list[TreeJoint] = [self._tree_joint(c) for c in self.order[1:]]
        self.chords: list[Chord] = [self._chord(k) for k in self.chord_indices]
        self.driver_tree = self.tree_joint_indices.index(dj)
        self.driver_sigma = self.joints[self.driver_tree].sigma
        self.prismatic = [k for k, j in enumerate(mech.joints) if isinstance(j, Prismatic)]
        self.has_mass = mech.has_mass
        self.size = self._size()
        self.mass, self.com, self.inertia = self._mass_properties()
        self.path = self._hinge_paths()

    def _spanning_tree(self, dj: int, chords: str) -> None:
        """``order``, ``parent``, ``tree_joint_indices``, ``chord_indices``: the tree
        takes the driver, then the prismatic joints, then the revolute ones (``chords
        == "moving"``: those at the ground first, so the loops close between moving
        bodies); a loop closed at a prismatic joint is refused."""
        mech, joints = self.mech, self.mech.joints
        rest = [k for k in range(len(joints)) if k != dj]
        rev = [k for k in rest if isinstance(joints[k], Revolute)]
        if chords == "moving":
            rev = [k for k in rev if mech.ground in joints[k].bodies] + \
                [k for k in rev if mech.ground not in joints[k].bodies]
        elif chords != "analytic":
            raise ValueError(f"chords must be 'moving' or 'analytic', got {chords!r}")
        cand = [dj] + [k for k in rest if isinstance(joints[k], Prismatic)] + rev
        _, chord_joints, parent, order = spanning_tree(mech, cand)
        for k in chord_joints:
            if isinstance(joints[k], Prismatic):
                raise UnsupportedClosureError(
                    f"mechanism {mech.name!r}: prismatic joint {joints[k].name!r} would close a "
                    "loop; the engine builders close loops at revolute joints only", mech.source)
        self.order = order
        self.parent = parent
        self.tree_joint_indices = [parent[c][1] for c in order[1:]]
        self.chord_indices = chord_joints

    def _tree_joint(self, c: int) -> TreeJoint:
        """The tree joint whose child is body ``c``, at the reference pose."""
        names, th, org = self.body_names, self.theta_ref, self.origin_ref
        topo = self.linkage.topo
        p, k = self.parent[c]
        jt = self.mech.joints[k]
        a_c = np.array(topo.attach(k, c), float)
        a_p = np.array(topo.attach(k, p), float)
        rel_pos = _rot(th[p]).T @ (org[c] - org[p])
        rel_angle = float(wrap(th[c] - th[p]))
        if isinstance(jt, Revolute):
            sigma = 1.0 if names[c] == jt.body_b else -1.0
            return TreeJoint(k, jt.name, "hinge", p, c, sigma, a_p, a_c, np.zeros(2), rel_pos,
                             rel_angle, rel_angle)
        gb = names.index(jt.guide)
        sigma = 1.0 if c == names.index(jt.slider) else -1.0
        u_world = _rot(th[gb]) @ np.array([math.cos(jt.direction), math.sin(jt.direction)])
        axis_c = _rot(th[c]).T @ u_world
        s_ref = float(self.kin_ref.slider(jt.name)[0][0])
        return TreeJoint(k, jt.name, "slide", p, c, sigma, a_p, a_c, axis_c, rel_pos,
                         rel_angle, s_ref)

    def _chord(self, k: int) -> Chord:
        """Loop-closing joint ``k``: its bodies and its point on each."""
        jt = self.mech.joints[k]
        pts = self.linkage.topo.body_points
        a, b = self.body_names.index(jt.body_a), self.body_names.index(jt.body_b)
        return Chord(k, jt.name, a, b, pts[a][jt.point_a].copy(), pts[b][jt.point_b].copy())

    def _mass_properties(self):
        """(B,) mass, (B, 2) centre of mass, (B,) inertia as given to the engines: the
        description's (a zero mass or inertia floored at :data:`MASS_FLOOR` of the
        largest), or without masses in the description uniform bars as placeholders."""
        mech, B = self.mech, len(self.body_names)
        mass, com, inertia = np.zeros(B), np.zeros((B, 2)), np.zeros(B)
        if self.has_mass:
            mmax = max(b.mass for b in mech.moving_bodies)
            imax = max(b.inertia for b in mech.moving_bodies)
            if mmax <= 0:
                mmax, imax = 1.0, 1e-3 * self.size ** 2
            for i, b in enumerate(mech.bodies):
                if i == self.ground:
                    continue
                mass[i] = b.mass if b.mass > 0 else MASS_FLOOR * mmax
                inertia[i] = b.inertia if b.inertia > 0 else MASS_FLOOR * imax
                com[i] = b.com
        else:
            for i, b in enumerate(mech.bodies):
                if i == self.ground:
                    continue
                P = np.array(list(b.points.values()), float)
                c = P.mean(axis=0)
                L = max((np.linalg.norm(x - y) for x in P for y in P), default=0.0)
                if L <= 0:
                    L = 0.1 * self.size
                mass[i], com[i], inertia[i] = 1.0, c, L * L / 12
        return mass, com, inertia

    def _hinge_paths(self) -> np.ndarray:
        """(B, tree joints) ancestor hinge matrix: absolute theta_b = theta_ref_b + the
        sum of the hinge coordinates on its path to the ground."""
        B = len(self.body_names)
        path = np.zeros((B, len(self.joints)))
        pos_in_tree = {c: i for i, c in enumerate(self.order[1:])}
        for b in range(B):
            x = b
            while x != self.ground:
                i = pos_in_tree[x]
                if self.joints[i].kind == "hinge":
                    path[b, i] = 1.0
                x = self.parent[x][0]
        return path

    def _size(self) -> float:
        s = 0.0
        for b in self.mech.bodies:
            P = np.array(list(b.points.values()), float)
            if len(P) > 1:
                s = max(s, float(np.max(np.linalg.norm(P[:, None] - P[None], axis=-1))))
        return s if s > 0 else 1.0

    # ------------------------------------------------------------------------
    @property
    def tree_names(self) -> list[str]:
        return [j.name for j in self.joints]

    def analytic_chords(self) -> list[str]:
        """Loop-closing joints of the analytic tree (for the report)."""
        topo = self.linkage.topo
        return [topo.joint_names[k] for k in topo.chords]

    def coords(self, kin, order: int = 2):
        """Tree coordinates ``q, qd, qdd`` (N, nt) of an analytic :class:`Kinematics`."""
        N = kin.n
        nt = len(self.joints)
        q, qd, qdd = np.zeros((N, nt)), np.zeros((N, nt)), np.zeros((N, nt))
        for i, tj in enumerate(self.joints):
            p, c = tj.parent, tj.child
            if tj.kind == "hinge":
                if i == self.driver_tree:
                    q[:, i] = tj.sigma * (kin.value - self.mech.driver.value)
                else:
                    q[:, i] = wrap(kin.theta[:, c] - kin.theta[:, p] - tj.rel_angle)
                qd[:, i] = kin.omega[:, c] - kin.omega[:, p]
                qdd[:, i] = kin.alpha[:, c] - kin.alpha[:, p]
            else:
                s, sd, sdd = kin.slider(tj.name)
                q[:, i] = tj.sigma * (s - tj.q_ref)
                qd[:, i] = tj.sigma * sd
                qdd[:, i] = tj.sigma * sdd
        return q, qd, qdd

    def propagate(self, q, qd, qdd):
        """Body poses, rates and frame-origin accelerations from tree coordinates.

        Arrays ``(N, nt)`` in; ``theta, omega, alpha`` (N, B) and ``origin, v, a``
        (N, B, 2) out (world frame).
        """
        q, qd, qdd = (np.atleast_2d(np.asarray(x, float)) for x in (q, qd, qdd))
        N = q.shape[0]
        B = len(self.body_names)
        th = np.zeros((N, B))
        om = np.zeros((N, B))
        al = np.zeros((N, B))
        org = np.zeros((N, B, 2))
        v = np.zeros((N, B, 2))
        a = np.zeros((N, B, 2))
        g = self.ground
        th[:, g] = self.theta_ref[g]
        org[:, g] = self.origin_ref[g]

        # element by element the same arithmetic as _rot / _perp (bitwise the same
        # results), without stacking: this runs once per joint per call
        def rot(t, x):
            c, s = np.cos(t), np.sin(t)
            out = np.empty((len(t), 2))
            out[:, 0] = c * x[0] - s * x[1]
            out[:, 1] = s * x[0] + c * x[1]
            return out

        def _perp(v):
            out = np.empty_like(v)
            out[:, 0] = -v[:, 1]
            out[:, 1] = v[:, 0]
            return out

        for i, tj in enumerate(self.joints):
            p, c = tj.parent, tj.child
            wp, ap = om[:, p, None], al[:, p, None]
            if tj.kind == "hinge":
                th[:, c] = th[:, p] + tj.rel_angle + q[:, i]
                om[:, c] = om[:, p] + qd[:, i]
                al[:, c] = al[:, p] + qdd[:, i]
                r = rot(th[:, p], tj.anchor_parent)
                P, vP, aP = org[:, p] + r, v[:, p] + wp * _perp(r), \
                    a[:, p] + ap * _perp(r) - wp * wp * r
                rc = -rot(th[:, c], tj.anchor_child)
                wc, ac = om[:, c, None], al[:, c, None]
                org[:, c] = P + rc
                v[:, c] = vP + wc * _perp(rc)
                a[:, c] = aP + ac * _perp(rc) - wc * wc * rc
            else:
                th[:, c] = th[:, p] + tj.rel_angle
                om[:, c] = om[:, p]
                al[:, c] = al[:, p]
                u = rot(th[:, c], tj.axis_child)
                r = rot(th[:, p], tj.rel_pos) + q[:, i, None] * u
                sd, sdd = qd[:, i, None], qdd[:, i, None]
                org[:, c] = org[:, p] + r
                v[:, c] = v[:, p] + wp * _perp(r) + sd * u
                a[:, c] = a[:, p] + ap * _perp(r) - wp * wp * r + sdd * u \
                    + 2 * wp * sd * _perp(u)
        return th, om, al, org, v, a

    def point_world(self, theta, origin, b: int, c):
        """World position (N, 2) of body-frame point ``c`` of body ``b``."""
        t = theta[:, b]
        cs, sn = np.cos(t), np.sin(t)
        c = np.asarray(c, float)
        return origin[:, b] + np.stack([cs * c[0] - sn * c[1], sn * c[0] + cs * c[1]], -1)

    def driver_value(self, q_driver):
        """Driver value (rad or m) from the driver's tree coordinate."""
        return self.mech.driver.value + self.driver_sigma * np.asarray(q_driver)

    def driver_path(self, t):
        """Prescribed driver value, velocity, acceleration at times t (s)."""
        d = self.mech.driver
        t = np.asarray(t, float)
        return (d.value + d.velocity * t + 0.5 * d.acceleration * t * t,
                d.velocity + d.acceleration * t, np.full_like(t, d.acceleration))
