"""The fused solver kernel: positions, rates, tree walk and forces in one pass.

For a mechanism with a dyad plan (every built-in case), :class:`FusedKernel`
compiles the plan into one numba function (:mod:`analytic.kernels.codegen`) that
runs over the input values once, each configuration in registers, writing only the
outputs.  A mechanism solved by Newton-Raphson (no dyad plan) has no kernel:
:func:`kernel_for` returns ``None`` and the numpy path is used.

The kernel is compiled once per mechanism *structure* (the geometry is a parameter
array) and cached on disk by numba (``cache=True``) under :func:`cache_dir`, so a
second process pays only the load.  The numpy path stays the reference:
``XVAL_FUSED=0`` (or :func:`kernel_for` ``(..., enabled=False)``) forces it, and
``tests/analytic/test_fused.py`` checks the two agree to 1e-13 of peak on every
built-in case.

Branch signs are an input, one row per configuration or one row for all, so the
branch continuation of :class:`analytic.positions.PositionSolver` (signs that
change after a change point) is evaluated unchanged.

Memory: the kernel allocates nothing per configuration.  Its outputs are the whole
cost: :meth:`FusedKernel.state` (``q, q', q''``, every joint force, the drive
effort and the power terms) is ``8 (3 nq + 2 J + 2 P + 5)`` bytes per configuration,
176 B for a four-bar; :meth:`FusedKernel.kinematics` materialises the full
:class:`analytic.kinematics.Kinematics` arrays (poses, origin rates, Jacobian,
joint points), about 600 B for a four-bar.
"""

from __future__ import annotations

import functools
import importlib.util
import math
import os
import sys
import time
from dataclasses import dataclass

import numpy as np

from .errors import AssemblyError, SingularConfigurationError
from .kernels.cache import (  # noqa: F401 - cache_dir and module_name: the module's API
    _MODULES,
    _load,
    cache_dir,
    mark_ready,
    module_name,
    on_disk,
)
from .kin_result import DEFERRED, CompactKinematics, FusedTag, Kinematics
from .kinetostatics import Forces, solve_forces
from .linalg import condition
from .positions import _fmt_value, _infeasible
from .tolerances import SINGULAR_CONDITION

#: how many suspect (near-singular) configurations one call records; past it the
#: screen is repeated in numpy over the stored Jacobians
SUSPECT_CAP = 4096
#: every specialisation of a kernel module compiled or loaded from numba's cache in this
#: process: module name -> ``[(how, seconds), ...]``, ``how`` "compiled" or "loaded"
#: (one entry per module: the kernel takes one set of argument types, see :func:`_arg`)
COMPILE_LOG: dict[str, list[tuple[str, float]]] = {}


def enabled() -> bool:
    """The fused path is on unless ``XVAL_FUSED=0`` or numba is missing."""
    if os.environ.get("XVAL_FUSED", "1").strip().lower() in ("0", "off", "no", "false"):
        return False
    return _have_numba()


@functools.cache
def _have_numba() -> bool:
    return importlib.util.find_spec("numba") is not None


def _arg(a: np.ndarray) -> np.ndarray:
    """An input as the kernel's one specialisation takes it: C-contiguous, writeable
    float64 (numba types a read-only array, such as a slice of a ``broadcast_to`` view,
    as another type, and would compile the whole kernel a second time for it)."""
    if a.dtype == np.float64 and a.flags.c_contiguous and a.flags.writeable:
        return a
    return np.array(a, dtype=np.float64, order="C")


#: the kernel's output arguments, in its order
_OUT_KEYS = ("q", "qd", "qdd", "theta", "omega", "alpha", "E", "zO", "zv", "za", "A", "det",
             "trv", "jp", "jf", "nm", "sc")
#: outputs the kernel writes at each level whatever their size (the others it writes
#: only when they have rows)
_NEED = (frozenset(), frozenset(), frozenset(), frozenset({"jf", "nm", "sc"}))


@dataclass
class State:
    """The compact result of one pass (SI, world axes), from which every other
    quantity follows: ``q, qd, qdd (N, nq)``; ``joint_force (N, J, 2)`` by body_a on
    body_b; ``normal_moment (N, P, 2)`` of the prismatic joints; ``scalars (N, 5)``:
    effort, power, kinetic_rate, load_power, power_residual (``None`` without forces)."""

    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    joint_force: np.ndarray | None
    normal_moment: np.ndarray | None
    scalars: np.ndarray | None


class FusedKernel:
    """The compiled kernel of one :class:`analytic.kinematics.Linkage`."""

    def __init__(self, linkage):
        from .kernels.codegen import KernelSource
        if linkage.topo.plan is None:
            raise ValueError(f"mechanism {linkage.mech.name!r} has no dyad plan: no kernel")
        self.lk = linkage
        self.with_forces = linkage.mech.has_mass
        ks = KernelSource(linkage, self.with_forces)
        self.source = ks
        self.pf, self.pc = ks.params()
        self.name = module_name(ks.source)
        self._fn = None  # the compiled function: imported on first use (imports numba)
        self.compile_seconds = None  # import + compile or load, at the first call
        topo = linkage.topo
        self.B, self.nq, self.J = len(topo.body_names), topo.nq, len(linkage.mech.joints)
        self.n = ks.n
        self.P = len(topo.prismatic)
        self.T = ks.n_dyad_trans
        self.trans_names = [t[0] for t in ks.trans]
        self.n_branch = ks.n_branch
        #: whether the source is over :data:`MAX_KERNEL_LINES` (compiled only when
        #: ``XVAL_FUSED=always``)
        self.too_large = ks.source.count("\n") > MAX_KERNEL_LINES

    @property
    def loaded(self) -> bool:
        """Whether the kernel is compiled or loaded in this process (a call costs only
        its run), by this linkage or another of the same structure."""
        fn = self._fn
        if fn is None:
            mod = _MODULES.get(self.name)
            fn = getattr(mod, "kernel", None)
        return fn is not None and len(fn.overloads) > 0

    def sample_args(self) -> tuple:
        """Arguments of a call at no configurations, of the types every call passes:
        compiling the kernel for them compiles it for every call
        (:mod:`analytic.kernels.background`)."""
        level = 3 if self.with_forces else 2
        out = self.alloc(0, level, full=True)
        return (level, np.zeros(0), np.zeros(1), np.zeros(1), np.zeros((1, self.n_branch)),
                self.pf, self.pc, np.zeros(1 + 2 * self.lk.topo.n_groups),
                np.zeros(3, np.int64), np.zeros(1), np.empty(1, np.int64), *out.values())

    @property
    def fn(self):
        if self._fn is None:
            t0 = time.perf_counter()
            self.module = _load(self.source.source)
            self._fn = self.module.kernel
            self._t_load = time.perf_counter() - t0
        return self._fn

    # -- raw evaluation ---------------------------------------------------------
    def signs_for(self, values: np.ndarray, branch: str = "continued") -> np.ndarray:
        """Branch signs ``(1 or N, n_branch)`` for ``values``: the position solver's
        schedule (signs that change after change points) or its held signs."""
        ps = self.lk.positions
        sch = getattr(ps, "schedule", None) if branch != "held" else None
        if sch is None or getattr(sch, "constant", True) or not len(values):
            # one row for all; kept while the solver's signs are these (read only by
            # the kernel)
            key = tuple(ps.signs)
            held = self.__dict__.get("_held")
            if held is None or held[0] != key:
                held = self._held = (key, np.array([key], float).reshape(1, self.n_branch))
            return held[1]
        combos, idx = sch.signs_for(values)
        if len(combos) == 1:
            return np.array([combos[0]], float).reshape(1, self.n_branch)
        return np.asarray(combos, float)[idx].reshape(len(values), self.n_branch)

    def alloc(self, N: int, level: int = 3, full: bool = False, joints: bool = False,
              state: bool = True) -> dict:
        """Output arrays for ``N`` configurations, zero-sized where not wanted.

        ``level`` 0: poses; 1: + angles and ``q``; 2: + rates and the tree walk;
        3: + forces.  ``full`` adds what :class:`Kinematics` holds besides ``q, q',
        q''`` (angles, poses, origin rates, Jacobian, transmission and joint points);
        ``joints`` the joint points at any level; ``state=False`` leaves out ``q, q',
        q''`` (a forces pass at a known state).
        """
        key = (level, full, joints, state)
        plan = self.__dict__.setdefault("_plans", {}).get(key)
        if plan is None:
            plan = self._plans[key] = self._alloc_split(self._alloc_plan(*key))
        shared, wanted = plan
        out = dict(shared)  # the kernel's order: every key, unwanted ones zero-sized
        for k, tail, dt in wanted:
            out[k] = np.empty((N, *tail), dt)
        return out

    @staticmethod
    def _alloc_split(plan: tuple) -> tuple[dict, tuple]:
        """:meth:`_alloc_plan`'s entries as the dict of every key in the kernel's order
        (the shared zero-sized arrays, None where a call allocates) and the entries a
        call allocates."""
        shared = {k: e for k, _, _, e in plan}
        return shared, tuple((k, tail, dt) for k, tail, dt, e in plan if e is None)

    def _alloc_plan(self, level: int, full: bool, joints: bool, state: bool) -> tuple:
        """``(key, row shape, dtype, None or the shared zero-sized array)`` per output,
        in the kernel's order: arrays not wanted are zero-sized, one shared per key
        (never written), so a call allocates only what it returns."""
        B, J, n = self.B, self.J, self.n
        shapes = (("q", level >= 1 and state, (self.nq,), float),
                  ("qd", level >= 2 and state, (self.nq,), float),
                  ("qdd", level >= 2 and state, (self.nq,), float),
                  ("theta", full and level >= 1, (B,), float),
                  ("omega", full and level >= 2, (B,), float),
                  ("alpha", full and level >= 2, (B,), float), ("E", full, (B,), complex),
                  ("zO", full, (B,), complex), ("zv", full and level >= 2, (B,), complex),
                  ("za", full and level >= 2, (B,), complex),
                  ("A", full and level >= 2, (n, n), float),
                  ("det", full and level >= 2, (), float),
                  ("trv", full and level >= 2, (2 * self.T,), complex),
                  ("jp", (full and level >= 2) or joints, (J,), complex),
                  ("jf", level >= 3, (J, 2), float),
                  ("nm", level >= 3, (self.P, 2), float), ("sc", level >= 3, (5,), float))
        assert tuple(k for k, *_ in shapes) == _OUT_KEYS  # run(fresh=True) relies on it
        empty = self.__dict__.setdefault("_empty", {})
        for k, ok, tail, dt in shapes:
            if not ok and k not in empty:
                empty[k] = np.empty((0, *tail), dt)
        return tuple((k, tail, dt, None if ok else empty[k]) for k, ok, tail, dt in shapes)

    def run(self, values, velocity, acceleration, signs, out: dict, level: int = 3,
            carry=None, fresh: bool = False):
        """Evaluate into ``out`` (see :meth:`alloc`; its first dimension may exceed
        ``len(values)``: the leading rows are written).  ``carry`` (``1 + 2 n_groups``)
        continues the angle unwrapping of a previous block.  ``fresh``: ``out`` is
        :meth:`alloc` ``(len(values), level)``'s own, unchanged (its rows need no
        check and no cut).  Returns ``(first
        infeasible index or -1, index of the worst loop residual, worst residual (m),
        suspect indices)``."""
        if level >= 3 and not self.with_forces:
            raise ValueError("forces need masses")
        N = len(values)
        # the kernel does not check bounds: every array it writes must hold N rows
        need = _NEED[min(max(level, 0), 3)]
        # views of N rows (zero-sized arrays stay zero-sized; arrays of N rows are
        # passed as they are)
        v = list(out.values()) if fresh else []
        for k in () if fresh else _OUT_KEYS:
            a = out[k]
            r = len(a)
            if r != N:
                if r < N and (r or k in need):
                    raise ValueError(f"output {k!r} holds {r} rows, {N} needed")
                if r:
                    a = a[:N]
            v.append(a)
        if signs.shape != (1, self.n_branch) and signs.shape != (N, self.n_branch):
            raise ValueError(f"signs must be (1 or {N}, {self.n_branch}), got {signs.shape}")
        if len(velocity) not in (1, N) or len(acceleration) not in (1, N):
            raise ValueError("velocity and acceleration: one value or one per input value")
        if carry is None:
            carry = np.zeros(1 + 2 * self.lk.topo.n_groups)
        stat = np.zeros(3, np.int64)
        statf = np.zeros(1)
        cap = min(N, SUSPECT_CAP)
        susp = np.empty(max(cap, 1), np.int64)
        fn = self.fn
        nover = len(fn.overloads)
        t0 = time.perf_counter()
        fn(level, _arg(values), _arg(velocity), _arg(acceleration), _arg(signs), self.pf,
           self.pc, carry, stat, statf, susp, *v)
        if len(fn.overloads) != nover:  # a specialisation compiled or loaded: log it
            self._log(time.perf_counter() - t0)
        nsus = int(stat[2])
        return int(stat[0]), int(stat[1]), float(statf[0]), (susp[:nsus] if nsus <= cap
                                                              else None)

    def _log(self, seconds: float):
        fn = self._fn
        first = self.compile_seconds is None
        seconds += self._t_load if first else 0.0
        hits = sum(fn.stats.cache_hits.values())
        how = "loaded" if hits > self.__dict__.get("_hits", 0) else "compiled"
        self._hits = hits
        COMPILE_LOG.setdefault(self.name, []).append((how, seconds))
        if first:
            self.compile_seconds = seconds
        mark_ready(self.name, fn)

    # -- the solver's results -------------------------------------------------------
    def _inputs(self, values, velocity, acceleration):
        d = self.lk.mech.driver
        if not (type(values) is np.ndarray and values.dtype == np.float64  # noqa: E721
                and values.ndim == 1 and values.flags.c_contiguous):
            values = np.ascontiguousarray(np.atleast_1d(np.asarray(
                d.value if values is None else values, float)))
        N = len(values)
        if velocity is None and acceleration is None:  # the driver's: made once
            rates = self.__dict__.get("_driver_rates")
            if rates is None:
                rates = self._driver_rates = (np.array([float(d.velocity)]),
                                              np.array([float(d.acceleration)]))
            return (values, *rates)

        def rate(x):  # a constant rate stays one number: the kernel broadcasts it
            x = np.asarray(x, float)
            if x.ndim == 0 or x.size == 1:
                return np.ascontiguousarray(x.reshape(1))
            return np.ascontiguousarray(np.broadcast_to(x, (N,)))
        return (values, rate(d.velocity if velocity is None else velocity),
                rate(d.acceleration if acceleration is None else acceleration))

    def _check(self, values, bad, worst_i, worst):
        lk = self.lk
        if bad < 0 and (not lk.topo.n_loops or not len(values) or worst <= lk.positions.tol):
            return  # the common case: nothing to raise
        if bad >= 0:
            raise _infeasible(lk.topo, float(values[bad]))
        tol = lk.positions.tol
        if lk.topo.n_loops and len(values) and not worst <= tol:
            raise AssemblyError(
                f"mechanism {lk.mech.name!r}: loop residual {worst:.3g} m "
                f"at driver = {_fmt_value(lk.topo, float(values[worst_i]))} exceeds "
                f"{tol:.3g} m", float(values[worst_i]))

    def _singular(self, values, susp, A, on_singular):
        """Raise as the numpy path does at the first configuration whose loop Jacobian
        is singular (condition number from the stored Jacobians)."""
        if on_singular != "raise" or self.n == 0:
            return
        if susp is None:  # more suspects than recorded: screen them all again
            susp = np.arange(len(values))
        if not len(susp):
            return
        cond = condition(A[susp] * getattr(self.lk, "column_scale", 1.0))  # as Kinematics
        badm = ~(cond < SINGULAR_CONDITION)
        if not badm.any():
            return
        k = int(np.flatnonzero(badm)[0])
        v = float(values[susp[k]])
        lk = self.lk
        vs = f"{math.degrees(v):.6g} deg" if lk.driver_is_revolute else f"{v:.6g} m"
        raise SingularConfigurationError(
            f"mechanism {lk.mech.name!r}: singular configuration (dead centre or change "
            f"point) at driver {lk.mech.driver.joint!r} = {vs}: loop Jacobian condition "
            f"number {float(cond[k]):.3g}; velocities are not determined by the input there",
            v)

    def solve(self, values=None, velocity=None, acceleration=None, on_singular="raise",
              branch="continued", forces: bool = False):
        """``(Kinematics, Forces or None)`` in one pass, as
        ``Linkage.kinematics`` and ``Linkage.forces`` compute them."""
        values, vel, acc = self._inputs(values, velocity, acceleration)
        if forces:
            self._require_mass()
        level = 3 if forces else 2
        out = self.alloc(len(values), level, full=True)
        bad, wi, worst, susp = self.run(values, vel, acc, self.signs_for(values, branch), out,
                                        level, fresh=True)
        self._check(values, bad, wi, worst)
        self._singular(values, susp, out["A"], on_singular)
        # a sample near a singular position (bound on the condition number reached)
        singular = susp is None or len(susp) > 0
        return self._wrap(values, vel, acc, out, branch, forces, singular)

    def solve_block(self, values, velocity, acceleration, out: dict, carry: np.ndarray,
                    level: int = 3, branch: str = "continued", on_singular="flag"):
        """As :meth:`solve` for one block of a longer run, into the preallocated
        ``out`` (:meth:`alloc` with ``full=True``) with the unwrapping ``carry`` of the
        previous block; the results are views of ``out``."""
        values, vel, acc = self._inputs(values, velocity, acceleration)
        if level >= 3:
            self._require_mass()
        bad, wi, worst, susp = self.run(values, vel, acc, self.signs_for(values, branch), out,
                                        level, carry)
        N = len(values)
        cut = {k: (a[:N] if a.shape[0] else a) for k, a in out.items()}
        self._check(values, bad, wi, worst)
        self._singular(values, susp, cut["A"], on_singular)
        singular = susp is None or len(susp) > 0
        return self._wrap(values, vel, acc, cut, branch, level >= 3, singular)

    def _wrap(self, values, vel, acc, out, branch, forces, singular):
        """The full :class:`Kinematics` of ``out`` (views), tagged with this kernel
        (``Linkage.forces`` runs its forces pass), and the forces where written."""
        trans = [(name, out["trv"][:, 2 * d], out["trv"][:, 2 * d + 1])
                 for d, name in enumerate(self.trans_names)]
        jp = {j: out["jp"][:, j] for j in range(self.J)}
        N = len(values)
        kin = Kinematics(
            linkage=self.lk, value=values, velocity=np.broadcast_to(vel, (N,)),
            acceleration=np.broadcast_to(acc, (N,)), q=out["q"],
            qd=out["qd"], qdd=out["qdd"], theta=out["theta"], omega=out["omega"],
            alpha=out["alpha"], E=out["E"], zO=out["zO"], zv=out["zv"], za=out["za"],
            jacobian=out["A"], determinant=out["det"], transmission_vectors=trans,
            joint_point=jp, fused=FusedTag(self, branch, singular))
        return kin, (self._forces(out) if forces else None)

    def kinematics(self, values=None, velocity=None, acceleration=None, on_singular="raise",
                   branch="continued", forces: bool = False, joints: bool = False):
        """As :meth:`analytic.kinematics.Linkage.kinematics`: a
        :class:`analytic.kinematics.CompactKinematics` (``q, q', q''`` now, the rest on
        first use), or where a sample is near a singular position the full result of
        :meth:`solve` (its Jacobians screen the samples, and flag them for the numpy
        path's singular treatment).  ``forces``: the same pass writes the forces too
        (kept on the result for :meth:`forces`: its ``fused.forces``); ``joints``: and
        every joint's point (``joint_point``), so neither costs another pass."""
        values, vel, acc = self._inputs(values, velocity, acceleration)
        if forces:
            self._require_mass()
        level = 3 if forces else 2
        out = self.alloc(len(values), level, joints=joints)
        bad, wi, worst, susp = self.run(values, vel, acc, self.signs_for(values, branch), out,
                                        level, fresh=True)
        self._check(values, bad, wi, worst)
        if susp is None or len(susp):
            kin, frc = self.solve(values, vel, acc, on_singular, branch, forces)
            kin.fused.forces = frc
            return kin
        kin = CompactKinematics(self, self.lk, values, vel, acc, out["q"], out["qd"],
                                out["qdd"], branch, self._forces(out) if forces else None)
        if joints:
            kin.joint_point = {j: out["jp"][:, j] for j in range(self.J)}
        return kin

    def deferred(self, kin) -> dict:
        """The arrays a :class:`analytic.kinematics.CompactKinematics` defers, from one
        full pass at its inputs."""
        full, _ = self.solve(kin.value, *_rates(kin), "flag", kin.fused.branch)
        return {k: getattr(full, k) for k in DEFERRED}

    def forces(self, kin):
        """As :func:`analytic.kinetostatics.solve_forces`: the forces of the pass that
        made ``kin`` where it wrote them (:meth:`kinematics` ``forces=True``), else one
        more pass of the kernel at ``kin``'s inputs, writing only the forces."""
        self._require_mass()
        tag = kin.fused
        if tag is not None and tag.forces is not None:
            return tag.forces
        N = kin.n
        out = self.alloc(N, 3, state=False)  # the state is kin's: the forces only
        branch = "continued" if tag is None else tag.branch
        _, vel, acc = self._inputs(kin.value, *_rates(kin))
        self.run(kin.value, vel, acc, self.signs_for(kin.value, branch), out, 3, fresh=True)
        return self._forces(out)

    def _require_mass(self):
        if not self.with_forces:
            solve_forces(self.lk, None)  # raises the typed MissingMassError
            raise AssertionError("unreachable")

    def _forces(self, out):
        names = self.__dict__.get("_force_names")
        if names is None:  # per joint, per slider: fixed by the structure
            mech, topo = self.lk.mech, self.lk.topo
            names = self._force_names = ([jt.name for jt in mech.joints],
                                         [mech.joints[j].name for j in topo.prismatic])
        jn, pn = names
        # views, one per joint and slider (a transposed view splits in one C loop); no
        # slider: no views to make (two empty splits cost a microsecond at 36 points)
        if pn:
            nm = out["nm"].transpose(1, 2, 0)
            normal = dict(zip(pn, nm[:, 0], strict=True))
            moment = dict(zip(pn, nm[:, 1], strict=True))
        else:
            normal, moment = {}, {}
        sc = out["sc"]
        return Forces(dict(zip(jn, out["jf"].transpose(1, 0, 2), strict=True)), normal,
                      moment, sc[:, 0], sc[:, 1], sc[:, 2], sc[:, 3], sc[:, 4])

    def state(self, values=None, velocity=None, acceleration=None, level: int = 3,
              branch: str = "continued", out: dict | None = None) -> State:
        """The compact result (:class:`State`) in one pass: ``q`` (level 1), with
        ``q', q''`` (level 2), with the forces (level 3).  ``out`` (from
        :meth:`alloc` ``(N, level)``) reuses preallocated outputs."""
        values, vel, acc = self._inputs(values, velocity, acceleration)
        if level >= 3:
            self._require_mass()
        fresh = out is None
        if fresh:
            out = self.alloc(len(values), level)
        bad, wi, worst, _ = self.run(values, vel, acc, self.signs_for(values, branch), out,
                                     level, fresh=fresh)
        self._check(values, bad, wi, worst)
        N = len(values)
        if fresh:
            cut = {k: (a if len(a) else None) for k, a in out.items()}
        else:
            cut = {k: (a[:N] if len(a) else None) for k, a in out.items()}
        return State(cut["q"], cut["qd"], cut["qdd"], cut["jf"], cut["nm"], cut["sc"])

    def poses(self, values, branch: str = "continued", out: dict | None = None):
        """Body poses only (level 0): ``exp(i theta)`` and origins, complex ``(N, B)``
        each, from which every point follows (angles are not computed)."""
        values, out = self._positions_only(values, branch, out, full=True)
        return out["E"][:len(values)], out["zO"][:len(values)]

    def joint_positions(self, values, branch: str = "continued", out: dict | None = None
                        ) -> np.ndarray:
        """Every joint's world point (complex ``(N, J)``, x + iy, m; the point on the
        tree walk's parent body, a prismatic joint's slider point), from the poses alone
        (level 0): what a position solver that tracks joints returns.  The same numbers
        as the ``joint_point`` of :meth:`solve`, bit for bit."""
        values, out = self._positions_only(values, branch, out, joints=True)
        return out["jp"][:len(values)]

    def _positions_only(self, values, branch, out, **want):
        """One level-0 pass into ``out`` (fresh from :meth:`alloc` with ``want`` when
        ``None``), checked; returns the values as an array and the outputs."""
        values = np.ascontiguousarray(np.atleast_1d(np.asarray(values, float)))
        fresh = out is None
        if fresh:
            out = self.alloc(len(values), 0, **want)
        z = np.zeros(1)
        bad, wi, worst, _ = self.run(values, z, z, self.signs_for(values, branch), out, 0,
                                     fresh=fresh)
        self._check(values, bad, wi, worst)
        return values, out


def _rates(kin) -> tuple[np.ndarray, np.ndarray]:
    """``kin``'s input rates, each as one number where constant."""
    r = kin.__dict__.get("_rates")
    if r is not None:
        return r
    return _compact(kin.velocity), _compact(kin.acceleration)


def _compact(x: np.ndarray) -> np.ndarray:
    """A rate series as one number when it is constant (a broadcast view or equal)."""
    x = np.asarray(x, float)
    if x.ndim and x.size and (x.strides[0] == 0 or np.all(x == x[0])):
        return x[:1]
    return x


#: Which path a call takes where the kernel is not yet in this process.  The numpy
#: path's cost is estimated as ``NUMPY_CALL_S + NUMPY_POINT_S n`` (kinematics and
#: forces of a four-bar at load 1: 1.2 ms at 36 points, 4.2 ms at 3,600, 0.9-1.5 us a
#: point from 36,000 on, the six-bar about twice that); loading a compiled kernel from
#: numba's cache costs :data:`LOAD_S` (importing numba and its typing context, then the
#: load: 0.33-0.43 s in all at load 1, 0.9-1.4 s at load 2-3) or
#: :data:`LOAD_IMPORTED_S` once numba is imported.  A structure's calls run on numpy
#: until their estimated cost reaches the load's, then load it (never more than twice
#: the better of the two choices made in hindsight); a call of 2**20 points or more
#: (:data:`COMPILE_NOW_POINTS`, ``XVAL_FUSED_MIN``) compiles a kernel that is not
#: cached at all (5-15 s, once per structure and machine), below that the compile runs
#: in a background process (:mod:`analytic.kernels.background`) while the numpy path
#: answers.
NUMPY_CALL_S, NUMPY_POINT_S = 1e-3, 2e-6
LOAD_S, LOAD_IMPORTED_S = 0.4, 0.1
COMPILE_NOW_POINTS = 1 << 20
#: Largest kernel source (lines) compiled unless ``XVAL_FUSED=always``: every built-in
#: case is 335-844 lines (11.6 s to compile the six-bar's at load 2) and Andrews'
#: mechanism 1258; the IFToMM N four-bar makes 1714 lines at N = 4, 4210 at N = 8 and
#: about 58,000 at N = 40, whose background compile held 9.7 GB and 17 min of CPU and
#: had not finished.  Beyond it the numpy path answers every call and nothing compiles.
MAX_KERNEL_LINES = 2000
#: estimated seconds spent on the numpy path per kernel module (this process)
_SPENT: dict[str, float] = {}


def dispatch(linkage, n: int) -> FusedKernel | None:
    """The kernel ``Linkage.kinematics`` should use for ``n`` input values, or ``None``
    for the numpy path: no dyad plan, ``XVAL_FUSED=0`` or no numba; or the kernel is
    neither in this process nor worth loading yet (see :data:`COMPILE_NOW_POINTS`).
    Once in this process, the kernel serves every call whatever its size;
    ``XVAL_FUSED=always`` takes it (compiling it if need be) at any ``n``."""
    fk = linkage.fused_kernel
    mode = os.environ.get("XVAL_FUSED")
    if mode is None and fk is not None and fk._fn is not None and fk._fn.overloads:
        return fk  # the common case, first: in the process and not overridden
    fk = kernel_for(linkage)
    if fk is None:
        return None
    if fk.loaded or (mode or "").strip() == "always":
        return fk
    if fk.too_large:  # its compile would take minutes and gigabytes: numpy serves it
        return None
    spent = _SPENT.get(fk.name, 0.0) + NUMPY_CALL_S + NUMPY_POINT_S * n
    if on_disk(fk.name):
        if spent >= (LOAD_IMPORTED_S if "numba" in sys.modules else LOAD_S):
            return fk
    else:
        try:
            least = int(os.environ.get("XVAL_FUSED_MIN", COMPILE_NOW_POINTS))
        except ValueError:
            least = COMPILE_NOW_POINTS
        if n >= least:
            return fk
        from .kernels.background import start
        start(fk)
    _SPENT[fk.name] = spent
    return None


def kernel_for(linkage, enabled_: bool | None = None) -> FusedKernel | None:
    """The linkage's fused kernel (built once and kept in the linkage's declared
    ``fused_kernel``), or ``None`` on the Newton path, when disabled (``XVAL_FUSED=0``)
    or without numba."""
    if not (enabled() if enabled_ is None else enabled_) or linkage.topo.plan is None:
        return None
    fk = linkage.fused_kernel
    if fk is None:
        fk = linkage.fused_kernel = FusedKernel(linkage)
    return fk
