"""The position solver of a :class:`analytic.kinematics.Linkage`: the assembly at the
reference input, and the branch followed from it to any input value.

With a dyad plan the assembly is a choice of dyad signs
(:func:`analytic.positions.choose_branches`) and :class:`analytic.branches.BranchSchedule`
says which signs hold where; without one it is a Newton-Raphson assembly
(:func:`analytic.positions.assemble`) whose branch
:func:`analytic.continuation.trace_branch` traces along the input.  Either way the
assembly must lie near the hints (:func:`analytic.positions.check_hints`) and every
solution is checked against the loop residual.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from .branches import BranchSchedule
from .continuation import trace_branch
from .errors import AssemblyError
from .loops import LoopEquations
from .positions import (
    ClosedForm,
    _fmt_value,
    _infeasible,
    assemble,
    check_hints,
    choose_branches,
    feasible_ranges,
    poses_from_q,
    q_from_poses,
    size_of,
)
from .tolerances import LOOP_RESIDUAL, TOGGLE_SNAP
from .topology import Topology


class PositionSolver:
    """Solve positions for any input values; remembers the branch choice.

    The assembly at the reference input is the one nearest the hints (closed form: the
    dyad signs; otherwise :func:`assemble`), and it must lie within
    :data:`HINT_DISTANCE` of them (:func:`check_hints`).  Other inputs continue that
    assembly along the input axis (see :meth:`solve`).

    ``branch_rule`` says what to do at a change point (two branches crossing):
    ``"continuous"`` (default) continues the branch whose velocity is continuous and,
    where that cannot decide, holds the dyad signs; ``"hold"`` always holds them;
    ``"switch"`` always switches the touching dyads.
    """

    RULES = ("continuous", "hold", "switch")

    def __init__(self, topo: Topology, eqs: LoopEquations, branch_rule: str = "continuous"):
        if branch_rule not in self.RULES:
            raise ValueError(f"branch_rule must be one of {self.RULES}, got {branch_rule!r}")
        self.topo, self.eqs = topo, eqs
        self.branch_rule = branch_rule
        self.size = size_of(topo)
        self.tol = LOOP_RESIDUAL * self.size
        self.cf = ClosedForm(topo) if topo.plan is not None else None
        v0 = topo.mech.driver.value
        self.reference = v0
        if self.cf is not None:
            self.signs = choose_branches(topo, self.cf, v0)
            th, E, O, _, _ = self.cf.run(np.array([v0]), self.signs)
        else:
            self.q_ref = assemble(topo, eqs, v0, self.tol)
            th, E, O = poses_from_q(topo, self.q_ref)
        check_hints(topo, th, E, O, v0)

    @cached_property
    def schedule(self):
        """The dyad signs along the input axis (:class:`analytic.branches.BranchSchedule`);
        ``None`` on the Newton path."""
        if self.cf is None:
            return None
        return BranchSchedule(self.topo, self.cf, self.signs, self.reference, self.branch_rule)

    @cached_property
    def trace(self):
        """The assembled branch traced over the input (:class:`analytic.continuation.Trace`);
        ``None`` on the dyad path."""
        if self.cf is not None:
            return None
        return trace_branch(self.eqs, self.q_ref[0], self.reference, self.tol)

    def feasible(self) -> list[tuple[float, float]]:
        """Input intervals (SI) the assembled branch reaches (see :func:`feasible_ranges`)."""
        if self.cf is None:
            return self.trace.feasible
        return feasible_ranges(self.topo, signs=self.signs)

    def solve(self, values: np.ndarray, branch: str = "continued"):
        """Positions for sorted or unsorted input values (SI).

        ``values`` lie on the input axis reached by moving the input continuously from
        the reference value (so 2 pi and 0 are different after a change point):
        ``branch="continued"`` follows the assembled branch through change points as
        the linkage moves (:attr:`schedule`, :attr:`trace`); ``"held"`` holds the
        reference dyad signs (the closed form's old behaviour).

        Returns ``(q, theta, E, O, trans, pre)``: the loop unknowns ``(N, nq)``, body
        angles ``(N, B)``, ``exp(i theta)`` and origins (complex ``(N, B)``), the
        dyads' transmission data and the loop vectors (:meth:`LoopEquations.terms`).

        Raises
        ------
        AssemblyError
            At the first value where a loop cannot close, with the feasible ranges,
            or when the loop residual exceeds the tolerance.
        """
        values = np.asarray(values, float)
        trans = []
        if self.cf is not None:
            theta, E, O, disc, trans = self._closed_form(values, branch)
            if disc.size:
                bad = np.flatnonzero(np.any(disc < -TOGGLE_SNAP, axis=1))
                if bad.size:
                    raise _infeasible(self.topo, float(values[bad[0]]))
            q = q_from_poses(self.topo, theta, E, O)
            # body angles continuous over the batch, like the unwrapped q
            for b, g in enumerate(self.topo.group_of):
                if g >= 0:
                    theta[:, b] = q[:, g] + self.topo.offset[b]
        else:
            if len(values) and np.all(values == self.reference):
                q = np.repeat(self.q_ref, len(values), axis=0)  # no trace needed
            else:
                q = self.trace.solve(values)
            theta, E, O = poses_from_q(self.topo, q)
        pre = self.eqs.terms_from_poses(q, E)
        if self.eqs.L and len(q):
            # one flat reduction: a reduction along the short axis costs 20x more
            res = np.abs(self.eqs.residual(q, pre))
            k = int(np.argmax(res))
            if not res.flat[k] <= self.tol:
                worst = k // res.shape[1]
                raise AssemblyError(
                    f"mechanism {self.topo.mech.name!r}: loop residual {res.flat[k]:.3g} m "
                    f"at driver = {_fmt_value(self.topo, float(values[worst]))} exceeds "
                    f"{self.tol:.3g} m", float(values[worst]))
        return q, theta, E, O, trans, pre

    def _closed_form(self, values, branch):
        """The closed form with each value's dyad signs from the schedule."""
        if branch == "held" or not len(values) or self.schedule.constant:
            return self.cf.run(values, self.signs)
        combos, idx = self.schedule.signs_for(values)
        if len(combos) == 1:
            return self.cf.run(values, combos[0])
        N, B = len(values), len(self.topo.body_names)
        theta, E, O = np.zeros((N, B)), np.ones((N, B), complex), np.zeros((N, B), complex)
        disc = None
        trans = None
        for k, sg in enumerate(combos):
            sel = np.flatnonzero(idx == k)
            th_, E_, O_, d_, tr_ = self.cf.run(values[sel], sg)
            theta[sel], E[sel], O[sel] = th_, E_, O_
            if disc is None:
                disc = np.zeros((N, d_.shape[1]))
                trans = [(n, np.zeros(N, complex), np.zeros(N, complex)) for n, _, _ in tr_]
            disc[sel] = d_
            for (_, a, b), (_, a_, b_) in zip(trans, tr_, strict=True):
                a[sel], b[sel] = a_, b_
        return theta, E, O, disc, trans
