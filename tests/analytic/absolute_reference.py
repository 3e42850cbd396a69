"""An independent free-motion reference for revolute-jointed planar linkages: Newton-Euler
in absolute coordinates (x, y of each body's centre of mass, theta), the pin constraints
with Lagrange multipliers (index 1, Baumgarte-stabilised so that the integration's drift
decays instead of growing), integrated by SciPy's DOP853 at a tight tolerance.

Nothing here comes from the analytic solver except the initial state (every body's
centre of mass, angle and their rates at t = 0, which the solver's closed form gives to
rounding).  Force elements: gravity, point springs, joint dampers and joint springs on
revolute joints, constant motors on revolute joints.  The joint coordinate of a revolute
joint is ``theta_b - theta_a`` (as in :mod:`analytic.free_motion`).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from analytic.motion_spec import JointDamper, JointSpring, PointSpring

#: Baumgarte's gains (1/s): critically damped drift of the constraint, time constant
#: 1/50 s, far slower than DOP853's steps so the stabilisation stays non-stiff.
BAUMGARTE = 50.0


class AbsoluteModel:
    """The equations of motion of ``mech`` in absolute coordinates."""

    def __init__(self, mech):
        self.mech = mech
        self.bodies = [b for b in mech.bodies if b.name != mech.ground]
        self.idx = {b.name: i for i, b in enumerate(self.bodies)}
        self.nb = len(self.bodies)
        self.Mdiag = np.concatenate([[b.mass, b.mass, b.inertia] for b in self.bodies])
        self.g = np.array(mech.gravity, float)
        self.pins = [(j.body_a, j.point_a, j.body_b, j.point_b) for j in mech.joints]
        fm = mech.motion
        self.springs, self.dampers, self.motors = fm.springs, fm.dampers, fm.motors

    def point(self, z, zd, body, pt):
        """World position, velocity and the body-frame lever (rotated) of a body point."""
        if body == self.mech.ground:
            return np.array(self.mech.body(body).points[pt], float), np.zeros(2), None
        i = self.idx[body]
        b = self.bodies[i]
        th, w = z[3 * i + 2], zd[3 * i + 2]
        c, s = math.cos(th), math.sin(th)
        r = np.array(b.points[pt], float) - np.array(b.com, float)
        Rr = np.array([c * r[0] - s * r[1], s * r[0] + c * r[1]])
        return z[3 * i:3 * i + 2] + Rr, zd[3 * i:3 * i + 2] + w * np.array([-Rr[1], Rr[0]]), Rr

    def angle(self, z, zd, body):
        if body == self.mech.ground:
            return 0.0, 0.0
        i = self.idx[body]
        return z[3 * i + 2], zd[3 * i + 2]

    def _apply(self, F, body, force, Rr):
        if body == self.mech.ground:
            return
        i = self.idx[body]
        F[3 * i:3 * i + 2] += force
        F[3 * i + 2] += Rr[0] * force[1] - Rr[1] * force[0]

    def _torque(self, F, body, tau):
        if body != self.mech.ground:
            F[3 * self.idx[body] + 2] += tau

    def forces(self, z, zd, t):
        F = np.concatenate([[b.mass * self.g[0], b.mass * self.g[1], 0.0] for b in self.bodies])
        for s in self.springs:
            if isinstance(s, PointSpring):
                pa, _, ra = self.point(z, zd, s.body_a, s.point_a)
                pb, _, rb = self.point(z, zd, s.body_b, s.point_b)
                d = pb - pa
                L = math.hypot(*d)
                f = s.stiffness * (L - s.free_length) * d / L  # pulls b towards a
                self._apply(F, s.body_a, f, ra)
                self._apply(F, s.body_b, -f, rb)
            else:
                assert isinstance(s, JointSpring)
                jt = self.mech.joint(s.joint)
                tau = -s.stiffness * (self.angle(z, zd, jt.body_b)[0]
                                      - self.angle(z, zd, jt.body_a)[0] - s.free_value)
                self._torque(F, jt.body_b, tau)
                self._torque(F, jt.body_a, -tau)
        for d in self.dampers:
            assert isinstance(d, JointDamper)
            jt = self.mech.joint(d.joint)
            tau = -d.coefficient * (self.angle(z, zd, jt.body_b)[1]
                                    - self.angle(z, zd, jt.body_a)[1])
            self._torque(F, jt.body_b, tau)
            self._torque(F, jt.body_a, -tau)
        for mo in self.motors:
            jt = self.mech.joint(mo.joint)
            tau = mo.at(t)
            self._torque(F, jt.body_b, tau)
            self._torque(F, jt.body_a, -tau)
        return F

    def constraints(self, z, zd):
        n = 3 * self.nb
        C, J, gam = [], np.zeros((2 * len(self.pins), n)), []
        for k, (ba, pa, bb, pb) in enumerate(self.pins):
            Pa, _, ra = self.point(z, zd, ba, pa)
            Pb, _, rb = self.point(z, zd, bb, pb)
            C.append(Pa - Pb)
            g = np.zeros(2)
            for sgn, b, Rr in ((1.0, ba, ra), (-1.0, bb, rb)):
                if Rr is None:
                    continue
                i = self.idx[b]
                J[2 * k:2 * k + 2, 3 * i:3 * i + 2] += sgn * np.eye(2)
                J[2 * k:2 * k + 2, 3 * i + 2] += sgn * np.array([-Rr[1], Rr[0]])
                g += sgn * zd[3 * i + 2] ** 2 * Rr  # -(dJ/dt) zd
            gam.append(g)
        return np.concatenate(C), J, np.concatenate(gam)

    def solve(self, t, y):
        """Accelerations and multipliers; the multipliers of pin k, ``sol[n + 2k:n + 2k
        + 2]``, are the force by body_a on body_b (N, world frame)."""
        n = 3 * self.nb
        z, zd = y[:n], y[n:]
        C, J, gam = self.constraints(z, zd)
        a = BAUMGARTE
        rc = gam - 2 * a * (J @ zd) - a * a * C
        m = len(C)
        A = np.zeros((n + m, n + m))
        A[:n, :n] = np.diag(self.Mdiag)
        A[:n, n:] = J.T
        A[n:, :n] = J
        return np.linalg.lstsq(A, np.concatenate([self.forces(z, zd, t), rc]), rcond=None)[0]

    def rhs(self, t, y):
        n = 3 * self.nb
        return np.concatenate([y[n:], self.solve(t, y)[:n]])


def initial_state(mech, lk, value: float, rate: float) -> np.ndarray:
    """Absolute coordinates and rates at the release, from the solver's closed form at
    the released joint's value (a position solution only: no dynamics)."""
    model = AbsoluteModel(mech)
    kin = lk.kinematics(np.array([value]), rate, 0.0)
    z, zd = np.zeros(3 * model.nb), np.zeros(3 * model.nb)
    for b in model.bodies:
        i, k = mech.bodies.index(b), model.idx[b.name]
        r, v, _ = kin.com(i)
        z[3 * k:3 * k + 3] = [r[0, 0], r[0, 1], kin.theta[0, i]]
        zd[3 * k:3 * k + 3] = [v[0, 0], v[0, 1], kin.omega[0, i]]
    return np.concatenate([z, zd])


def joint_history(mech, lk, times, rtol: float = 1e-13, reactions: dict | None = None,
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Every joint's coordinate and rate ``(N, J)`` at ``times`` from the release of
    ``mech.motion`` (``lk``: a Linkage driven at the released joint, for the start);
    ``reactions``, if given, is filled with joint -> ``(N, 2)`` forces by body_a on
    body_b (N), the pins' Lagrange multipliers."""
    fm = mech.motion
    model = AbsoluteModel(mech)
    y0 = initial_state(mech, lk, fm.value, fm.rate)
    sol = solve_ivp(model.rhs, (0.0, float(times[-1])), y0, method="DOP853", rtol=rtol,
                    atol=rtol * 1e-2, t_eval=times)
    assert sol.success, sol.message
    n = 3 * model.nb
    if reactions is not None:
        lam = np.array([model.solve(t, sol.y[:, i])[n:] for i, t in enumerate(times)])
        for k, jt in enumerate(mech.joints):
            reactions[jt.name] = lam[:, 2 * k:2 * k + 2]
    x = np.zeros((len(times), len(mech.joints)))
    xd = np.zeros_like(x)
    for k, jt in enumerate(mech.joints):
        for i in range(len(times)):
            z, zd = sol.y[:n, i], sol.y[n:, i]
            (tb, wb), (ta, wa) = model.angle(z, zd, jt.body_b), model.angle(z, zd, jt.body_a)
            x[i, k], xd[i, k] = tb - ta, wb - wa
    return x, xd
