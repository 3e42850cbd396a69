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

import math
from dataclasses import dataclass

import numpy as np

from .errors import MissingMassError
from .linalg import solve_small
from .mechanism import Revolute
from .positions import rotate
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

    def power_balance_error(self) -> float:
        """Max |residual| over the batch relative to the peak of the largest power term."""
        peak = max(np.max(np.abs(self.power)), np.max(np.abs(self.kinetic_rate)),
                   np.max(np.abs(self.load_power)), 1e-300)
        return float(np.max(np.abs(self.power_residual)) / peak)

    def check_power_balance(self) -> None:
        err = self.power_balance_error()
        if not err <= POWER_BALANCE:
            raise AssertionError(f"power balance violated: {err:.3g} > {POWER_BALANCE}")


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def solve_forces(linkage, kin) -> Forces:
    """Solve the kinetostatic problem for every configuration of ``kin``.

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
    N, B = kin.theta.shape
    g = np.asarray(mech.gravity, float)
    f = np.zeros((N, B, 2))     # effective force = sum of joint reactions on the body
    mo = np.zeros((N, B))       # their moment about the world origin
    ke_rate = np.zeros(N)
    load_pow = np.zeros(N)
    for b, body in enumerate(mech.bodies):
        if b == topo.ground:
            continue
        rG, vG, aG = kin.com(b)
        m, I = body.mass, body.inertia
        f[:, b] = m * aG - m * g
        h = I * kin.alpha[:, b]
        ke_rate += m * np.einsum("ni,ni->n", aG, vG) + I * kin.alpha[:, b] * kin.omega[:, b]
        load_pow += m * (vG @ g)
        for ld in mech.loads:
            if ld.body != body.name:
                continue
            F = np.asarray(ld.force, float)
            if ld.point is not None:
                rP, vP, _ = kin.point(body.name, ld.point)
            else:
                rP, vP = rG, vG
            f[:, b] -= F
            h = h - ld.torque - _cross(rP - rG, F)
            load_pow += vP @ F + ld.torque * kin.omega[:, b]
        mo[:, b] = h + _cross(rG, f[:, b])

    joints = mech.joints
    names = topo.body_names
    chords = topo.chords
    # unknown columns: 2 per chord, then the drive effort
    n_x = 2 * len(chords) + 1
    Fc = np.zeros((N, n_x, 2))  # force of unit unknown on the chord's body_b
    Mc = np.zeros((N, n_x))     # its moment about the world origin
    for i, j in enumerate(chords):
        jt = joints[j]
        bb = names.index(jt.body_b)
        P = kin.origin[:, bb] + rotate(kin.theta[:, bb], topo.attach(j, bb))
        if isinstance(jt, Revolute):
            Fc[:, 2 * i, 0] = 1.0
            Fc[:, 2 * i + 1, 1] = 1.0
            Mc[:, 2 * i] = -P[:, 1]
            Mc[:, 2 * i + 1] = P[:, 0]
        else:
            gb = names.index(jt.guide)
            n = rotate(kin.theta[:, gb], [-math.sin(jt.direction), math.cos(jt.direction)])
            Fc[:, 2 * i] = n
            Mc[:, 2 * i] = _cross(P, n)
            Mc[:, 2 * i + 1] = 1.0
    eps = np.zeros((len(topo.tree), n_x))
    for t in range(len(topo.tree)):
        S = topo.subtree[t]
        for i, j in enumerate(chords):
            a, b = names.index(joints[j].body_a), names.index(joints[j].body_b)
            e = (1.0 if S[b] and not S[a] else -1.0 if S[a] and not S[b] else 0.0)
            eps[t, 2 * i:2 * i + 2] = e

    Sf = np.einsum("nbc,tb->ntc", f, topo.subtree.astype(float))  # (N, nt, 2)
    Smo = mo @ topo.subtree.T.astype(float)                      # (N, nt)
    A = np.zeros((N, len(topo.tree), n_x))
    rhs = np.zeros((N, len(topo.tree)))
    for t, j in enumerate(topo.tree):
        jt = joints[j]
        c = topo.tree_child[t]
        P = kin.origin[:, c] + rotate(kin.theta[:, c], topo.attach(j, c))
        sgn_drive = 1.0 if names[c] == jt.body_b else -1.0
        if isinstance(jt, Revolute):
            A[:, t, :] = eps[t] * (Mc - _cross(P[:, None, :], Fc))
            rhs[:, t] = Smo[:, t] - _cross(P, Sf[:, t])
        else:
            gb = names.index(jt.guide)
            u = rotate(kin.theta[:, gb], [math.cos(jt.direction), math.sin(jt.direction)])
            A[:, t, :] = eps[t] * np.einsum("nxc,nc->nx", Fc, u)
            rhs[:, t] = np.einsum("nc,nc->n", Sf[:, t], u)
        if j == topo.driver_joint:
            A[:, t, -1] = sgn_drive
    x = solve_small(A, rhs)

    joint_force, normal, moment = {}, {}, {}
    for i, j in enumerate(chords):
        jt = joints[j]
        if isinstance(jt, Revolute):
            joint_force[jt.name] = x[:, 2 * i:2 * i + 2]
        else:
            normal[jt.name] = x[:, 2 * i]
            moment[jt.name] = x[:, 2 * i + 1]
            joint_force[jt.name] = Fc[:, 2 * i] * x[:, 2 * i, None]
    for t, j in enumerate(topo.tree):
        jt = joints[j]
        c = topo.tree_child[t]
        onchild = Sf[:, t] - np.einsum("x,nxc,nx->nc", eps[t], Fc, x)
        to_b = onchild if names[c] == jt.body_b else -onchild
        if isinstance(jt, Revolute):
            joint_force[jt.name] = to_b
        else:
            gb = names.index(jt.guide)
            n = rotate(kin.theta[:, gb], [-math.sin(jt.direction), math.cos(jt.direction)])
            nn = np.einsum("nc,nc->n", to_b, n)
            normal[jt.name] = nn
            joint_force[jt.name] = n * nn[:, None]
            sb = names.index(jt.slider)
            P = kin.origin[:, sb] + rotate(kin.theta[:, sb], topo.attach(j, sb))
            mom = Smo[:, t] - _cross(P, Sf[:, t]) - np.einsum(
                "x,nx,nx->n", eps[t], Mc - _cross(P[:, None, :], Fc), x)
            moment[jt.name] = mom if names[c] == jt.body_b else -mom
    effort = x[:, -1]
    power = effort * kin.velocity
    resid = power - (ke_rate - load_pow)
    ordered = {jt.name: joint_force[jt.name] for jt in joints}
    return Forces(ordered, normal, moment, effort, power, ke_rate, load_pow, resid)
