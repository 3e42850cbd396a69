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
from functools import cached_property

import numpy as np

from .errors import SingularConfigurationError
from .fused import dispatch as fused_dispatch
from .kin_result import DEFERRED, CompactKinematics, Kinematics  # noqa: F401 - re-exported
from .linalg import condition, det_small
from .loops import LoopEquations
from .mechanism import Mechanism, Revolute
from .planar import cplx
from .position_solver import PositionSolver
from .positions import size_of
from .tolerances import SINGULAR_CONDITION
from .topology import Topology, build_topology


class _ForcesGuess:
    """Marks a kinematics result whose pass also wrote the forces unasked
    (:meth:`Linkage._forces_guess`): ``used`` once :meth:`Linkage.forces` reads them."""

    __slots__ = ("used",)

    def __init__(self):
        self.used = False


class Linkage:
    """A compiled mechanism: topology, loop equations and position solver.

    This is the solver's front door::

        lk = Linkage(mech)
        kin = lk.kinematics(np.radians([30, 60]))          # at the driver's rates
        frc = lk.forces(kin)                               # needs masses
        df = lk.sweep(360)                                 # full cycle, DataFrame
    """

    def __init__(self, mech: Mechanism, branch_rule: str = "continuous"):
        """``branch_rule``: what the solution does at a change point, where two
        assembly branches cross (:class:`analytic.position_solver.PositionSolver`):
        ``"continuous"`` (default) continues the branch whose velocity is continuous,
        as the physical linkage and the engines do, holding the dyad signs where
        continuity cannot decide; ``"hold"`` holds the signs; ``"switch"`` switches."""
        self.mech = mech
        self.topo: Topology = build_topology(mech)
        self.eqs = LoopEquations(self.topo)
        self.positions = PositionSolver(self.topo, self.eqs, branch_rule)
        #: the fused kernel of this linkage (:class:`analytic.fused.FusedKernel`), built
        #: by :func:`analytic.fused.kernel_for` on first use; ``None`` until then
        self.fused_kernel = None
        #: what other modules derive from this linkage once and keep with it, by name
        #: (:mod:`analytic.free_motion.dynamics`: ``"free_chain"``, ``"free_massive"``)
        self.derived: dict = {}

    def __getstate__(self) -> dict:
        """Pickled without its process-local caches: the fused kernel holds a compiled
        module, which cannot be pickled (an engine run carries its Linkage back from the
        report's worker processes), and is found again on first use in the receiving
        process; ``derived`` is rebuilt likewise."""
        state = dict(self.__dict__)
        state["fused_kernel"] = None
        state["derived"] = {}
        return state

    def body_index(self, name: str) -> int:
        try:
            return self.topo.body_names.index(name)
        except ValueError:
            self.mech.body(name)  # raises the typed error
            raise

    @property
    def driver_is_revolute(self) -> bool:
        return isinstance(self.mech.driver_joint, Revolute)

    @cached_property
    def column_scale(self) -> np.ndarray:
        """Scale of each column of the loop Jacobian in the unknowns (``(n,)``): 1 for
        an angle (its column is in m/rad, about a link length), the mechanism's size for
        a slider (its column is dimensionless), so that every column of ``A * scale`` is
        in metres and its condition number does not depend on the length unit."""
        topo = self.topo
        cols = [i for i in range(topo.nq) if i != topo.driven_var]
        return np.array([size_of(topo) if i >= topo.n_groups else 1.0 for i in cols])

    def kinematics(self, values=None, velocity=None, acceleration=None,
                   on_singular: str = "raise", branch: str = "continued",
                   limits: bool = True) -> Kinematics:
        """Solve positions, velocities and accelerations.

        Parameters
        ----------
        values
            Driver values (rad or m), scalar or ``(N,)``; default the description's.
            In any order, over any number of turns.  A value is a point on the input
            axis reached by moving the input continuously from the description's
            reference value, and gets the branch the linkage is on there: the
            assembled branch continued through change points (see
            :mod:`analytic.branches`; :meth:`branch_crossings` lists them), exactly as
            in :meth:`sweep`.
        branch
            ``"continued"`` (default, above) or ``"held"``: hold the reference dyad
            signs at every value (the other assembly mode past a change point).
        velocity, acceleration
            Driver rates (scalar or ``(N,)``); default the description's.
        on_singular
            ``"raise"``: a :class:`SingularConfigurationError` naming the input
            value where the loop Jacobian is singular (condition number above
            :data:`analytic.tolerances.SINGULAR_CONDITION`); ``"flag"``: return the
            result; at such points the rates are their limits along the branch where
            the linkage passes through, else NaN (``at_singular`` says which;
            :mod:`analytic.singular`), and ``condition`` flags them.
        limits
            ``False``: leave the linear solve's values at singular points (used by
            :mod:`analytic.singular` itself, on regular samples).
        """
        return self._kinematics(values, velocity, acceleration, on_singular, branch, limits)

    def solve(self, values=None, velocity=None, acceleration=None,
              on_singular: str = "raise", branch: str = "continued", joints: bool = False):
        """``(Kinematics, Forces)`` at ``values`` (arguments as :meth:`kinematics`), in
        one pass of the fused kernel where there is one: the same numbers as
        ``forces(kinematics(values))``, with each quantity computed once.  ``joints``:
        the same pass also writes every joint's point (``Kinematics.joint_point``),
        the positions pylinkage returns.  Needs masses (:class:`MissingMassError`)."""
        kin = self._kinematics(values, velocity, acceleration, on_singular, branch, True,
                               forces=True, joints=joints)
        frc = self.forces(kin)
        if joints:
            kin.joint_point  # noqa: B018 - computed now (on the numpy path: already)
        return kin, frc

    def _kinematics(self, values, velocity, acceleration, on_singular, branch, limits,
                    forces: bool = False, joints: bool = False) -> Kinematics:
        fk = fused_dispatch(self, 1 if values is None else np.size(values))
        if fk is not None and (fk.with_forces or not forces):
            # the fused kernel (analytic/fused.py): the same numbers, one pass
            guess = None if forces or not fk.with_forces else self._forces_guess()
            kin = fk.kinematics(values, velocity, acceleration, "flag", branch,
                                forces or guess is not None, joints)
            if guess is not None:
                kin.fused.forces_guess = guess
            if not kin.fused.singular:  # singular samples are the numpy path's to treat
                return kin
        d = self.mech.driver
        values = np.atleast_1d(np.asarray(d.value if values is None else values, float))
        N = len(values)
        vel = np.broadcast_to(np.asarray(d.velocity if velocity is None else velocity,
                                         float), (N,)).copy()
        acc = np.broadcast_to(np.asarray(d.acceleration if acceleration is None
                                         else acceleration, float), (N,)).copy()
        q, theta, E, O, trans, pre = self.positions.solve(values, branch)
        eqs = self.eqs
        L2 = 2 * eqs.L
        J = eqs.jacobian(q, pre)
        A, _ = eqs.split(J)
        n = A.shape[-1]
        if n:
            cs = self.column_scale
            det, cmax, cmin = self._normalised_det(A)
            # cond(A) <= n^(n/2) / |det of the column-normalised A| * (max/min column
            # norm): only where that bound reaches the threshold is the exact
            # condition number worth computing
            with np.errstate(divide="ignore", invalid="ignore"):
                bound = n ** (n / 2) / np.abs(det) * (cmax / cmin)
            suspect = np.flatnonzero(~(bound < SINGULAR_CONDITION))
            cond_s = condition(A[suspect] * cs) if suspect.size else np.zeros(0)
            bad = suspect[~(cond_s < SINGULAR_CONDITION)]
        else:
            det, bad = np.ones(N), np.zeros(0, int)
        if bad.size and on_singular == "raise":
            v = float(values[bad[0]])
            vs = f"{math.degrees(v):.6g} deg" if self.driver_is_revolute else f"{v:.6g} m"
            c0 = float(cond_s[np.flatnonzero(suspect == bad[0])[0]])
            raise SingularConfigurationError(
                f"mechanism {self.mech.name!r}: singular configuration (dead centre or change "
                f"point) at driver {d.joint!r} = {vs}: loop Jacobian condition number "
                f"{c0:.3g}; velocities are not determined by the input there", v)
        with np.errstate(all="ignore"):
            qd = eqs.solve_rates(J, np.zeros((N, L2)), vel)
            qdd = eqs.solve_rates(J, -eqs.gamma(q, qd, pre), acc)
        omega, alpha = self._group_rates(qd), self._group_rates(qdd)
        zv, za, jp = self._propagate(qd, qdd, E, O, omega, alpha)
        kin = Kinematics(self, values, vel, acc, q, qd, qdd, theta, omega, alpha,
                         E, O, zv, za, A, det, trans, jp)
        if bad.size and limits:  # singular samples: the limits along the branch, or NaN
            from .singular import rate_limits
            rate_limits(self, kin, bad, branch)
        return kin

    def _normalised_det(self, A: np.ndarray):
        """The determinant of ``A (N, n, n)`` with unit columns (``Kinematics.determinant``),
        and per sample the largest and smallest column norm, sliders' in sizes."""
        N, n = A.shape[0], A.shape[-1]
        colnorm = np.ones(N)
        cmax, cmin = np.zeros(N), np.full(N, np.inf)
        cs = self.column_scale
        # column norms, short axes unrolled (a long one, as in a chain of 40 loops,
        # in one reduction)
        norms = np.sqrt(np.einsum("nrc,nrc->nc", A, A)) if n > 8 else None
        for c in range(n):
            cn = norms[:, c] if norms is not None else \
                np.sqrt(sum(A[:, r, c] ** 2 for r in range(n)))
            colnorm *= cn
            cn = cn * cs[c]  # the bound is on the condition with sliders in sizes
            cmax, cmin = np.maximum(cmax, cn), np.minimum(cmin, cn)
        return det_small(A) / np.where(colnorm > 0, colnorm, 1.0), cmax, cmin

    def loop_determinant(self, values, branch: str = "continued") -> np.ndarray:
        """The loop Jacobian's normalised determinant at ``values`` (``(N,)``, the
        numpy path's :attr:`Kinematics.determinant`; its sign changes where the linkage
        passes a singular position), from the positions alone: no rates, no condition
        number."""
        values = np.atleast_1d(np.asarray(values, float))
        q, _, _, _, _, pre = self.positions.solve(values, branch)
        A, _ = self.eqs.split(self.eqs.jacobian(q, pre))
        return self._normalised_det(A)[0] if A.shape[-1] else np.ones(len(values))

    def _group_rates(self, x: np.ndarray) -> np.ndarray:
        g = self.topo.group_of
        out = np.zeros((x.shape[0], len(g)))
        m = g >= 0
        out[:, m] = x[:, g[m]]
        return out

    def _propagate(self, qd, qdd, E, O, omega, alpha):
        """Origin velocities and accelerations (complex), walking the spanning tree;
        also the world point of every joint (on body_b)."""
        topo = self.topo
        N, B = E.shape
        zv = np.zeros((N, B), complex)
        za = np.zeros((N, B), complex)
        jp = {}
        for c in topo.order[1:]:
            p, j = topo.parent[c]
            jt = self.mech.joints[j]
            wp, ap = omega[:, p], alpha[:, p]
            rp = E[:, p] * cplx(topo.attach(j, p))
            P = O[:, p] + rp
            vP = zv[:, p] + 1j * wp * rp
            aP = za[:, p] + (1j * ap - wp * wp) * rp
            if not isinstance(jt, Revolute):
                i = topo.n_groups + topo.slider_index[j]
                gb = topo.body_names.index(jt.guide)
                u = E[:, gb] * complex(math.cos(jt.direction), math.sin(jt.direction))
                sd, sdd = qd[:, i], qdd[:, i]
                rel_v = sd * u
                rel_a = (sdd + 2j * omega[:, gb] * sd) * u  # sliding + Coriolis
                if c == topo.body_names.index(jt.slider):
                    # P is the guide's line origin; the guide's material point under the
                    # slider point moves rigidly with the guide, the slider slides on it
                    PS = O[:, c] + E[:, c] * cplx(topo.attach(j, c))
                    r = PS - P
                    vP = vP + 1j * wp * r + rel_v
                    aP = aP + (1j * ap - wp * wp) * r + rel_a
                    P = PS
                else:
                    # P is the slider point; the guide's material point there moves with
                    # the slider's velocity less the sliding
                    vP, aP = vP - rel_v, aP - rel_a
            jp[j] = P
            wc, ac = omega[:, c], alpha[:, c]
            rc = O[:, c] - P
            zv[:, c] = vP + 1j * wc * rc
            za[:, c] = aP + (1j * ac - wc * wc) * rc
        for j in topo.chords:
            bb = topo.body_names.index(self.mech.joints[j].body_b)
            jp[j] = O[:, bb] + E[:, bb] * cplx(topo.attach(j, bb))
        return zv, za, jp

    def kinematics_along(self, values, velocity=None, acceleration=None,
                         on_singular: str = "flag") -> Kinematics:
        """Kinematics at arbitrary input values on the branch the moving linkage
        follows: :meth:`kinematics` with ``branch="continued"`` and singular positions
        flagged, not raised.  For comparing with a run (an engine's sampled inputs,
        possibly over several turns, possibly reversing): each value gets the branch
        continued from the reference value through every change point in between."""
        return self.kinematics(values, velocity, acceleration, on_singular=on_singular,
                               branch="continued")

    def branch_crossings(self, lo: float, hi: float):
        """Change points met moving the input from the reference value to ``lo`` and
        to ``hi`` (SI): a list of :class:`analytic.branches.Crossing` (value, joints,
        signs before and after, the rule that chose).  Empty on the Newton path, where
        :attr:`PositionSolver.trace` lists the singular positions crossed."""
        sch = self.positions.schedule
        return [] if sch is None else sch.crossings(lo, hi)

    def feasible_ranges(self) -> list[tuple[float, float]]:
        """Input intervals (SI) the assembled branch reaches; for a Newton-path
        mechanism, the traced branch between its limit positions."""
        return self.positions.feasible()

    # convenience wrappers ----------------------------------------------------
    def _forces_guess(self):
        """Whether the kernel's kinematics pass should write the forces too: yes while
        the caller asks for the forces of what it gets (``forces(kinematics(x))``, the
        second call on is one pass), until a result's forces go unused (then the
        kinematics pass writes none again).  Returns the new result's mark (its
        ``used`` set by :meth:`forces`), or ``None``."""
        d = self.__dict__
        if not d.get("_forces_follow"):
            return None
        last = d.get("_forces_last")
        if last is not None and not last.used:  # the last guess was wasted: stop
            d["_forces_follow"], d["_forces_last"] = False, None
            return None
        d["_forces_last"] = mark = _ForcesGuess()
        return mark

    def forces(self, kin: Kinematics):
        """Kinetostatic solution for a :class:`Kinematics` (see :mod:`analytic.kinetostatics`).
        Of a result of the fused kernel: the forces its pass wrote (:meth:`solve`, or
        :meth:`kinematics` once forces have followed kinematics: see
        :meth:`_forces_guess`), else one more pass writing only the forces."""
        tag = getattr(kin, "fused", None)
        if tag is not None:  # the kernel's forces pass
            if tag.forces is None:  # asked for after a kinematics-only pass
                self.__dict__.update(_forces_follow=True, _forces_last=None)
            elif tag.forces_guess is not None:
                tag.forces_guess.used = True
            return tag.kernel.forces(kin)
        from .kinetostatics import solve_forces
        return solve_forces(self, kin)

    def sweep(self, points: int = 360, **kw):
        """Full-cycle table (see :func:`analytic.sweep.sweep`)."""
        from .sweep import sweep
        return sweep(self, points, **kw)
