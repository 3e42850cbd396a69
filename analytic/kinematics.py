"""Kinematics of every body, point and slider, vectorised over input values.

Velocities and accelerations of the vector-loop unknowns come from the linear
systems obtained by differentiating the loop equations
(:class:`analytic.loops.LoopEquations`): ``J q' = 0`` and
``J q'' = -gamma(q, q')`` plus the driver row.  Body frames' origin velocities
and accelerations then follow by walking the spanning tree from ground with the
rigid-body relations (and, across a slider, the relative velocity ``s' u`` and
the Coriolis term ``2 omega_guide s' sigma``).

Frames and signs: world axes, x right, y up; angles, omega, alpha
counter-clockwise positive (see :mod:`analytic.mechanism`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .errors import SingularConfigurationError
from .linalg import condition
from .loops import LoopEquations
from .mechanism import Mechanism, Revolute
from .positions import PositionSolver, poses_from_q, rotate
from .tolerances import SINGULAR_CONDITION
from .topology import Topology, build_topology


def _perp(v: np.ndarray) -> np.ndarray:
    """Rotate by +90 deg: ``J v``."""
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


@dataclass
class Kinematics:
    """Positions, velocities and accelerations for N input values (SI, world frame).

    Attributes
    ----------
    value, velocity, acceleration : (N,)
        The driver's coordinate (rad or m) and its rates.
    q, qd, qdd : (N, nq)
        Vector-loop unknowns (moving group angles, then slider displacements).
    theta, omega, alpha : (N, B)
        Body angles (rad), angular velocities (rad/s), accelerations (rad/s^2).
    origin, v_origin, a_origin : (N, B, 2)
        Body frame origins and their velocity and acceleration.
    condition : (N,)
        Condition number of the loop Jacobian in the unknowns (inf: singular).
    determinant : (N,)
        Its determinant, normalised by the product of its column norms (in
        [-1, 1]; a sign change marks passing a dead-centre or change point).
    transmission : dict joint name -> (N,) deg
        Transmission angle at the inner joint of each dyad (0..180 deg; 90 is ideal).
    """

    linkage: Linkage
    value: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    origin: np.ndarray
    v_origin: np.ndarray
    a_origin: np.ndarray
    condition: np.ndarray
    determinant: np.ndarray
    transmission: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(self.value)

    def point(self, body: str, point: str | tuple[float, float]):
        """Position, velocity and acceleration ``(N, 2)`` each of a body point.

        ``point`` is a point name or body-frame coordinates in m.
        """
        topo = self.linkage.topo
        b = self.linkage.body_index(body)
        if isinstance(point, str):
            self.linkage.mech.body(body).point(point)  # typed error for an unknown name
            c = topo.body_points[b][point]
        else:
            c = np.asarray(point, float)
        r = rotate(self.theta[:, b], c)
        w, al = self.omega[:, b, None], self.alpha[:, b, None]
        p = self.origin[:, b] + r
        v = self.v_origin[:, b] + w * _perp(r)
        a = self.a_origin[:, b] + al * _perp(r) - w * w * r
        return p, v, a

    def slider(self, joint: str):
        """Displacement s (m), velocity s' and acceleration s'' ``(N,)`` of a prismatic joint."""
        topo = self.linkage.topo
        k = topo.joint_names.index(joint)
        if k not in topo.slider_index:
            raise KeyError(f"joint {joint!r} is not prismatic")
        i = topo.n_groups + topo.slider_index[k]
        return self.q[:, i], self.qd[:, i], self.qdd[:, i]

    def com(self, b: int):
        """Centre-of-mass position, velocity, acceleration of body index ``b``."""
        body = self.linkage.mech.bodies[b]
        return self.point(body.name, body.com)


class Linkage:
    """A compiled mechanism: topology, loop equations and position solver.

    This is the solver's front door::

        lk = Linkage(mech)
        kin = lk.kinematics(np.radians([30, 60]))          # at the driver's rates
        frc = lk.forces(kin)                               # needs masses
        df = lk.sweep(360)                                 # full cycle, DataFrame
    """

    def __init__(self, mech: Mechanism):
        self.mech = mech
        self.topo: Topology = build_topology(mech)
        self.eqs = LoopEquations(self.topo)
        self.positions = PositionSolver(self.topo, self.eqs)

    def body_index(self, name: str) -> int:
        try:
            return self.topo.body_names.index(name)
        except ValueError:
            self.mech.body(name)  # raises the typed error
            raise

    @property
    def driver_is_revolute(self) -> bool:
        return isinstance(self.mech.driver_joint, Revolute)

    def kinematics(self, values=None, velocity=None, acceleration=None,
                   on_singular: str = "raise") -> Kinematics:
        """Solve positions, velocities and accelerations.

        Parameters
        ----------
        values
            Driver values (rad or m), scalar or ``(N,)``; default the description's.
        velocity, acceleration
            Driver rates (scalar or ``(N,)``); default the description's.
        on_singular
            ``"raise"``: a :class:`SingularConfigurationError` naming the input
            value where the loop Jacobian is singular (condition number above
            :data:`analytic.tolerances.SINGULAR_CONDITION`); ``"flag"``: return the
            result, rates at such points are not meaningful and ``condition`` says so.
        """
        d = self.mech.driver
        values = np.atleast_1d(np.asarray(d.value if values is None else values, float))
        N = len(values)
        vel = np.broadcast_to(np.asarray(d.velocity if velocity is None else velocity,
                                         float), (N,)).copy()
        acc = np.broadcast_to(np.asarray(d.acceleration if acceleration is None
                                         else acceleration, float), (N,)).copy()
        q, trans = self.positions.solve(values)
        eqs = self.eqs
        L2 = 2 * eqs.L
        J = eqs.jacobian(q)
        A, _ = eqs.split(J)
        cond = condition(A) if A.shape[-1] else np.ones(N)
        if A.shape[-1]:
            colnorm = np.prod(np.linalg.norm(A, axis=1), axis=1)
            from .linalg import det_small
            det = det_small(A) / np.where(colnorm > 0, colnorm, 1.0)
        else:
            det = np.ones(N)
        bad = np.flatnonzero(~(cond < SINGULAR_CONDITION))
        if bad.size and on_singular == "raise":
            v = float(values[bad[0]])
            vs = f"{math.degrees(v):.6g} deg" if self.driver_is_revolute else f"{v:.6g} m"
            raise SingularConfigurationError(
                f"mechanism {self.mech.name!r}: singular configuration (dead centre or change "
                f"point) at driver {d.joint!r} = {vs}: loop Jacobian condition number "
                f"{cond[bad[0]]:.3g}; velocities are not determined by the input there", v)
        with np.errstate(all="ignore"):
            qd = eqs.solve_rates(J, np.zeros((N, L2)), vel)
            qdd = eqs.solve_rates(J, -eqs.gamma(q, qd), acc)
        theta, origin = poses_from_q(self.topo, q)
        omega, alpha = self._group_rates(qd), self._group_rates(qdd)
        v_o, a_o = self._propagate(q, qd, qdd, theta, origin, omega, alpha)
        tr = {}
        for name, e1, e2 in trans:
            c = np.einsum("ni,ni->n", e1, e2) / (np.linalg.norm(e1, axis=1)
                                                 * np.linalg.norm(e2, axis=1))
            tr[name] = np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))
        return Kinematics(self, values, vel, acc, q, qd, qdd, theta, omega, alpha,
                          origin, v_o, a_o, cond, det, tr)

    def _group_rates(self, x: np.ndarray) -> np.ndarray:
        g = self.topo.group_of
        out = np.zeros((x.shape[0], len(g)))
        m = g >= 0
        out[:, m] = x[:, g[m]]
        return out

    def _propagate(self, q, qd, qdd, theta, origin, omega, alpha):
        topo = self.topo
        N, B = theta.shape
        v_o = np.zeros((N, B, 2))
        a_o = np.zeros((N, B, 2))

        def carry(b, P, vP, aP, to):
            """Velocity/acceleration of point ``to`` of body b from point P of b."""
            r = to - P
            w, al = omega[:, b, None], alpha[:, b, None]
            return vP + w * _perp(r), aP + al * _perp(r) - w * w * r

        for c in topo.order[1:]:
            p, j = topo.parent[c]
            jt = self.mech.joints[j]
            P = origin[:, p] + rotate(theta[:, p], topo.attach(j, p))
            vP, aP = carry(p, origin[:, p], v_o[:, p], a_o[:, p], P)
            if not isinstance(jt, Revolute):
                i = topo.n_groups + topo.slider_index[j]
                gb = topo.body_names.index(jt.guide)
                u = rotate(theta[:, gb], [math.cos(jt.direction), math.sin(jt.direction)])
                sd, sdd = qd[:, i, None], qdd[:, i, None]
                wg = omega[:, gb, None]
                rel_v = sd * u
                rel_a = sdd * u + 2 * wg * sd * _perp(u)
                if c == topo.body_names.index(jt.slider):
                    # P is the guide's line origin; move along the guide to the slider point
                    PS = origin[:, c] + rotate(theta[:, c], topo.attach(j, c))
                    vG, aG = carry(p, P, vP, aP, PS)
                    P, vP, aP = PS, vG + rel_v, aG + rel_a
                else:
                    # P is the slider point; the guide's material point there moves with
                    # the slider's velocity less the relative sliding
                    vP, aP = vP - rel_v, aP - rel_a
            v_o[:, c], a_o[:, c] = carry(c, P, vP, aP, origin[:, c])
        return v_o, a_o

    # convenience wrappers ----------------------------------------------------
    def forces(self, kin: Kinematics):
        """Kinetostatic solution for a :class:`Kinematics` (see :mod:`analytic.kinetostatics`)."""
        from .kinetostatics import solve_forces
        return solve_forces(self, kin)

    def sweep(self, points: int = 360, **kw):
        """Full-cycle table (see :func:`analytic.sweep.sweep`)."""
        from .sweep import sweep
        return sweep(self, points, **kw)
