"""Kinetostatics: joint reactions, drive effort and power of a driven mechanism.

Newton-Euler with inertia forces for every body.  Instead of solving all
``3 (B - 1)`` body equations at once, the unknowns are reduced to the reactions
at the loop-closing (chord) joints and the drive effort, ``2 L + 1 = B - 1`` in
all.  Each tree joint contributes one equation along its free direction:

* a revolute tree joint transmits no moment, so the moment about its pin of
  everything acting on the subtree beyond it vanishes (or equals the drive
  torque, at the driven joint);
* a prismatic tree joint transmits no force along its line (or the drive force).

With those solved, each tree joint's reaction is the net effective force on its
subtree less the chord reactions acting on it: no further solve.

Sign conventions
----------------
* Revolute joint force ``(fx, fy)``: exerted **by body_a on body_b**, world axes, N.
* Prismatic joint: ``normal`` N and ``moment`` N m exerted by the guide on the
  slider (force ``normal * n`` at the slider point, ``n`` = line direction
  rotated +90 deg; couple ccw positive); ``force`` is ``normal * n``.
* Drive effort: torque (N m, ccw on body_b) or force (N, along the line on the
  slider); drive power = effort x driver velocity (W), positive when the driver
  does work on the mechanism.
"""

from __future__ import annotations

import cmath
from dataclasses import dataclass

import numpy as np

from .errors import MissingMassError
from .linalg import solve_small
from .mechanism import Revolute
from .planar import as_xy, cross
from .singular import force_limits, singular_samples
from .tolerances import POWER_BALANCE


@dataclass
class Forces:
    """Kinetostatic results for N configurations (SI, world axes).

    Attributes
    ----------
    joint_force : dict joint -> (N, 2)
        Force by body_a (guide) on body_b (slider).
    normal, moment : dict prismatic joint -> (N,)
    effort : (N,)
        Drive torque (N m) or force (N).
    power : (N,)
        Input power, W.
    kinetic_rate, load_power : (N,)
        dKE/dt and the power of gravity and external loads, W.
    power_residual : (N,)
        ``power - (kinetic_rate - load_power)``, W: zero to rounding.
    """

    joint_force: dict[str, np.ndarray]
    normal: dict[str, np.ndarray]
    moment: dict[str, np.ndarray]
    effort: np.ndarray
    power: np.ndarray
    kinetic_rate: np.ndarray
    load_power: np.ndarray
    power_residual: np.ndarray
    #: per sample where the loop Jacobian is singular: 1 every value is its limit along
    #: the branch, 2 some joint forces are unbounded there (NaN), 3 not determined (NaN);
    #: 0 regular (:mod:`analytic.singular`).  ``None``: no singular sample.
    at_singular: np.ndarray | None = None

    def power_balance_error(self) -> float:
        """Max |residual| over the batch relative to the peak of the largest power term."""
        peak = max(np.max(np.abs(self.power)), np.max(np.abs(self.kinetic_rate)),
                   np.max(np.abs(self.load_power)), 1e-300)
        return float(np.max(np.abs(self.power_residual)) / peak)

    def check_power_balance(self) -> None:
        err = self.power_balance_error()
        if not err <= POWER_BALANCE:
            raise AssertionError(f"power balance violated: {err:.3g} > {POWER_BALANCE}")


def solve_forces(linkage, kin) -> Forces:
    """Solve the kinetostatic problem for every configuration of ``kin``.

    Phases: each body's effective wrench (d'Alembert), the unit columns of the chord
    unknowns, the subtree sums, one equation per tree joint, the chord reactions then
    the drive effort, and every joint's reaction from them.

    Raises
    ------
    MissingMassError
        When a moving body has no mass properties.
    """
    mech, topo = linkage.mech, linkage.topo
    missing = [b.name for b in mech.moving_bodies if b.mass is None]
    if missing:
        raise MissingMassError(
            f"forces need the mass and inertia of every moving body; missing for {missing} "
            "(give mass = 0 and inertia = 0 for a massless link)", mech.source)
    f, mo, ke_rate, load_pow = _effective_wrenches(mech, topo, kin)
    Fc, Mc, eps = _chord_columns(mech, topo, kin)
    Sf, Smo = _subtree_sums(topo, f, mo)
    A, rhs, td, sd = _tree_rows(mech, topo, kin, Fc, Mc, eps, Sf, Smo)
    # at a singular sample the chord rows are singular too (they are the loop
    # Jacobian's transpose): solved for their limits below, not divided by zero here
    sing = singular_samples(kin)
    x = _solve_unknowns(A, rhs, td, sd, sing)
    joint_force, normal, moment = _reactions(mech, topo, kin, Fc, Mc, eps, Sf, Smo, x)
    effort = x[:, -1]
    power = effort * kin.velocity
    resid = power - (ke_rate - load_pow)
    ordered = {jt.name: joint_force[jt.name] for jt in mech.joints}
    frc = Forces(ordered, normal, moment, effort, power, ke_rate, load_pow, resid)
    if sing.size:  # the limits along the branch, or NaN where unbounded (and said so)
        force_limits(linkage, kin, frc, sing)
    return frc


def _effective_wrenches(mech, topo, kin):
    """Per body the effective force ``m (aG - g)`` less its loads (N, B) complex, its
    moment about the world origin (N, B), and the kinetic-energy rate and load power
    (N,).  Planar vectors are complex (x + iy); cross(a, b) = Im(conj(a) b)."""
    N, B = kin.theta.shape
    g = complex(*mech.gravity)
    f = np.zeros((N, B), complex)  # effective force = sum of joint reactions on the body
    mo = np.zeros((N, B))          # their moment about the world origin
    ke_rate = np.zeros(N)
    load_pow = np.zeros(N)
    for b, body in enumerate(mech.bodies):
        if b == topo.ground:
            continue
        rG, vG, aG = kin.com_c(b)
        m, I = body.mass, body.inertia
        f[:, b] = m * (aG - g)
        h = I * kin.alpha[:, b]
        ke_rate += (m * (aG.real * vG.real + aG.imag * vG.imag)
                    + I * kin.alpha[:, b] * kin.omega[:, b])
        load_pow += m * (vG.real * g.real + vG.imag * g.imag)
        for ld in mech.loads:
            if ld.body != body.name:
                continue
            F = complex(*ld.force)
            rP, vP = (kin.point_c(b, ld.point)[:2] if ld.point is not None else (rG, vG))
            f[:, b] -= F
            h = h - ld.torque - cross(rP - rG, F)
            load_pow += vP.real * F.real + vP.imag * F.imag + ld.torque * kin.omega[:, b]
        mo[:, b] = h + cross(rG, f[:, b])
    return f, mo, ke_rate, load_pow


def _chord_columns(mech, topo, kin):
    """The unknowns, 2 per chord then the drive effort: the force ``Fc`` (N, n_x)
    complex of a unit unknown on the chord's body_b and its moment ``Mc`` (N, n_x) about
    the world origin; ``eps`` (tree joints, n_x): +1/-1 where a chord unknown acts on a
    tree joint's subtree from outside / inside, else 0."""
    joints, names, chords = mech.joints, topo.body_names, topo.chords
    N = kin.theta.shape[0]
    n_x = 2 * len(chords) + 1
    Fc = np.zeros((N, n_x), complex)
    Mc = np.zeros((N, n_x))
    for i, j in enumerate(chords):
        jt = joints[j]
        P = kin.joint_point[j]
        if isinstance(jt, Revolute):
            Fc[:, 2 * i], Fc[:, 2 * i + 1] = 1.0, 1j
            Mc[:, 2 * i], Mc[:, 2 * i + 1] = -P.imag, P.real
        else:
            n = kin.E[:, names.index(jt.guide)] * (1j * cmath.exp(1j * jt.direction))
            Fc[:, 2 * i] = n
            Mc[:, 2 * i] = cross(P, n)
            Mc[:, 2 * i + 1] = 1.0
    eps = np.zeros((len(topo.tree), n_x))
    for t in range(len(topo.tree)):
        S = topo.subtree[t]
        for i, j in enumerate(chords):
            a, b = names.index(joints[j].body_a), names.index(joints[j].body_b)
            e = (1.0 if S[b] and not S[a] else -1.0 if S[a] and not S[b] else 0.0)
            eps[t, 2 * i:2 * i + 2] = e
    return Fc, Mc, eps


def _subtree_sums(topo, f, mo):
    """Net effective force (N, tree joints) complex of each tree joint's subtree and its
    moment about the origin; explicit sums over the few members beat strided small
    matrix products."""
    N, nt = f.shape[0], len(topo.tree)
    Sf = np.empty((N, nt), complex)
    Smo = np.empty((N, nt))
    for t in range(nt):
        members = np.flatnonzero(topo.subtree[t])
        Sf[:, t] = f[:, members[0]]
        Smo[:, t] = mo[:, members[0]]
        for b in members[1:]:
            Sf[:, t] += f[:, b]
            Smo[:, t] += mo[:, b]
    return Sf, Smo


def _tree_rows(mech, topo, kin, Fc, Mc, eps, Sf, Smo):
    """One equation per tree joint in the unknowns: a revolute joint's moment about its
    point, a prismatic joint's force along its line.  Returns ``A`` (N, nt, n_x),
    ``rhs`` (N, nt), the driven joint's row ``td`` and the sign ``sd`` of its effort."""
    joints, names = mech.joints, topo.body_names
    N, n_x = Fc.shape
    nt = len(topo.tree)
    A = np.zeros((N, nt, n_x))
    rhs = np.zeros((N, nt))
    for t, j in enumerate(topo.tree):
        jt = joints[j]
        c = topo.tree_child[t]
        acting = np.flatnonzero(eps[t])  # chord unknowns acting across this subtree
        if isinstance(jt, Revolute):
            P = kin.joint_point[j]
            for k in acting:
                A[:, t, k] = eps[t, k] * (Mc[:, k] - cross(P, Fc[:, k]))
            rhs[:, t] = Smo[:, t] - cross(P, Sf[:, t])
        else:
            u = kin.E[:, names.index(jt.guide)] * cmath.exp(1j * jt.direction)
            for k in acting:
                A[:, t, k] = eps[t, k] * (u.real * Fc[:, k].real + u.imag * Fc[:, k].imag)
            rhs[:, t] = u.real * Sf[:, t].real + u.imag * Sf[:, t].imag
        if j == topo.driver_joint:
            td, sd = t, (1.0 if names[c] == jt.body_b else -1.0)
    return A, rhs, td, sd


def _solve_unknowns(A, rhs, td, sd, sing):
    """The effort appears only in the driven joint's row: the other rows give the chord
    reactions (identity rows at the singular samples ``sing``, solved for their limits
    later), then that row gives the effort.  Returns ``x`` (N, n_x)."""
    N, nt, n_x = A.shape
    rows = [t for t in range(nt) if t != td]
    x = np.empty((N, n_x))
    if n_x > 1:
        As = A[:, rows, :-1]
        if sing.size:
            As = As.copy()
            As[sing] = np.eye(n_x - 1)
        x[:, :-1] = solve_small(As, rhs[:, rows])
    x[:, -1] = (rhs[:, td] - np.einsum("nx,nx->n", A[:, td, :-1], x[:, :-1])) / sd
    return x


def _reactions(mech, topo, kin, Fc, Mc, eps, Sf, Smo, x):
    """Every joint's force (N, 2) by body_a on body_b; a prismatic joint's normal force
    and moment: the chords' from their unknowns, the tree joints' from the subtree sums
    less the chord forces acting across them."""
    joints, names, chords = mech.joints, topo.body_names, topo.chords
    joint_force, normal, moment = {}, {}, {}
    for i, j in enumerate(chords):
        jt = joints[j]
        if isinstance(jt, Revolute):
            joint_force[jt.name] = x[:, 2 * i:2 * i + 2]
        else:
            normal[jt.name] = x[:, 2 * i]
            moment[jt.name] = x[:, 2 * i + 1]
            joint_force[jt.name] = as_xy(Fc[:, 2 * i] * x[:, 2 * i])
    for t, j in enumerate(topo.tree):
        jt = joints[j]
        c = topo.tree_child[t]
        onchild = Sf[:, t].copy()  # force from the parent on the subtree
        for k in np.flatnonzero(eps[t]):
            onchild -= eps[t, k] * x[:, k] * Fc[:, k]
        to_b = onchild if names[c] == jt.body_b else -onchild
        if isinstance(jt, Revolute):
            joint_force[jt.name] = as_xy(to_b)
        else:
            n = kin.E[:, names.index(jt.guide)] * (1j * cmath.exp(1j * jt.direction))
            nn = n.real * to_b.real + n.imag * to_b.imag
            normal[jt.name] = nn
            joint_force[jt.name] = as_xy(n * nn)
            PS = kin.joint_point[j]
            mom = Smo[:, t] - cross(PS, Sf[:, t]) - ((Mc - cross(PS[:, None], Fc)) * x) @ eps[t]
            moment[jt.name] = mom if names[c] == jt.body_b else -mom
    return joint_force, normal, moment
