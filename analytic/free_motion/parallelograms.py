"""Exact, well-conditioned kinematics of a chain of parallelogram windows (IFToMM A02).

Why: at a change point of a parallelogram window (flat: zero base, or stretched) the
solver's dyad closed form and its loop Jacobian are singular.  Its positions there are
exact to ~1e-16/d (d the input's distance from the change point, rad), its
velocities, which go through the near-singular Jacobian, to ~1e-16/d^2 and its
accelerations to ~1e-16/d^3: measured on A02 (N = 8) 1e-3 rad from phi = -pi,
C(q) = M'(q)/2 (exactly 0) came out as 7e-6 kg m^2 and 3e-3 at 1e-4 rad.  DOP853 at
rtol 1e-13 reads that noise as error and shrinks its step without end (the published
20 s run never finished).

On the parallelogram branch no such division is needed: a window ``k1 - x1 - x2 - k3``
(the solver's RRR dyad placing ``x1, x2`` from the placed bodies ``k1, k3``, closed
by a revolute joint ``j0`` between ``k1`` and ``k3``) with equal opposite sides keeps
them parallel, so ``theta_x2 = theta_k1 + const`` and ``theta_x1 = theta_k3 + const``
and their rates are equal: an identity of that branch, exact at every input, change
points included.  The anti-parallelogram branch meets it only at the change points.

Which branch the solver is on is the solver's to say (its branch schedule continues
the branch whose velocity is continuous: the parallelogram).  :class:`Chain` checks it,
once per stretch between two consecutive change points of the schedule, at the middle
of that stretch (far from either change point, where the solver is exact to ~1e-15
and the two branches differ by O(1)): the solver's pose must agree with the chain's to
:data:`AGREE` of the size.  Where it does not, the solver's own kinematics are used.

Applies to linkages whose closed-form plan is a crank driven from ground followed only
by such windows, all revolute (the N four-bar of any N, a single parallelogram
four-bar); any other linkage returns ``None`` from :meth:`Chain.of`.
"""

from __future__ import annotations

import cmath
import math
from functools import cached_property

import numpy as np

from ..kin_result import Kinematics
from ..mechanism import Revolute, mechanism_size
from ..planar import cplx

#: Agreement of the solver's pose with the chain's at the middle of a stretch between
#: change points (fraction of the size; the solver is exact to ~1e-15 there, the
#: anti-parallelogram differs by O(1)).
AGREE = 1e-9
#: Relative equality of a window's opposite sides.
SIDES = 1e-12


class Chain:
    """The parallelogram windows of a linkage, in the solver's plan order."""

    def __init__(self, lk, drv: int, sign: float, windows):
        self.lk = lk
        self.drv, self.sign = drv, sign  # theta_drv = sign * q
        self.windows = windows  # (x1, k3, d1, x2, k1, d2): theta_x = theta_k + d
        self.size = mechanism_size(lk.mech.bodies) or 1.0
        self._verified: dict[int, bool] = {}
        self._cps = None  # (lo, hi, sorted change point values)

    @classmethod
    def of(cls, lk) -> Chain | None:
        """The chain of ``lk`` (a :class:`analytic.Linkage`), or ``None``."""
        topo = lk.topo
        mech = lk.mech
        if topo.plan is None or any(not isinstance(j, Revolute) for j in mech.joints):
            return None
        first, *rest = topo.plan
        if first.kind != "driven_revolute" or not rest:
            return None
        drv, jd = first.bodies[0], first.joints[0]
        if topo.other(jd, drv) != topo.ground:
            return None
        sign = 1.0 if mech.joints[jd].body_b == topo.body_names[drv] else -1.0
        windows = []
        for st in rest:
            w = _window(topo, st)
            if w is None:
                return None
            windows.append(w)
        return cls(lk, drv, sign, windows)

    # --- which stretches are on the parallelogram branch ---------------------------
    def _change_points(self, lo: float, hi: float) -> np.ndarray:
        c = self._cps
        if c is None or lo < c[0] or hi > c[1]:
            ref = self.lk.positions.reference
            lo2, hi2 = min(lo, ref) - 2 * math.pi, max(hi, ref) + 2 * math.pi
            if c is not None:
                lo2, hi2 = min(lo2, c[0]), max(hi2, c[1])
            vals = np.array(sorted(x.value for x in self.lk.branch_crossings(lo2, hi2)))
            self._cps = c = (lo2, hi2, vals)
        return c[2]

    def applies(self, q: np.ndarray) -> bool:
        """Whether every value of ``q`` lies on a stretch where the solver's branch is
        the parallelogram (checked once per stretch)."""
        lo, hi = float(np.min(q)), float(np.max(q))
        cps = self._change_points(lo - math.pi, hi + math.pi)
        for k in np.unique(np.searchsorted(cps, q)):
            k = int(k)
            if k not in self._verified:
                a = cps[k - 1] if k > 0 else cps[0] - math.pi if cps.size else lo - 1.0
                b = cps[k] if k < cps.size else (cps[-1] + math.pi if cps.size else hi + 1.0)
                self._verified[k] = self._agrees(0.5 * (a + b))
            if not self._verified[k]:
                return False
        return True

    def _agrees(self, v: float) -> bool:
        mine = self.kinematics(np.array([v]))
        # the solver's positions only (its rates and conditioning are not compared)
        _, _, E, O, _, _ = self.lk.positions.solve(np.array([v]))
        return bool(np.max(np.abs(O[0] - mine.zO[0])) <= AGREE * self.size
                    and np.max(np.abs(E[0] - mine.E[0])) <= AGREE)

    # --- the kinematics -------------------------------------------------------------
    def kinematics(self, q: np.ndarray) -> Kinematics:
        """The solver's :class:`Kinematics` quantities at ``q`` with unit input rate and
        zero input acceleration, from the parallelogram identities (exact everywhere on
        that branch).  ``jacobian`` and ``determinant`` are the solver's, computed when
        asked for."""
        lk, topo = self.lk, self.lk.topo
        q = np.asarray(q, float)
        N, B = len(q), len(topo.body_names)
        theta = np.zeros((N, B))
        omega = np.zeros((N, B))
        theta[:, self.drv] = self.sign * q
        omega[:, self.drv] = self.sign
        for x1, k3, d1, x2, k1, d2 in self.windows:
            theta[:, x1] = theta[:, k3] + d1
            theta[:, x2] = theta[:, k1] + d2
            omega[:, x1] = omega[:, k3]
            omega[:, x2] = omega[:, k1]
        alpha = np.zeros((N, B))
        E = np.exp(1j * theta)
        # every origin is a sum over its tree path of E_b times fixed body-frame vectors:
        # one product with the path matrix for positions, velocities, accelerations
        O = self._along_paths(E)
        zv = self._along_paths(1j * omega * E)
        za = self._along_paths((1j * alpha - omega * omega) * E)
        lead = topo.group_leader
        off = topo.offset[lead]
        qv = theta[:, lead] - off
        return _ChainKinematics(lk, q, np.ones(N), np.zeros(N), qv, omega[:, lead],
                                alpha[:, lead], theta, omega, alpha, E, O, zv, za, None, None,
                                [], {})

    def _along_paths(self, Z: np.ndarray) -> np.ndarray:
        """``(N, B)``: per body ``c``, the sum over ``b`` of ``Z_b T[b, c]`` (see
        :attr:`_paths`), summed without BLAS (a small complex product through a
        threaded BLAS cost 25 ms on a loaded machine)."""
        rows, vals, cols, starts = self._paths
        out = np.zeros(Z.shape, complex)
        if len(rows):
            out[:, cols] = np.add.reduceat(Z[:, rows] * vals, starts, axis=1)
        return out

    @cached_property
    def _paths(self):
        """The nonzeros of ``T`` (``(B, B)`` complex: origin ``c`` is the sum over
        ``b`` of ``E_b T[b, c]``, walking the spanning tree: ``O_c = O_p + E_p a_jp -
        E_c a_jc`` at the tree joint), grouped by column: rows, values, the columns
        and where each starts."""
        topo = self.lk.topo
        B = len(topo.body_names)
        T = np.zeros((B, B), complex)
        for c in topo.order[1:]:
            p, j = topo.parent[c]
            T[:, c] = T[:, p]
            T[p, c] += cplx(topo.attach(j, p))
            T[c, c] -= cplx(topo.attach(j, c))
        r, c = np.nonzero(T.T)  # column-major: grouped by column
        cols, starts = np.unique(r, return_index=True)
        return c, T[c, r], cols, starts


def _window(topo, st):
    """``(x1, k3, d1, x2, k1, d2)`` of an RRR step closing a parallelogram, else None."""
    if st.kind != "RRR":
        return None
    (x1, x2), (j1, j2, j3) = st.bodies, st.joints
    k1, k3 = topo.other(j1, x1), topo.other(j3, x2)
    mech = topo.mech
    names = topo.body_names
    j0 = next((j for j, jt in enumerate(mech.joints)
               if {jt.body_a, jt.body_b} == {names[k1], names[k3]} and k1 != k3), None)
    if j0 is None:
        return None
    a = cplx
    s_k1 = a(topo.attach(j1, k1)) - a(topo.attach(j0, k1))   # P0 -> P1
    s_x1 = a(topo.attach(j2, x1)) - a(topo.attach(j1, x1))   # P1 -> P2
    s_x2 = a(topo.attach(j2, x2)) - a(topo.attach(j3, x2))   # P3 -> P2
    s_k3 = a(topo.attach(j3, k3)) - a(topo.attach(j0, k3))   # P0 -> P3
    for u, v in ((s_k1, s_x2), (s_x1, s_k3)):
        if not abs(u) > 0 or abs(abs(u) - abs(v)) > SIDES * (abs(u) + abs(v)):
            return None
    # parallelogram: P2 - P3 = P1 - P0 and P2 - P1 = P3 - P0, as world vectors
    d2 = cmath.phase(s_k1) - cmath.phase(s_x2)
    d1 = cmath.phase(s_k3) - cmath.phase(s_x1)
    return x1, k3, d1, x2, k1, d2


class _ChainKinematics(Kinematics):
    """:class:`Kinematics` of a :class:`Chain`; the loop Jacobian and its determinant
    (diagnostics, not on the equation's path) are the solver's, on first use."""

    def __init__(self, *args):
        super().__init__(*args)
        del self.__dict__["jacobian"], self.__dict__["determinant"]

    def __getattr__(self, name):
        d = self.__dict__
        if name == "determinant":  # the events' sign test: positions and Jacobian only
            d[name] = d["linkage"].loop_determinant(d["value"])
            return d[name]
        if name == "jacobian":
            kin = d["linkage"].kinematics(d["value"], 1.0, 0.0, on_singular="flag")
            d["jacobian"] = kin.jacobian
            return d[name]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
