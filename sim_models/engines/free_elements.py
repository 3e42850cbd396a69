"""The harness's force elements of a released run, for the engines that do not build them
natively (:class:`ElementLoads`: point and joint springs and dampers, motors and constant
loads as world wrenches about each body's centre of mass, from the bodies' state)."""

from __future__ import annotations

import math

import numpy as np

from analytic import Revolute
from analytic.motion_spec import JointSpring, PointDamper, PointSpring

from ..builders.tree import SimTree


class ElementLoads:
    """The description's springs, dampers and motors as world wrenches about each
    body's centre of mass, from the bodies' state: what an engine without such an
    element has the harness apply every step.  Signs: :mod:`analytic.motion_spec`."""

    def __init__(self, tree: SimTree, x_offset: np.ndarray | None = None):
        self.tree = tree
        mech = tree.mech
        self.fm = mech.motion
        self.idx = {n: i for i, n in enumerate(tree.body_names)}
        self.jidx = {j.name: k for k, j in enumerate(mech.joints)}
        self.x0 = x_offset
        fm = self.fm
        self.any = bool(fm and (fm.springs or fm.dampers or fm.motors))
        self._x_last: dict[int, float] = {}

    @property
    def x0(self):
        return self._x0

    @x0.setter
    def x0(self, value) -> None:
        """The joint coordinates at the start (J,): revolute angles are followed
        continuously from them, step by step (a torsional spring on a joint that turns
        sees whole turns)."""
        self._x0 = value
        self._x_last = {}

    def motor_effort(self, t: float) -> float:
        """The sum of the motors' efforts at ``t`` (N m or N); NaN without a motor."""
        fm = self.fm
        if not (fm and fm.motors):
            return math.nan
        return float(sum(mo.at(t) for mo in fm.motors))

    def _joint_state(self, k: int, th, om, pt) -> tuple[float, float]:
        """Joint ``k``'s coordinate (continuous) and rate at one state."""
        jt = self.tree.mech.joints[k]
        if isinstance(jt, Revolute):
            a, b = self.idx[jt.body_a], self.idx[jt.body_b]
            d = th[b] - th[a]
            last = self._x_last.get(k, None if self._x0 is None else float(self._x0[k]))
            if last is not None:
                d += 2 * math.pi * round((last - d) / (2 * math.pi))
            self._x_last[k] = d
            return d, om[b] - om[a]
        g, sl = self.idx[jt.guide], self.idx[jt.slider]
        c, s_ = math.cos(th[g] + jt.direction), math.sin(th[g] + jt.direction)
        (px, py), (pvx, pvy) = pt(sl, jt.point)
        (ox, oy), (ovx, ovy) = pt(g, jt.origin)
        dx, dy = px - ox, py - oy
        return c * dx + s_ * dy, c * (pvx - ovx) + s_ * (pvy - ovy) + om[g] * (c * dy - s_ * dx)

    def wrenches(self, theta, omega, origin, v, t: float):
        """``(F (B, 2), M (B,))``: the elements' force on each body and its moment about
        the body's centre of mass (engine mass properties: ``tree.com``), N and N m, at
        one state (arrays with one row) and time ``t`` (scalar arithmetic: called every
        step by a harness that applies them)."""
        st, mech, fm = self.tree, self.tree.mech, self.fm
        B = len(st.body_names)
        F, M = np.zeros((B, 2)), np.zeros(B)
        if not self.any:
            return F, M
        th, om = theta[0].tolist(), omega[0].tolist()
        org, vo = origin[0].tolist(), v[0].tolist()
        cos, sin = math.cos, math.sin

        def pt(b, name):  # world position and velocity of a named point of body b
            px, py = mech.bodies[b].points[name]
            c, s_ = cos(th[b]), sin(th[b])
            rx, ry = c * px - s_ * py, s_ * px + c * py
            return ((org[b][0] + rx, org[b][1] + ry),
                    (vo[b][0] - om[b] * ry, vo[b][1] + om[b] * rx))

        def at(b, P, fx, fy):  # force (fx, fy) at world point P on body b
            cx, cy = st.com[b]
            c, s_ = cos(th[b]), sin(th[b])
            gx, gy = org[b][0] + c * cx - s_ * cy, org[b][1] + s_ * cx + c * cy
            F[b, 0] += fx
            F[b, 1] += fy
            M[b] += (P[0] - gx) * fy - (P[1] - gy) * fx

        effort: dict[int, float] = {}
        for el in fm.springs + fm.dampers:
            if isinstance(el, PointSpring | PointDamper):
                a, b = self.idx[el.body_a], self.idx[el.body_b]
                (ra, va), (rb, vb) = pt(a, el.point_a), pt(b, el.point_b)
                dx, dy = rb[0] - ra[0], rb[1] - ra[1]
                L = math.hypot(dx, dy)
                ux, uy = dx / L, dy / L
                tension = (el.stiffness * (L - el.free_length) if isinstance(el, PointSpring)
                           else el.coefficient * (ux * (vb[0] - va[0]) + uy * (vb[1] - va[1])))
                at(a, ra, tension * ux, tension * uy)
                at(b, rb, -tension * ux, -tension * uy)
            else:
                k = self.jidx[el.joint]
                x, xd = self._joint_state(k, th, om, pt)
                effort[k] = effort.get(k, 0.0) + (
                    -el.stiffness * (x - el.free_value) if isinstance(el, JointSpring)
                    else -el.coefficient * xd)
        for mo in fm.motors:
            k = self.jidx[mo.joint]
            effort[k] = effort.get(k, 0.0) + mo.at(t)
        for k, e in effort.items():
            jt = mech.joints[k]
            if isinstance(jt, Revolute):
                M[self.idx[jt.body_b]] += e
                M[self.idx[jt.body_a]] -= e
                continue
            g, sl = self.idx[jt.guide], self.idx[jt.slider]
            ux, uy = cos(th[g] + jt.direction), sin(th[g] + jt.direction)
            P, _ = pt(sl, jt.point)
            at(sl, P, e * ux, e * uy)
            at(g, P, -e * ux, -e * uy)
        F[st.ground], M[st.ground] = 0.0, 0.0
        return F, M


# ============================================================================ session


__all__ = ["ElementLoads"]
