"""The vector-loop equations and their time derivatives, vectorised over N inputs.

With the loop vectors ``m_t mu(phi_t)`` of :class:`analytic.topology.LoopTerms`
(``mu = (cos, sin)``, ``sigma = (-sin, cos)``), each loop ``l`` satisfies

* position:      ``f_l(q) = sum_t m_t mu(phi_t) = 0``
* velocity:      ``sum_t (m'_t mu + m_t phi'_t sigma) = J(q) q' = 0``
* acceleration:  ``J(q) q'' + gamma(q, q') = 0`` with
  ``gamma = sum_t (2 m'_t phi'_t sigma - m_t phi'_t^2 mu)``

because ``d mu/dt = phi' sigma`` and ``d sigma/dt = -phi' mu``.  The Jacobian
column of a group angle is ``sum m_t sigma(phi_t)``, of a slider displacement
``sign_t mu(phi_t)``.  The driver adds the linear row ``c . q = value + const``.
"""

from __future__ import annotations

import numpy as np

from .linalg import cmatmul, solve_small
from .topology import Topology

#: Size of the dense term-to-Jacobian maps (terms x loops x unknowns) above which
#: :meth:`LoopEquations.jacobian` uses sparse ones.
_DENSE_LIMIT = 200_000


class LoopEquations:
    """Evaluate ``f``, ``J`` and ``gamma`` for a topology.  Rows are ordered
    ``[x_0, y_0, x_1, y_1, ...]`` (loop by loop), columns as ``q``."""

    def __init__(self, topo: Topology):
        t = topo.terms
        self.topo = topo
        self.ng = topo.n_groups
        self.ns = len(topo.prismatic)
        self.nq = topo.nq
        self.L = topo.n_loops
        T = len(t.loop)
        # group/slider index into arrays padded with a trailing zero column
        self.gi = np.where(t.group >= 0, t.group, self.ng)
        self.si = np.where(t.slider >= 0, t.slider, self.ns)
        self.beta = t.beta
        self.r = t.r
        self.sign = t.sign
        self.Lmat = np.zeros((T, self.L))
        self.Lmat[np.arange(T), t.loop] = 1.0
        self.Eq = np.zeros((T, self.L, self.nq))
        self.Es = np.zeros((T, self.L, self.nq))
        for k in range(T):
            if t.group[k] >= 0:
                self.Eq[k, t.loop[k], t.group[k]] = 1.0
            if t.slider[k] >= 0:
                self.Es[k, t.loop[k], self.ng + t.slider[k]] = t.sign[k]
        self.Eq = self.Eq.reshape(T, self.L * self.nq)  # explicit: T = 0 for an open chain
        # term direction = E of one body of its group (the ground for the ground group)
        # times exp(i (beta - that body's offset from its group angle))
        lead = topo.group_leader
        self.term_body = np.array([lead[g] if g >= 0 else topo.ground for g in t.group], int)
        self.term_rot = np.exp(1j * (self.beta - topo.offset[self.term_body]))
        self.Es = self.Es.reshape(T, self.L * self.nq)
        # a large chain (the IFToMM N four-bar: 40 loops, 81 unknowns) has one entry
        # per row in Eq and Es: a sparse product is ~100x cheaper than the dense one
        self._sparse = None
        if T * self.L * self.nq > _DENSE_LIMIT:
            from scipy.sparse import csr_array
            self._sparse = (csr_array(self.Eq).T.tocsr(), csr_array(self.Es).T.tocsr())

    def terms(self, q: np.ndarray):
        """The loop vectors' unit directions ``exp(i phi) (N, T)`` and lengths ``m``."""
        N = q.shape[0]
        z = np.zeros((N, 1))
        th = np.concatenate([q[:, :self.ng], z], axis=1)
        s = np.concatenate([q[:, self.ng:], z], axis=1)
        phi = th[:, self.gi] + self.beta
        m = self.r + self.sign * s[:, self.si]
        return np.exp(1j * phi), m

    def terms_from_poses(self, q: np.ndarray, E: np.ndarray):
        """As :meth:`terms`, from the bodies' ``exp(i theta)``: each term's direction is
        one body's ``E`` times a constant (the ground's ``E`` is 1), no trigonometry."""
        ez = E[:, self.term_body] * self.term_rot
        if not self.ns:
            return ez, self.r
        return ez, self.r + self.sign * np.concatenate(
            [q[:, self.ng:], np.zeros((q.shape[0], 1))], axis=1)[:, self.si]

    def _rows(self, z: np.ndarray) -> np.ndarray:
        """Complex per-loop sums ``(N, L, ...)`` -> real rows ``(N, 2L, ...)`` (x, y)."""
        N = z.shape[0]
        out = np.stack([z.real, z.imag], axis=2)
        return out.reshape(N, 2 * self.L, *z.shape[2:])

    def residual(self, q: np.ndarray, pre=None) -> np.ndarray:
        """Loop closure residual ``(N, 2L)`` in m: sum of ``m mu(phi)`` per loop."""
        ez, m = pre if pre is not None else self.terms(q)
        return self._rows(cmatmul(m * ez, self.Lmat))

    def jacobian(self, q: np.ndarray, pre=None) -> np.ndarray:
        """``(N, 2L, nq)``: column of a group angle ``sum m sigma(phi)``, of a slider
        displacement ``sign mu(phi)`` (``sigma = i mu``)."""
        ez, m = pre if pre is not None else self.terms(q)
        N = q.shape[0]
        if self._sparse is not None:
            EqT, EsT = self._sparse
            cz = (EqT @ ((1j * m) * ez).T + EsT @ np.broadcast_to(ez, (N, ez.shape[1])).T).T
        else:
            cz = cmatmul((1j * m) * ez, self.Eq) + cmatmul(ez, self.Es)
        return self._rows(cz.reshape(N, self.L, self.nq))

    def gamma(self, q: np.ndarray, qd: np.ndarray, pre=None) -> np.ndarray:
        """``(N, 2L)`` velocity-product terms: ``sum (2 m' phi' sigma - m phi'^2 mu)``."""
        ez, m = pre if pre is not None else self.terms(q)
        N = q.shape[0]
        z = np.zeros((N, 1))
        w = np.concatenate([qd[:, :self.ng], z], axis=1)[:, self.gi]
        if not self.ns:
            return self._rows(cmatmul((-m * w * w) * ez, self.Lmat))
        md = self.sign * np.concatenate([qd[:, self.ng:], z], axis=1)[:, self.si]
        return self._rows(cmatmul((2j * md * w - m * w * w) * ez, self.Lmat))

    # -- the square system with the driver row -------------------------------
    def split(self, J: np.ndarray):
        """Partition ``J`` into the columns of the unknowns and of the driven variable.

        Returns ``(A, col_d)`` where ``A`` is the square system for the unknown
        variables and ``col_d`` the driven variable's column (or ``None`` when the
        driver is a general linear row, in which case ``A`` includes that row).
        """
        k = self.topo.driven_var
        if k is not None:
            keep = [i for i in range(self.nq) if i != k]
            return J[:, :, keep], J[:, :, k]
        N = J.shape[0]
        row = np.broadcast_to(self.topo.driver_row, (N, 1, self.nq))
        return np.concatenate([J, row], axis=1), None

    def solve_rates(self, J: np.ndarray, rhs_loops: np.ndarray, drive_rate: np.ndarray):
        """Solve ``J x = rhs_loops`` with the driver row ``c . x = drive_rate``.

        ``x`` is q' (rhs 0) or q'' (rhs ``-gamma``).  Returns ``(N, nq)``.
        """
        k = self.topo.driven_var
        A, col = self.split(J)
        N = J.shape[0]
        if k is not None:
            xd = drive_rate / self.topo.driver_row[k]
            rhs = rhs_loops - col * xd[:, None]
            xu = solve_small(A, rhs) if A.shape[-1] else np.zeros((N, 0))
            return np.insert(xu, k, xd, axis=1)
        rhs = np.concatenate([rhs_loops, drive_rate[:, None]], axis=1)
        return solve_small(A, rhs)

    def driver_value(self, q: np.ndarray) -> np.ndarray:
        """The driver coordinate ``c . q - const`` (rad or m)."""
        return q @ self.topo.driver_row - self.topo.driver_const
