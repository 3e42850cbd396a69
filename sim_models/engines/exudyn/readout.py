"""The readout of an Exudyn run in the analytic conventions (:class:`ExudynReadout`):
positions, velocities and accelerations of the bodies from the nodes, and joint forces and
drive effort from the Lagrange multipliers (the mapping is in
:mod:`sim_models.engines.exudyn.driven`'s docstring)."""

from __future__ import annotations

import math

import numpy as np

from analytic import Prismatic

from ...builders.tree import SimModelError
from ..protocol import (
    Recorder,
)
from .planar import _cross_rows, _dot, _perp, _perp_rows, _world, _world_many


class ExudynReadout:
    """Reading an :class:`~sim_models.engines.exudyn.driven.ExudynSession`'s state and
    multipliers into a :class:`~sim_models.engines.protocol.Recorder`."""

    def record(self, t: float):
        """Copies of the state at ``t``: coordinates, velocities, and either the
        integrator's own accelerations and multipliers (``sample_by="integrator"``) or
        Exudyn's constraint Jacobian and applied forces there (``"state"``: the
        accelerations and multipliers are solved from them in :meth:`convert`).  A
        non-finite state is a reason at once."""
        sd = self.mbs.systemData
        q, qd = np.array(sd.GetODE2Coordinates()), np.array(sd.GetODE2Coordinates_t())
        if not (math.isfinite(q.sum()) and math.isfinite(qd.sum())):
            return None, 0.0, "non-finite state (simulation diverged)"
        if self.settings.sample_by == "integrator":
            return (q, qd, np.array(sd.GetODE2Coordinates_tt()),
                    np.array(sd.GetAECoordinates())), 0.0, None
        C, f = self._jacobian_and_forces()
        return (q, qd, C, f), 0.0, None

    def _jacobian_and_forces(self):
        """Exudyn's constraint Jacobian ``C`` (nAE, nODE2; the drive's velocity-level row
        included) and its generalized applied forces ``f`` (nODE2) at the current state,
        from the probe solver's structures (no re-initialisation)."""
        pr, n = self.probe, self.n_ode2
        pr.SetSystemJacobian(self._zero_jacobian)  # ComputeJacobianAE adds into it
        pr.ComputeJacobianAE(self.mbs, 1.0, 1.0, 0.0, False)
        C = np.array(pr.GetSystemJacobian())[n:, :n]
        pr.ComputeODE2RHS(self.mbs)
        return C, np.array(pr.GetSystemResidual())[:n]

    def convert(self, times, raws, rows, rec: Recorder):
        """The analytic conventions of K records at once.  Sampling by state solves
        ``[M C^T; C 0] [q''; lambda] = [f; gamma]`` per record (one batched solve) with
        Exudyn's mass matrix, constraint Jacobian and forces at the record's state, and
        ``gamma`` the constraints' exact velocity terms (:meth:`_gamma`)."""
        q, qd, a3, a4 = (np.array(x) for x in zip(*raws, strict=True))
        times = np.asarray(times, float)
        if self.settings.sample_by == "integrator":
            qdd, lam = a3, a4
        else:
            qdd, lam = self._solve_state(times, q, qd, a3, a4)
        return self._readout(times, rows, rec, q, qd, qdd, lam)

    def _solve_state(self, times, q, qd, C, f):
        """Accelerations and multipliers consistent with the state (K records)."""
        K, n = q.shape
        m = C.shape[1]
        A = np.zeros((K, n + m, n + m))
        A[:, :n, :n] = self.M
        A[:, :n, n:] = C.transpose(0, 2, 1)
        A[:, n:, :n] = C
        b = np.concatenate([f, self._gamma(times, q, qd)], axis=1)
        try:
            x = np.linalg.solve(A, b[..., None])[..., 0]
        except np.linalg.LinAlgError:  # a singular record (a singular position): NaN there
            x = np.full_like(b, np.nan)
            for k in range(K):
                try:
                    x[k] = np.linalg.solve(A[k], b[k])
                except np.linalg.LinAlgError:
                    pass
        return x[:, :n], x[:, n:]

    def _geometry(self):
        """Per joint, the marker data the velocity terms need (built once)."""
        st = self.tree
        mech = st.mech
        idx = {nm: i for i, nm in enumerate(st.body_names)}
        out = []
        for k, jt in enumerate(mech.joints):
            a, b = idx[jt.body_a], idx[jt.body_b]
            pa = np.asarray(mech.bodies[a].points[jt.point_a], float)
            pb = np.asarray(mech.bodies[b].points[jt.point_b], float)
            ra = pa if a == self.g else pa - self.com[a]
            rb = pb if b == self.g else pb - self.com[b]
            extra = None
            if isinstance(jt, Prismatic):
                nn = jt.direction + math.pi / 2 - jt.angle
                extra = (np.array([math.cos(jt.direction), math.sin(jt.direction)]),
                         np.array([math.cos(nn), math.sin(nn)]))
            out.append((k, a, b, ra, rb, extra))
        return out

    def _bodies(self, q, qd, qdd=None):
        """theta, omega, alpha (K, B) and centre-of-mass position, velocity,
        acceleration (K, B, 2) of every body (the ground: fixed, its reference pose)."""
        K, B = len(q), len(self.tree.body_names)
        th = np.full((K, B), float(self.tree.kin_ref.theta[0, self.g]))
        om, al = np.zeros((K, B)), np.zeros((K, B))
        xG, vG, aG = np.zeros((K, B, 2)), np.zeros((K, B, 2)), np.zeros((K, B, 2))
        for b, ltg in self.ltg.items():
            th[:, b] = self.ref[b][2] + q[:, ltg[2]]
            om[:, b] = qd[:, ltg[2]]
            xG[:, b] = self.ref[b][:2] + q[:, ltg[:2]]
            vG[:, b] = qd[:, ltg[:2]]
            if qdd is not None:
                al[:, b] = qdd[:, ltg[2]]
                aG[:, b] = qdd[:, ltg[:2]]
        return th, om, al, xG, vG, aG

    def _gamma(self, times, q, qd):
        """``gamma = -(C q')_q q'`` per record (K, nAE), exactly, from the joints'
        geometry, in Exudyn's row signs (:meth:`_row_signs`), plus the prescribed driver
        acceleration on the drive row (which Exudyn's own initial solve leaves out)."""
        th, om, _, xG, vG, _ = self._bodies(q, qd)
        g = np.zeros((len(q), self.n_ae))
        for k, a, b, ra, rb, line in self._joints:
            Ra, va_, wa = _world(th[:, a], ra), vG[:, a], om[:, a]
            Rb, vb_, wb = _world(th[:, b], rb), vG[:, b], om[:, b]
            rows = self.joint_ae[k]
            if line is None:   # p_b - p_a = 0
                g[:, rows] = (wb * wb)[:, None] * Rb - (wa * wa)[:, None] * Ra
                continue
            t0, n1 = _world(th[:, a], line[0]), _world(th[:, b], line[1])
            d = (xG[:, b] + Rb) - (xG[:, a] + Ra if a != self.g else Ra)
            dv = (vb_ + wb[:, None] * _perp_rows(Rb)) - (va_ + wa[:, None] * _perp_rows(Ra))
            g[:, rows[0]] = (_dot(wb[:, None] ** 2 * Rb - wa[:, None] ** 2 * Ra, n1)
                             - 2 * wb * _dot(dv, _perp_rows(n1)) + wb * wb * _dot(d, n1))
            g[:, rows[1]] = (wb - wa) ** 2 * _dot(t0, n1)
        g *= self._signs
        g[:, self.drive_ae] = self._drive_sign * self.tree.driver_path(times)[2]
        return g

    def _row_signs(self):
        """Exudyn's sign of each joint's constraint rows relative to the ones
        :meth:`_gamma` is written for, from its Jacobian at the reference state (checked
        entry by entry: a different constraint form is an error here, not a wrong
        reading later)."""
        C, _ = self._jacobian_and_forces()
        q = np.zeros((1, self.n_ode2))
        th, _, _, _, _, _ = self._bodies(q, q)
        mine = np.zeros_like(C)
        for k, a, b, ra, rb, line in self._joints:
            rows = self.joint_ae[k]
            for body, r, s in ((a, ra, -1.0), (b, rb, 1.0)):
                if body == self.g:
                    continue
                cols = self.ltg[body]
                R = _world(th[:, body], r)[0]
                if line is None:
                    mine[rows[0], cols] = [s, 0.0, -s * R[1]]
                    mine[rows[1], cols] = [0.0, s, s * R[0]]
                    continue
                n1 = _world(th[:, b], line[1])[0]
                t0 = _world(th[:, a], line[0])[0]
                if body == b:   # (p_b - p_a) . n1 and t0 . n1, n1 turning with body b
                    d = self._ref_point(b, rb) - self._ref_point(a, ra)
                    mine[rows[0], cols] = [n1[0], n1[1], _perp(R) @ n1 + d @ _perp(n1)]
                    mine[rows[1], cols[2]] = t0 @ _perp(n1)
                else:
                    mine[rows[0], cols] = [-n1[0], -n1[1], -(_perp(R) @ n1)]
                    mine[rows[1], cols[2]] = _perp(t0) @ n1
        signs = np.ones(self.n_ae)
        for k, *_ in self._joints:
            for r in self.joint_ae[k]:
                s = 1.0 if C[r] @ mine[r] >= 0 else -1.0
                scale = max(np.abs(C[r]).max(), 1e-300)
                if np.abs(C[r] - s * mine[r]).max() > 1e-9 * scale:
                    raise SimModelError(
                        f"mechanism {self.tree.mech.name!r}: Exudyn's constraint row {r} "
                        f"(joint {self.tree.mech.joints[k].name!r}) is not the expected "
                        f"form: {C[r]} vs {s * mine[r]}")
                signs[r] = s
        # the drive row is q_b - q_a (rates): its acceleration equation is
        # row . q'' = +-acc with the sign of body b's (or sigma's) entry
        row = C[self.drive_ae]
        if self.sigma is not None:
            self._drive_sign = float(row[self.mbs.systemData.GetNodeLTGODE2(self.sigma)[0]])
        elif self._drive_b != self.g:
            self._drive_sign = float(row[self.ltg[self._drive_b][2]])
        else:
            self._drive_sign = -float(row[self.ltg[self._drive_a][2]])
        return signs

    def _readout(self, times, rows, rec: Recorder, q, qd, qdd, lam):
        """Fill ``rec`` from K records of coordinates, velocities, accelerations and
        multipliers; returns the loop gap (largest revolute gap, m) and driver rate."""
        st = self.tree
        mech = st.mech
        th, om, al, xG, vG, aG = self._bodies(q, qd, qdd)
        K, B = th.shape
        origin = xG - _world_many(th, np.array([self.com.get(b, np.zeros(2))
                                                for b in range(B)]))
        origin[:, self.g] = st.kin_ref.origin[0, self.g]
        J, P = len(mech.joints), len(st.prismatic)
        force = np.zeros((K, J, 2))
        sacc, normal, moment = np.zeros((K, P)), np.zeros((K, P)), np.zeros((K, P))
        effort = -lam[:, self.drive_ae]
        gap = np.zeros(K)

        def point(b, r):  # world position, velocity, acceleration of offset r of body b
            R = _world(th[:, b], r)
            if b == self.g:
                z = np.zeros_like(R)
                return R, z, z
            pR = _perp_rows(R)
            return (xG[:, b] + R, vG[:, b] + om[:, b, None] * pR,
                    aG[:, b] + al[:, b, None] * pR - (om[:, b] ** 2)[:, None] * R)

        for k, a, b, ra, rb, line in self._joints:
            L = lam[:, self.joint_ae[k]]
            jt = mech.joints[k]
            if line is None:
                force[:, k] = -L
                d = point(a, ra)[0] - point(b, rb)[0]
                gap = np.maximum(gap, np.hypot(d[:, 0], d[:, 1]))
                continue
            p = st.prismatic.index(k)
            ang = th[:, a] + jt.direction
            u = np.stack([np.cos(ang), np.sin(ang)], axis=1)
            n = _perp_rows(u)
            O, Ov, Oa = point(a, ra)
            S, Sv, Sa = point(b, rb)
            dd, dv, da = S - O, Sv - Ov, Sa - Oa
            wg, ag = om[:, a], al[:, a]
            # s = u . (S - O) differentiated twice with u turning with the guide
            sacc[:, p] = (_dot(ag[:, None] * n - (wg * wg)[:, None] * u, dd)
                          + 2 * wg * _dot(n, dv) + _dot(u, da))
            normal[:, p] = -L[:, 0]
            moment[:, p] = L[:, 1] + L[:, 0] * _dot(u, dd)
            if jt.name == mech.driver.joint:
                G = xG[:, b]
                moment[:, p] += _cross_rows(G - S, u) * effort
            force[:, k] = normal[:, p, None] * n
        value, rate = self._drivers(q, qd)
        rec.put_absolutes(rows, times, th, om, al, sacc, origin, value, rate)
        rec.put_forces_many(rows, force, effort, normal, moment)
        return gap, rate

    def _drivers(self, q, qd):
        """The driver's value (rad or m, unwrapped) and rate in the engine (K,)."""
        d = self.tree.mech.driver
        if self.sigma is not None:
            ls = self.mbs.systemData.GetNodeLTGODE2(self.sigma)[0]
            return d.value + q[:, ls], qd[:, ls]

        def rotation(x, v):  # rotation displacement (or rate) of body x (ground: 0)
            return v[:, self.ltg[x][2]] if x != self.g else np.zeros(len(v))

        a, b = self._drive_a, self._drive_b
        return (d.value + rotation(b, q) - rotation(a, q),
                rotation(b, qd) - rotation(a, qd))

