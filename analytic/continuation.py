"""Continuation of an assembled branch along the input, for mechanisms without a dyad plan.

From the reference assembly the branch is traced in both directions with
natural-parameter continuation (tangent predictor, Newton corrector, step halving).
The trace ends at a limit position, where the input cannot go further on this branch
(a fold: the two halves of the branch meet and the loop Jacobian in the unknowns is
singular), located by bisection to :data:`LIMIT_BISECTION`; or, for a revolute input,
after one turn when the pose repeats.  A singular position the branch passes through
(a change point: the determinant changes sign along a continuous branch) is crossed
and recorded.

Kinematics at arbitrary input values then start Newton from the trace (linear
interpolation between its nodes, periodic for a full turn), so every value lands on
the traced branch, in any order and over any number of turns.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .errors import AssemblyError
from .loops import LoopEquations
from .mechanism import Revolute
from .positions import _fmt_value, newton, size_of, step_limits
from .tolerances import LIMIT_BISECTION

#: Largest continuation step: 1 deg of a revolute input, 1/200 of the size for a slider.
_STEP_DEG = 1.0


@dataclass
class Trace:
    """The assembled branch sampled along the input.

    ``x`` (M,) ascending input values (SI), ``q`` (M, nq) the unknowns there.
    ``period`` is 2 pi when the branch closes after one turn of a revolute input
    (then ``shift`` is ``q(x + period) - q(x)``: whole turns of the group angles),
    else ``None`` and ``[x[0], x[-1]]`` is the feasible range, ending at the limit
    positions listed in ``limits``.  ``crossings`` are the singular positions passed.
    """

    eqs: LoopEquations
    x: np.ndarray
    q: np.ndarray
    tol: float
    period: float | None
    shift: np.ndarray
    limits: list[float] = field(default_factory=list)
    crossings: list[float] = field(default_factory=list)

    @property
    def feasible(self) -> list[tuple[float, float]]:
        if self.period is not None:
            return [(float(self.x[0]), float(self.x[0] + self.period))]
        return [(float(self.x[0]), float(self.x[-1]))]

    def start(self, values: np.ndarray) -> np.ndarray:
        """Newton starts ``(N, nq)`` on the traced branch (linear interpolation)."""
        x, q = self.x, self.q
        if self.period is not None:
            turns = np.floor((values - x[0]) / self.period)
            u = values - turns * self.period
        else:
            turns, u = np.zeros(len(values)), values
        k = np.clip(np.searchsorted(x, u) - 1, 0, len(x) - 2)
        w = ((u - x[k]) / (x[k + 1] - x[k]))[:, None]
        return q[k] * (1 - w) + q[k + 1] * w + turns[:, None] * self.shift

    def solve(self, values: np.ndarray) -> np.ndarray:
        """The unknowns ``(N, nq)`` at each input value, on the traced branch.

        Raises :class:`AssemblyError` for a value outside the feasible range (with
        the range) or where Newton fails to converge.
        """
        topo = self.eqs.topo
        values = np.asarray(values, float)
        u = values
        if self.period is None:
            lo, hi = self.x[0], self.x[-1]
            if isinstance(topo.mech.driver_joint, Revolute):
                # an angle a whole turn off the range is the same position (200 deg is
                # -160 deg): solve there with the input variable shifted by the turns
                u = np.where((values >= lo) & (values <= hi), values,
                             lo + np.mod(values - lo, 2 * math.pi))
            out = np.flatnonzero(~((u >= lo) & (u <= hi)))
            if out.size:
                v = float(values[out[0]])
                raise AssemblyError(
                    f"mechanism {topo.mech.name!r}: the loops cannot close at driver "
                    f"{topo.mech.driver.joint!r} = {_fmt_value(topo, v)} on the assembled "
                    f"branch; feasible input range: [{_fmt_value(topo, lo)}, "
                    f"{_fmt_value(topo, hi)}] (limit positions)", v, self.feasible)
        if not len(values):
            return np.zeros((0, topo.nq))
        q0 = self.start(u)
        c = topo.driver_row
        q0 = q0 + np.outer(values - u, c / (c @ c))
        q, ok = newton(self.eqs, q0, values, self.tol)
        # the trace's nodes are dense, so a start converges to its own branch; a start
        # that strays more than a step's worth of the branch is rejected
        far = np.max(np.abs(q - q0) / step_limits(topo), axis=1) > 0.2
        bad = np.flatnonzero(~ok | far)
        if bad.size:
            v = float(values[bad[0]])
            raise AssemblyError(
                f"mechanism {topo.mech.name!r}: Newton-Raphson did not converge on the "
                f"assembled branch at driver {topo.mech.driver.joint!r} = "
                f"{_fmt_value(topo, v)}", v, self.feasible)
        return q


def _det(eqs: LoopEquations, q: np.ndarray) -> float:
    """Determinant of the loop Jacobian in the unknowns, column-normalised."""
    A, _ = eqs.split(eqs.jacobian(q[None]))
    A = A[0]
    if not A.shape[-1]:
        return 1.0
    n = np.linalg.norm(A, axis=0)
    return float(np.linalg.det(A / np.where(n > 0, n, 1.0)))


def _tangent(eqs: LoopEquations, q: np.ndarray) -> np.ndarray:
    with np.errstate(all="ignore"):
        t = eqs.solve_rates(eqs.jacobian(q[None]), np.zeros((1, 2 * eqs.L)), np.ones(1))[0]
    return t if np.all(np.isfinite(t)) else np.zeros_like(q)


class _Walker:
    """One direction of the continuation (``d`` = +1 or -1)."""

    def __init__(self, eqs, tol, d, h_max, h_min, lim):
        self.eqs, self.tol, self.d = eqs, tol, d
        self.h_max, self.h_min, self.lim = h_max, h_min, lim

    def corrector(self, q, xn, guesses):
        for g in guesses:
            qn, ok = newton(self.eqs, g[None], np.array([xn]), self.tol, max_iter=8)
            if ok[0] and np.max(np.abs(qn[0] - q) / self.lim) <= 1.0:
                return qn[0]
        return None

    def step(self, x, q, h):
        """Try the step from ``x`` by ``d * h``: ``(qn, det)`` or ``None``."""
        xn = x + self.d * h
        t = _tangent(self.eqs, q)
        return self.corrector(q, xn, (q + t * (xn - x), q))

    def crossing(self, x, q, s, xn, qn):
        """``det`` changes sign between ``(x, q)`` and ``(xn, qn)``: bisect, starting
        each midpoint on the chord between the bracketing solutions (from one end
        alone, Newton at a bifurcation may take either branch).  Returns the singular
        input when the branch passes continuously through it (a change point), ``None``
        when the corrector had jumped to the other half of a fold (the bracketing
        solutions then stay apart as the bracket shrinks)."""
        a, qa, b, qb = x, q, xn, qn
        while abs(b - a) > self.h_min:
            m = 0.5 * (a + b)
            qm = self.corrector(qa, m, (0.5 * (qa + qb), qa))
            if qm is None:
                return None
            if np.sign(_det(self.eqs, qm)) == s:
                a, qa = m, qm
            else:
                b, qb = m, qm
        gap = np.max(np.abs(qb - qa) / self.lim)
        return 0.5 * (a + b) if gap < 1e-4 else None


def trace_branch(eqs: LoopEquations, q0: np.ndarray, v0: float, tol: float) -> Trace:
    """Trace the branch through ``(v0, q0)`` in both directions (see module docstring)."""
    topo = eqs.topo
    rev = isinstance(topo.mech.driver_joint, Revolute)
    size = size_of(topo)
    h_max = math.radians(_STEP_DEG) if rev else size / 200
    h_min = LIMIT_BISECTION * (1.0 if rev else size)
    reach = 2 * math.pi if rev else 4 * size
    lim = step_limits(topo)
    sides, limits, crossings = {}, [], []
    period = None
    for d in (1, -1):
        w = _Walker(eqs, tol, d, h_max, h_min, lim)
        xs, qs = [v0], [q0]
        x, q, h = v0, q0, h_max
        s = np.sign(_det(eqs, q0))
        while True:
            if abs(x + d * h - v0) >= reach:
                h = reach - abs(x - v0)
            if h <= 0:
                break
            qn = w.step(x, q, h)
            if qn is not None:
                sn = np.sign(_det(eqs, qn))
                if sn != s and s != 0 and sn != 0:
                    xc = w.crossing(x, q, s, x + d * h, qn)
                    if xc is None:  # jumped across a fold
                        qn = None
                    else:
                        crossings.append(xc)
                        s = sn
            if qn is None:
                if h <= h_min:
                    limits.append(x)
                    break
                h *= 0.5
                continue
            x, q = x + d * h, qn
            xs.append(x)
            qs.append(q)
            h = min(2 * h, h_max)
        sides[d] = (xs, qs)
        if d == 1 and rev and abs(x - v0 - reach) < 1e-12:
            dq = q - q0
            turns = np.round(dq[:topo.n_groups] / (2 * math.pi))
            rest = dq.copy()
            rest[:topo.n_groups] -= 2 * math.pi * turns
            if np.max(np.abs(rest) / lim) < 1e-6:
                period = 2 * math.pi
                shift = np.zeros_like(q0)
                shift[:topo.n_groups] = 2 * math.pi * turns
                # the input's own variable moves by the period through the driver row
                break
    if period is not None:
        xs, qs = sides[1]
        return Trace(eqs, np.array(xs), np.array(qs), tol, period, shift, [], crossings)
    xf, qf = sides[1]
    xb, qb = sides.get(-1, ([v0], [q0]))
    x = np.array(xb[::-1] + xf[1:])
    q = np.array(qb[::-1] + qf[1:])
    return Trace(eqs, x, q, tol, None, np.zeros(topo.nq), sorted(limits), sorted(crossings))
