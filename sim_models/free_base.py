"""Free motion in the engines: the released start, the harness's force elements, the
one readout and energy function, and the run loop every engine's free session shares
(issue 21; the result is :class:`sim_models.free_run.FreeEngineRun`).

A free session (:class:`FreeSession`, one per engine: :mod:`sim_models.mujoco_free`,
:mod:`sim_models.pybullet_free`, :mod:`sim_models.exudyn_free`) is built from the
compiled linkage (:class:`sim_models.tree.SimTree`) with no drive: no armature, no
prescribed motor, no drive constraint.  :func:`drive_free` releases it from the
reference's exact state at t = 0 (:func:`free_start`: every body's pose and rate,
mapped to the tree coordinates), steps it between the request's sample times
(:meth:`FreeSession.advance`, the loop :func:`time_free_steps` times) and reads it at
each sample (:meth:`FreeSession.read`: absolute body states, joint forces, the
engine's motor effort).  Joint coordinates, energies and loop gap then come from
:func:`free_readout`, the same function for every engine.

Conventions: those of :mod:`sim_models.free_run` (SI, world axes; a joint coordinate
is ``theta_b - theta_a`` continuous over turns, or the slider's displacement along
its line).
"""

from __future__ import annotations

import math
import time
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from analytic import Revolute
from analytic.free_motion import simulate
from analytic.motion_spec import JointSpring, PointDamper, PointSpring

from .engine_run import loop_gaps
from .engine_settings import EngineRefusal, EngineSettings
from .free_run import FreeEngineRun, FreeRequest
from .tree import SimTree, wrap


# ============================================================================ start
@dataclass(frozen=True)
class FreeStart:
    """The released state at t = 0: tree coordinates ``q, qd`` (nt,), absolute body
    angles and rates ``theta, omega`` (B,), body-frame origins and their velocities
    ``origin, v_origin`` (B, 2), and the reference's joint coordinates ``x, xd`` (J,)."""

    q: np.ndarray
    qd: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    origin: np.ndarray
    v_origin: np.ndarray
    x: np.ndarray
    xd: np.ndarray
    #: whole turns (rad, multiples of 2 pi) from the engines' body angles to the
    #: reference's (the tree starts within half a turn of its reference pose)
    turns: np.ndarray | None = None


def free_start(tree: SimTree, s0) -> FreeStart:
    """The tree coordinates of the reference's state at t = 0 (``s0``: a
    :class:`analytic.free_motion.FreeSamples` whose first row is t = 0): hinge ``q =
    theta_child - theta_parent - rel_angle`` (wrapped: the engines' tree starts within
    half a turn of its reference pose), slide ``q = sigma (s - s_ref)``; rates likewise."""
    mech = tree.mech
    th, om = np.asarray(s0.theta[0], float), np.asarray(s0.omega[0], float)
    jx, jxd = np.asarray(s0.x[0], float), np.asarray(s0.xd[0], float)
    nt = len(tree.joints)
    q, qd = np.zeros(nt), np.zeros(nt)
    for i, tj in enumerate(tree.joints):
        if tj.kind == "hinge":
            q[i] = float(wrap(th[tj.child] - th[tj.parent] - tj.rel_angle))
            qd[i] = om[tj.child] - om[tj.parent]
        else:
            q[i] = tj.sigma * (jx[tj.joint] - tj.q_ref)
            qd[i] = tj.sigma * jxd[tj.joint]
    pth, pom, _, org, vo, _ = tree.propagate(q[None], qd[None], np.zeros((1, nt)))
    if not np.allclose(wrap(pth[0] - th), 0.0, atol=1e-9):
        raise EngineRefusal(f"mechanism {mech.name!r}: the engines' tree cannot take the "
                            "reference's initial pose (body angles differ by "
                            f"{np.max(np.abs(wrap(pth[0] - th))):.3g} rad)")
    turns = 2 * np.pi * np.round((th - pth[0]) / (2 * np.pi))
    return FreeStart(q, qd, pth[0], pom[0], org[0], vo[0], jx, jxd, turns)


# ============================================================================ readout
def bodies_at(tree: SimTree, q, qd):
    """``theta, omega`` (1, B), body-frame ``origin, v_origin`` (1, B, 2) of one state in
    tree coordinates: :meth:`SimTree.propagate` without accelerations, in scalar
    arithmetic (a harness that applies forces every step calls it per step; ~15x
    faster than the vectorised one for one row)."""
    B = len(tree.body_names)
    th, om = [0.0] * B, [0.0] * B
    org, vo = [(0.0, 0.0)] * B, [(0.0, 0.0)] * B
    g = tree.ground
    th[g] = float(tree.theta_ref[g])
    org[g] = (float(tree.origin_ref[g][0]), float(tree.origin_ref[g][1]))
    cos, sin = math.cos, math.sin
    for i, tj in enumerate(tree.joints):
        p, c = tj.parent, tj.child
        cp, sp = cos(th[p]), sin(th[p])
        wp = om[p]
        if tj.kind == "hinge":
            th[c] = th[p] + tj.rel_angle + float(q[i])
            om[c] = wp + float(qd[i])
            ax, ay = tj.anchor_parent
            rx, ry = cp * ax - sp * ay, sp * ax + cp * ay
            cc, sc = cos(th[c]), sin(th[c])
            bx, by = tj.anchor_child
            kx, ky = -(cc * bx - sc * by), -(sc * bx + cc * by)
            org[c] = (org[p][0] + rx + kx, org[p][1] + ry + ky)
            vo[c] = (vo[p][0] - wp * ry - om[c] * ky, vo[p][1] + wp * rx + om[c] * kx)
        else:
            th[c] = th[p] + tj.rel_angle
            om[c] = wp
            cc, sc = cos(th[c]), sin(th[c])
            ux = cc * tj.axis_child[0] - sc * tj.axis_child[1]
            uy = sc * tj.axis_child[0] + cc * tj.axis_child[1]
            a, b = tj.rel_pos
            rx = cp * a - sp * b + float(q[i]) * ux
            ry = sp * a + cp * b + float(q[i]) * uy
            org[c] = (org[p][0] + rx, org[p][1] + ry)
            vo[c] = (vo[p][0] - wp * ry + float(qd[i]) * ux,
                     vo[p][1] + wp * rx + float(qd[i]) * uy)
    return (np.array([th]), np.array([om]), np.array([org]), np.array([vo]))


def _rot_rows(theta, r):
    """World vectors (N, 2) of body-frame vectors ``r`` (2,) or (N, 2) at angles (N,)."""
    c, s = np.cos(theta), np.sin(theta)
    r = np.broadcast_to(np.asarray(r, float), (len(theta), 2))
    return np.stack([c * r[:, 0] - s * r[:, 1], s * r[:, 0] + c * r[:, 1]], -1)


def _perp(v):
    return np.stack([-v[..., 1], v[..., 0]], -1)


def _point(tree: SimTree, theta, omega, origin, v, b: int, p):
    """World position and velocity (N, 2) of body-frame point ``p`` of body ``b``."""
    r = _rot_rows(theta[:, b], p)
    return origin[:, b] + r, v[:, b] + omega[:, b, None] * _perp(r)


def joint_coordinates(tree: SimTree, theta, omega, origin, v, x0=None):
    """Every joint's coordinate and rate (N, J) from absolute body states (analytic
    conventions): revolute ``theta_b - theta_a`` (whole turns chosen so the first row
    is nearest ``x0``), prismatic ``u . (P_slider - O_guide)`` with ``u`` the line's
    direction on the guide, and its time derivative."""
    mech = tree.mech
    idx = {n: i for i, n in enumerate(tree.body_names)}
    N, J = len(theta), len(mech.joints)
    x, xd = np.zeros((N, J)), np.zeros((N, J))
    for k, jt in enumerate(mech.joints):
        if isinstance(jt, Revolute):
            a, b = idx[jt.body_a], idx[jt.body_b]
            x[:, k] = theta[:, b] - theta[:, a]
            xd[:, k] = omega[:, b] - omega[:, a]
            if x0 is not None and N:
                x[:, k] += 2 * math.pi * round((x0[k] - x[0, k]) / (2 * math.pi))
            continue
        g, s = idx[jt.guide], idx[jt.slider]
        u = _rot_rows(theta[:, g], (math.cos(jt.direction), math.sin(jt.direction)))
        P, vP = _point(tree, theta, omega, origin, v, s, mech.bodies[s].points[jt.point])
        O, vO = _point(tree, theta, omega, origin, v, g, mech.bodies[g].points[jt.origin])
        d, dd = P - O, vP - vO
        x[:, k] = np.sum(u * d, -1)
        xd[:, k] = np.sum(u * dd, -1) + omega[:, g] * np.sum(_perp(u) * d, -1)
    return x, xd


def energies(tree: SimTree, theta, omega, origin, v, x):
    """Kinetic and potential energy (N,) J from absolute body states, with the
    description's own masses (a massless body carries none, as in the reference),
    gravity (potential ``-m g . r_G``), and springs (``k (L - L0)^2 / 2``, joint springs
    on the joint coordinates ``x``): the one energy function of every engine."""
    mech = tree.mech
    g = np.asarray(mech.gravity, float)
    N = len(theta)
    T, V = np.zeros(N), np.zeros(N)
    for b, body in enumerate(mech.bodies):
        if b == tree.ground or not (body.mass or body.inertia):
            continue
        rG, vG = _point(tree, theta, omega, origin, v, b, body.com)
        T += 0.5 * (body.mass * np.sum(vG * vG, -1) + body.inertia * omega[:, b] ** 2)
        V -= body.mass * (rG @ g)
    fm = mech.motion
    idx = {n: i for i, n in enumerate(tree.body_names)}
    jidx = {j.name: k for k, j in enumerate(mech.joints)}
    for s in (fm.springs if fm else ()):
        if isinstance(s, PointSpring):
            ra, _ = _point(tree, theta, omega, origin, v, idx[s.body_a],
                           mech.bodies[idx[s.body_a]].points[s.point_a])
            rb, _ = _point(tree, theta, omega, origin, v, idx[s.body_b],
                           mech.bodies[idx[s.body_b]].points[s.point_b])
            ext = np.linalg.norm(rb - ra, axis=-1) - s.free_length
        else:
            ext = x[:, jidx[s.joint]] - s.free_value
        V += 0.5 * s.stiffness * ext ** 2
    return T, V


def energy_scale(mech, kinetic0: float, size: float) -> float:
    """The run's energy scale (J), as the reference's integrator takes it: the initial
    kinetic energy, gravity's work over one size of height, each spring's energy at one
    size (or radian) of stretch, each motor's largest effort over one radian or size,
    each load's work over one size."""
    g = math.hypot(*mech.gravity)
    e = float(kinetic0) + sum((b.mass or 0.0) * g * size for b in mech.moving_bodies)
    fm = mech.motion
    for s in (fm.springs if fm else ()):
        e += s.stiffness * (size if isinstance(s, PointSpring) else 1.0) ** 2
    for mo in (fm.motors if fm else ()):
        e += max(abs(mo.effort), *(abs(v) for v in mo.efforts)) if mo.efforts else abs(mo.effort)
    for ld in mech.loads:
        e += math.hypot(*ld.force) * size + abs(ld.torque)
    return e or 1.0


# ============================================================================ elements
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
@dataclass(frozen=True)
class FreeRead:
    """One sample of an engine (absolute, world axes): ``theta, omega, alpha`` (B,),
    body-frame ``origin, v_origin`` (B, 2), ``joint_force`` (J, 2) by body_a on body_b,
    the engine's own ``motor_effort`` (NaN when none)."""

    theta: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    origin: np.ndarray
    v_origin: np.ndarray
    joint_force: np.ndarray
    motor_effort: float = math.nan


class FreeSession(ABC):
    """One engine model of one linkage, released (no drive).  Subclass per engine:
    ``__init__(tree, settings)`` builds it, :meth:`start` sets the released state,
    :meth:`advance` steps (no readout: the loop the speed study times), :meth:`read`
    reads the state at a step boundary.  Nothing raises for a diverging simulation:
    :meth:`advance` returns a reason, :meth:`read` may return ``None``."""

    name: ClassVar[str] = ""
    settings_class: ClassVar[type[EngineSettings]] = EngineSettings
    #: the integrator's name for the result (``settings.integrator`` where there is one)
    integrator_name: ClassVar[str] = ""
    #: which elements the engine builds itself and which the harness applies (README)
    native: ClassVar[str] = ""
    #: "engine" when :attr:`FreeRead.motor_effort` is the engine's own reading (an
    #: actuator's force), "harness" when it is the value the harness applied
    motor_effort_source: ClassVar[str] = "harness"

    def __init__(self, tree: SimTree, settings: EngineSettings | None = None):
        self.tree = tree
        self.settings = settings if settings is not None else self.settings_class()
        self.notes: list[str] = []

    @abstractmethod
    def start(self, s0: FreeStart, h: float) -> None:
        """Put the model in the released state ``s0`` at t = 0; ``h`` the first step."""

    @abstractmethod
    def advance(self, t: float, h: float, n: int) -> str | None:
        """``n`` steps of ``h`` s from ``t``; a divergence reason, or None."""

    @abstractmethod
    def read(self, t: float) -> FreeRead | None:
        """The state at ``t`` (a step boundary); None when it is not finite."""

    def integrator(self) -> str:
        return str(getattr(self.settings, "integrator", self.integrator_name))

    def close(self) -> None:  # noqa: B027 - optional, most engines hold nothing
        """Release the engine's resources."""


# ============================================================================ run loop
def step_plan(times: np.ndarray, h_max: float) -> list[tuple[float, int]]:
    """``(h, n)`` per sample interval: the fewest equal steps no longer than ``h_max``
    that end on the next sample time."""
    out = []
    for a, b in zip(times[:-1], times[1:], strict=True):
        n = max(1, math.ceil((b - a) / h_max * (1 - 1e-12)))
        out.append(((b - a) / n, n))
    return out


def _reference_start(mech, reference, request: FreeRequest):
    if reference is None:
        reference = simulate(mech, duration=request.duration)
    return reference, reference.at(np.array([0.0]), forces=False)


def drive_free(session: FreeSession, request: FreeRequest, reference=None,
             case: str | None = None) -> FreeEngineRun:
    """Release ``session`` from the reference's state at t = 0 and read it at
    ``request.times()``: **the one free run loop**.  ``wall`` times :meth:`advance`
    only.  A divergence (reason from the engine, non-finite state, energy outside
    ``E0 +- max_energy_growth * scale``, loop gap above ``max_gap * size``, the
    wall-clock limit) ends the run: ``ok = False``, ``t_fail`` = the sample time it was
    seen at, that row and later ones NaN."""
    st, mech = session.tree, session.tree.mech
    reference, s0 = _reference_start(mech, reference, request)
    start = free_start(st, s0)
    times = request.times()
    N, B, J = len(times), len(st.body_names), len(mech.joints)
    th, om, al = (np.full((N, B), np.nan) for _ in range(3))
    org, vo = np.full((N, B, 2), np.nan), np.full((N, B, 2), np.nan)
    jf, eff = np.full((N, J, 2), np.nan), np.full(N, np.nan)
    plan = step_plan(times, float(session.settings.timestep))
    h0 = plan[0][0] if plan else float(session.settings.timestep)
    session.start(start, h0)
    scale = energy_scale(mech, float(s0.kinetic[0]), st.size)
    e0 = float(s0.kinetic[0] + s0.potential[0])
    reason, t_fail, wall, steps = None, None, 0.0, 0
    for k, t in enumerate(times):
        if k:
            h, n = plan[k - 1]
            t0 = time.perf_counter()
            reason = session.advance(float(times[k - 1]), h, n)
            wall += time.perf_counter() - t0
            steps += n
            if reason is None and wall > request.wall_limit:
                reason = f"wall-clock limit {request.wall_limit:g} s reached"
        r = session.read(float(t)) if reason is None else None
        if reason is None and r is None:
            reason = "non-finite state (simulation diverged)"
        if reason is None:
            reason = _check_row(st, r, request, e0, scale, start.x)
        if reason is not None:
            t_fail = float(t)
            break
        th[k], om[k], al[k], org[k], vo[k] = (r.theta + start.turns, r.omega, r.alpha,
                                              r.origin, r.v_origin)
        jf[k], eff[k] = r.joint_force, r.motor_effort
    x, xd, gap, T, V = free_readout(st, th, om, org, vo, start.x)
    has_motor = bool(mech.motion and mech.motion.motors)
    return FreeEngineRun(
        case=case or mech.name, engine=session.name, mechanism=mech,
        settings=session.settings, request=request, ok=reason is None, reason=reason,
        t_fail=t_fail, times=times, joint_names=tuple(j.name for j in mech.joints),
        body_names=tuple(st.body_names), x=x, xd=xd, theta=th, omega=om, alpha=al,
        joint_force=jf, loop_gap=gap, kinetic=T, potential=V,
        motor_effort_engine=eff if has_motor else None, wall=wall, steps=steps,
        timestep=max((h for h, _ in plan), default=float(session.settings.timestep)),
        integrator=session.integrator(), notes=tuple(session.notes),
        precision=session.settings.arithmetic.name,
        extra={"native": session.native, "energy_scale": scale, "E0": e0,
               "motor_effort_source": session.motor_effort_source,
               "start_q": start.q, "start_qd": start.qd})


def free_readout(tree: SimTree, theta, omega, origin, v, x0):
    """``x, xd`` (N, J), loop gap (N,), kinetic and potential energy (N,) of absolute
    body states (NaN rows stay NaN)."""
    x, xd = joint_coordinates(tree, theta, omega, origin, v, x0)
    with np.errstate(invalid="ignore"):
        gap = loop_gaps(tree, theta, origin)
    gap[~np.isfinite(theta).all(axis=1)] = np.nan
    T, V = energies(tree, theta, omega, origin, v, x)
    return x, xd, gap, T, V


def _check_row(tree: SimTree, r: FreeRead, request: FreeRequest, e0: float, scale: float,
               x0) -> str | None:
    """The divergence tests of one sample (see :func:`drive_free`)."""
    if not (np.isfinite(r.theta).all() and np.isfinite(r.omega).all()
            and np.isfinite(r.origin).all()):
        return "non-finite state (simulation diverged)"
    _, _, gap, T, V = free_readout(tree, r.theta[None], r.omega[None], r.origin[None],
                                   r.v_origin[None], x0)
    gmax = request.max_gap * tree.size
    if not gap[0] <= gmax:
        return f"loop gap {gap[0]:.3g} m > {gmax:.3g} m ({request.max_gap:g} of the size)"
    dE = float(T[0] + V[0] - e0)
    if not abs(dE) <= request.max_energy_growth * scale:
        return (f"energy off by {dE:.3g} J, beyond {request.max_energy_growth:g} x the "
                f"energy scale {scale:.3g} J (simulation diverged)")
    return None


def time_free_steps(session: FreeSession, s0: FreeStart, h: float, n: int,
                    repeats: int = 3, clock=time.perf_counter) -> float:
    """Steps per second of ``n`` bare :meth:`FreeSession.advance` steps from the
    released state (no readout), best of ``repeats``: what the speed study times.
    ``clock``: wall time by default; ``time.process_time`` for CPU (``xval tune``)."""
    best = 0.0
    chunk = max(1, min(n, 200))
    for _ in range(max(1, repeats)):
        session.start(s0, h)
        done, t = 0, 0.0
        t0 = clock()
        while done < n:
            k = min(chunk, n - done)
            why = session.advance(t, h, k)
            done, t = done + k, t + k * h
            if why is not None:
                break
        el = clock() - t0
        if el > 0:
            best = max(best, done / el)
    return best


def subtree_correction(tree: SimTree, force: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Tree-joint reactions (J, 2) by body_a on body_b with the body forces ``F`` (B, 2)
    that the engine's readout did not see (a MuJoCo tendon's, a harness-applied
    element's) taken into account: the force by the parent on the child's subtree is
    the subtree's ``sum m a_G`` minus every external force on it, so each such force
    on a subtree body is subtracted (turned by the joint's ``sigma``)."""
    out = np.array(force, float)
    for tj in tree.joints:
        sub = [b for b in range(len(tree.body_names)) if _in_subtree(tree, b, tj.child)]
        out[tj.joint] -= tj.sigma * F[sub].sum(axis=0)
    return out


def _in_subtree(tree: SimTree, b: int, root: int) -> bool:
    while b != tree.ground:
        if b == root:
            return True
        b = tree.parent[b][0]
    return False


__all__ = ["ElementLoads", "FreeRead", "bodies_at", "FreeSession", "FreeStart", "energies",
           "energy_scale", "free_readout", "free_start", "joint_coordinates", "drive_free",
           "step_plan", "subtree_correction", "time_free_steps"]
