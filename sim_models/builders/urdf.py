"""URDF (for PyBullet) of a :class:`~analytic.mechanism.Mechanism`, written with ``xml.etree``.

URDF describes trees only, so the model is the simulation tree of
:class:`sim_models.builders.tree.SimTree` (the analytic spanning tree with prismatic
joints preferred) plus a list of :class:`Closure` records, one per
loop-closing revolute joint, to be added at run time as PyBullet
``JOINT_POINT2POINT`` constraints.

* The first link is the ground, the root: load it with ``useFixedBase=True``.
  Its link frame is the world frame.
* A URDF joint axis passes through its child link's frame origin, so the link
  frame of a moving body sits at the point of its tree joint (the pin, the
  slider point, or the guide's line origin), with the body's orientation; at
  ``q = 0`` every body is at its reference pose (tree joint coordinates as in
  :mod:`sim_models.builders.tree`).
* ``continuous`` joints about z, ``prismatic`` joints along the line.  URDF
  requires a ``<limit>`` on a prismatic joint; it is written with
  ``lower="1" upper="-1"``, which PyBullet reads as "no limit" (checked: the
  sliders of every built-in case travel freely and match the analytic
  accelerations).
* ``<inertial>`` blocks (load with ``URDF_USE_INERTIA_FROM_FILE``) with
  ``ixx = iyy = I/2, izz = I`` (a plane lamina); massless bodies get the
  mass floor of :mod:`sim_models.builders.tree`.  No ``<collision>``; thin ``box``
  visuals along the bodies for the GUI.
* Closure pivots are given in each link's **centre-of-mass frame** (what
  ``createConstraint`` expects for multibody links): ``point - com`` in body
  axes; the ground's centre-of-mass frame is the world frame.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from analytic import Mechanism

from .model_numbers import model_number, model_value
from .tree import SimTree, _rot


@dataclass(frozen=True)
class Closure:
    """A loop-closing revolute joint for ``createConstraint(JOINT_POINT2POINT)``.

    ``parent_link`` is body_a and ``child_link`` body_b of the joint; pivots in
    the links' centre-of-mass frames (m, 3-vectors).
    """

    joint: str
    parent_link: str
    child_link: str
    parent_pivot: tuple[float, float, float]
    child_pivot: tuple[float, float, float]


def _f(x: float) -> str:
    """A quantity that is never round-off of a zero (mass, inertia, box size)."""
    return model_number(x, 0.0)


def link_offsets(st: SimTree) -> dict[int, np.ndarray]:
    """Body-frame position of each body's URDF link frame (ground: origin)."""
    off = {st.ground: np.zeros(2)}
    for tj in st.joints:
        off[tj.child] = np.asarray(tj.anchor_child, float)
    return off


def build_urdf(mech: Mechanism, tree: SimTree | None = None) -> tuple[str, list[Closure]]:
    """The URDF text and the loop closures of ``mech`` (see module docstring)."""
    st = tree or SimTree(mech)
    names = st.body_names
    off = link_offsets(st)
    robot = ET.Element("robot", name=mech.name)
    width = 0.01 * st.size

    def xyz(v) -> str:  # a position, m: round-off relative to the mechanism's size
        return " ".join(model_number(x, st.size) for x in v)

    def rpy(yaw: float) -> str:  # a rotation about z, rad
        return f"0 0 {model_number(yaw)}"


    def link(b: int):
        lk = ET.SubElement(robot, "link", name=names[b])
        o = off[b]
        if b == st.ground:
            ine = ET.SubElement(lk, "inertial")
            ET.SubElement(ine, "origin", xyz="0 0 0", rpy="0 0 0")
            ET.SubElement(ine, "mass", value="0")
            ET.SubElement(ine, "inertia", ixx="0", ixy="0", ixz="0", iyy="0", iyz="0", izz="0")
        else:
            c = st.com[b] - o
            ine = ET.SubElement(lk, "inertial")
            ET.SubElement(ine, "origin", xyz=xyz((c[0], c[1], 0.0)), rpy="0 0 0")
            ET.SubElement(ine, "mass", value=_f(st.mass[b]))
            # a lamina: ixx + iyy = izz exactly.  izz is written as twice the rounded
            # ixx (exact in binary): rounded on its own it could exceed ixx + iyy, and
            # PyBullet then does not use the file's inertia (measured: joint forces off
            # by 20% of peak on the seed four-bar with izz rounded separately)
            half = _f(float(st.inertia[b]) / 2)
            ET.SubElement(ine, "inertia", ixx=half, ixy="0", ixz="0", iyy=half, iyz="0",
                          izz=repr(2.0 * float(half)))
        pts = [np.asarray(p, float) - o for p in mech.bodies[b].points.values()]
        for p, q in zip(pts[:-1], pts[1:], strict=True):
            L = float(np.hypot(*(q - p)))
            if L < 1e-12:
                continue
            m = (p + q) / 2
            vis = ET.SubElement(lk, "visual")
            ET.SubElement(vis, "origin", xyz=xyz((m[0], m[1], 0.0)),
                          rpy=rpy(math.atan2(q[1] - p[1], q[0] - p[0])))
            geo = ET.SubElement(vis, "geometry")
            ET.SubElement(geo, "box", size=" ".join(_f(x) for x in (L, width, width)))

    link(st.ground)
    for tj in st.joints:
        link(tj.child)
    for tj in st.joints:
        p, c = tj.parent, tj.child
        # child link frame relative to the parent link frame, at the reference
        Pc = st.origin_ref[c] + _rot(st.theta_ref[c]) @ off[c]
        Pp = st.origin_ref[p] + _rot(st.theta_ref[p]) @ off[p]
        rel = _rot(st.theta_ref[p]).T @ (Pc - Pp)
        kind = "continuous" if tj.kind == "hinge" else "prismatic"
        j = ET.SubElement(robot, "joint", name=tj.name, type=kind)
        ET.SubElement(j, "origin", xyz=xyz((rel[0], rel[1], 0.0)),
                      rpy=rpy(tj.rel_angle))
        ET.SubElement(j, "parent", link=names[p])
        ET.SubElement(j, "child", link=names[c])
        if tj.kind == "hinge":
            ET.SubElement(j, "axis", xyz="0 0 1")
        else:
            ET.SubElement(j, "axis", xyz=" ".join(model_number(x) for x in (*tj.axis_child, 0.0)))
            ET.SubElement(j, "limit", lower="1", upper="-1", effort="1e30", velocity="1e30")
        ET.SubElement(j, "dynamics", damping="0", friction="0")
    ET.indent(robot)
    text = ET.tostring(robot, encoding="unicode", xml_declaration=True)

    closures = []
    for ch in st.chords:
        pa = ch.point_a - (st.com[ch.body_a] if ch.body_a != st.ground else 0.0)
        pb = ch.point_b - (st.com[ch.body_b] if ch.body_b != st.ground else 0.0)
        closures.append(Closure(ch.name, names[ch.body_a], names[ch.body_b],
                                (model_value(pa[0], st.size), model_value(pa[1], st.size), 0.0),
                                (model_value(pb[0], st.size), model_value(pb[1], st.size), 0.0)))
    return text, closures
