"""Tree-joint reactions and drive effort by Newton-Euler from an engine's own motion.

Used where an engine's own pin-force reading is unreliable (PyBullet's
``jointReactionForces`` on moving-base joints, see ENGINE_NOTES.md): given the
engine's body motion (poses, rates, accelerations from its joint states) and
its loop-closure forces, the wrench the parent exerts on each tree joint's
subtree is the subtree's effective force (``m a_G - m g - loads``, moment
``I alpha - ...``) less the loop-closure forces entering the subtree.  This is
the analytic kinetostatics' reduction (:mod:`analytic.kinetostatics`) fed with
the engine's numbers instead of the analytic ones, so it checks the engine's
dynamics, not the analytic solution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..builders.tree import SimTree


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _rot(t, c):
    c = np.asarray(c, float)
    cs, sn = np.cos(t), np.sin(t)
    return np.stack([cs * c[0] - sn * c[1], sn * c[0] + cs * c[1]], axis=-1)


def reconstruct(st: SimTree, theta, omega, alpha, origin, a_origin, chord_force):
    """Tree-joint forces, prismatic normal/moment and drive effort, (N,) batches.

    Parameters
    ----------
    theta, omega, alpha : (N, B); origin, a_origin : (N, B, 2)
        Body motion in the engine.
    chord_force : (N, n_chords, 2)
        Force by body_a on body_b at each loop-closing joint (``st.chords`` order).

    Returns
    -------
    force : dict joint name -> (N, 2), by body_a on body_b (world axes)
    normal, moment : dict prismatic tree-joint name -> (N,)
    effort : (N,) drive torque / force on body_b (slider)
    """
    f, mo = _body_wrenches(st, theta, omega, alpha, origin, a_origin)
    _add_chord_forces(st, f, mo, theta, origin, chord_force)
    sub_f, sub_m = _subtree_sums(st, f, mo)
    force, normal, moment, effort = _tree_joint_reactions(st, theta, origin, sub_f, sub_m)
    for i, ch in enumerate(st.chords):
        force[ch.name] = chord_force[:, i]
    return force, normal, moment, effort


@dataclass(frozen=True)
class JointReadout:
    """:func:`reconstruct`'s forces as a recorder takes them, for K records: ``force``
    (K, J, 2) by body_a on body_b at each joint of ``joint_names`` (NaN where none is
    reconstructed), ``effort`` (K,) the drive's, ``normal`` and ``moment`` (K, P) at the
    prismatic tree joints (``st.prismatic`` order)."""

    force: np.ndarray
    effort: np.ndarray
    normal: np.ndarray
    moment: np.ndarray


def joint_readout(st: SimTree, prop, chord_force, joint_names: list[str]) -> JointReadout:
    """:func:`reconstruct` on the propagated motion ``prop`` (the recorder's
    ``(theta, omega, alpha, origin, _, a_origin)`` of K records), laid out per joint."""
    th, om, al, org, _, a_org = prop
    F, Nn, M, eff = reconstruct(st, th, om, al, org, a_org, chord_force)
    K, J = len(th), len(joint_names)
    force = np.full((K, J, 2), np.nan)
    for name, val in F.items():
        force[:, joint_names.index(name)] = val
    names = [st.mech.joints[k].name for k in st.prismatic]
    normal = np.array([Nn[n] for n in names]).reshape(len(names), K).T
    moment = np.array([M[n] for n in names]).reshape(len(names), K).T
    return JointReadout(force, eff, normal, moment)


def _body_wrenches(st: SimTree, theta, omega, alpha, origin, a_origin):
    """Per body, the wrench the rest of the linkage must exert on it (d'Alembert):
    force ``m aG - m g`` less the applied loads (N, B, 2) and moment about the world
    origin (N, B)."""
    mech = st.mech
    N, B = theta.shape
    g = np.asarray(mech.gravity, float)
    f = np.zeros((N, B, 2))
    mo = np.zeros((N, B))
    for b, body in enumerate(mech.bodies):
        if b == st.ground:
            continue
        rc = _rot(theta[:, b], st.com[b])
        w, al = omega[:, b, None], alpha[:, b, None]
        rG = origin[:, b] + rc
        aG = a_origin[:, b] + al * np.stack([-rc[:, 1], rc[:, 0]], -1) - w * w * rc
        m, inertia = st.mass[b], st.inertia[b]
        f[:, b] = m * aG - m * g
        h = inertia * alpha[:, b]
        for ld in mech.loads:
            if ld.body != body.name:
                continue
            F = np.asarray(ld.force, float)
            rP = rG if ld.point is None else origin[:, b] + _rot(theta[:, b],
                                                                 body.points[ld.point])
            f[:, b] -= F
            h = h - ld.torque - _cross(rP - rG, F)
        mo[:, b] = h + _cross(rG, f[:, b])
    return f, mo


def _add_chord_forces(st: SimTree, f, mo, theta, origin, chord_force) -> None:
    """The loop-closing forces as external wrenches on body_b (+F) and body_a (-F),
    taken off ``f`` and ``mo`` in place."""
    for i, ch in enumerate(st.chords):
        F = chord_force[:, i]
        Pb = origin[:, ch.body_b] + _rot(theta[:, ch.body_b], ch.point_b)
        f[:, ch.body_b] -= F
        mo[:, ch.body_b] -= _cross(Pb, F)
        if ch.body_a != st.ground:
            f[:, ch.body_a] += F
            mo[:, ch.body_a] += _cross(Pb, F)


def _subtree_sums(st: SimTree, f, mo):
    """Per tree joint's child, the wrench by the parent on its whole subtree:
    child body -> (N, 2) force, (N,) moment about the world origin."""
    children = {b: [] for b in range(f.shape[1])}
    for tj in st.joints:
        children[tj.parent].append(tj.child)
    sub_f, sub_m = {}, {}
    for tj in reversed(st.joints):
        c = tj.child
        sf, sm = f[:, c].copy(), mo[:, c].copy()
        for k in children[c]:
            sf += sub_f[k]
            sm += sub_m[k]
        sub_f[c], sub_m[c] = sf, sm
    return sub_f, sub_m


def _tree_joint_reactions(st: SimTree, theta, origin, sub_f, sub_m):
    """Each tree joint's force (by body_a on body_b), a prismatic joint's normal force
    and moment, and the drive effort, from the subtree wrenches."""
    mech = st.mech
    force, normal, moment = {}, {}, {}
    effort = np.full(theta.shape[0], math.nan)
    for t, tj in enumerate(st.joints):
        c = tj.child
        jt = mech.joints[tj.joint]
        if tj.kind == "hinge":
            P = origin[:, c] + _rot(theta[:, c], tj.anchor_child)
        else:
            sb = st.body_names.index(jt.slider)
            P = origin[:, sb] + _rot(theta[:, sb], mech.bodies[sb].points[jt.point])
        F_on_child = sub_f[c]
        M_on_child = sub_m[c] - _cross(P, F_on_child)  # about P
        F = tj.sigma * F_on_child
        force[tj.name] = F
        if tj.kind == "slide":
            gb = st.body_names.index(jt.guide)
            ang = theta[:, gb] + jt.direction
            n = np.stack([-np.sin(ang), np.cos(ang)], -1)
            u = np.stack([np.cos(ang), np.sin(ang)], -1)
            normal[tj.name] = np.einsum("nc,nc->n", F, n)
            moment[tj.name] = tj.sigma * M_on_child
            if t == st.driver_tree:
                effort = np.einsum("nc,nc->n", F, u)
        elif t == st.driver_tree:
            effort = tj.sigma * M_on_child
    return force, normal, moment, effort
