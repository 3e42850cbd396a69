"""The equation of motion at one state without numpy dispatch: the compiled path.

:func:`dynamics.coefficients` and :func:`dynamics.terms` evaluate one state through the
solver's array code (a :class:`analytic.Kinematics` of one row, then sums over bodies and
elements): ~0.1 ms of Python and numpy per call, thousands of calls per run.  Here one
state costs two compiled calls: the solver's fused kernel (:mod:`analytic.fused`, the
same numbers) into preallocated one-row outputs, or for a parallelogram chain
(:mod:`.parallelograms`: IFToMM A02, whose fused kernel is too large to compile) its
identities; then the generic kernel of :mod:`analytic.kernels.free_eom_kernel`, whose
structure is data (:class:`Layout`), so one compile serves every mechanism.

Rule as for the prescribed solver: no call waits for a compile.  A kernel in numba's
on-disk cache is loaded; one that is not is compiled by a background process
(:mod:`analytic.kernels.background`) while the numpy path answers.  ``XVAL_FUSED=0``
turns the compiled path off (and the prescribed solver's kernel), ``XVAL_FREE_COMPILED=0``
only this one (the numpy path's numbers, for comparisons); ``XVAL_FUSED=always``
compiles what is missing at once.
Where the compiled path cannot answer a state as the numpy path would (a configuration
near a singular position, outside the assembly, a parallelogram stretch not yet
verified), that state goes to the numpy path.
"""

from __future__ import annotations

import bisect
import math
import os
import time
from functools import cache
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from .. import fused
from ..kernels.cache import _MODULES, module_name, on_disk
from ..mechanism import Revolute
from ..motion_spec import PointDamper, PointSpring
from ..planar import cplx
from .dynamics import COINCIDENT, _chain, _massive, _size

#: layout of the kernel's ``out``: the terms of one state
OUT = ("M", "C", "Q", "motor_power", "load_power", "damper_power", "potential", "kinetic",
       "qdd")


@cache
def eom_source() -> str:
    """The generic kernel's module text (read, not imported: it imports numba)."""
    return (Path(__file__).resolve().parents[1] / "kernels" / "free_eom_kernel.py").read_text()


class _EomModule:
    """The generic kernel as :func:`analytic.kernels.background.start` takes a kernel:
    ``name``, ``source.source`` and the arguments of one call of the types every call
    passes."""

    def __init__(self):
        self.source = SimpleNamespace(source=eom_source())
        self.name = module_name(self.source.source)

    def sample_args(self) -> tuple:
        return _args(0, 0, 0.0, 0.0, np.zeros(0), np.zeros(1), Layout.empty(), _Poses(1, 1))


def _args(mode, new, q, qd, eff, ref, lay, p) -> tuple:
    return (mode, new, q, qd, eff, ref, lay.iv, lay.fv, lay.cv, p.theta, p.omega, p.alpha,
            p.E, p.zO, p.zv, p.za, p.sq, p.sqd, p.sqdd, p.x, p.xq, p.xqq, p.out)


class _Poses:
    """One configuration's arrays (the fused kernel's outputs or the chain's)."""

    def __init__(self, B: int, J: int, nq: int = 1):
        self.theta, self.omega, self.alpha = (np.zeros((1, B)) for _ in range(3))
        self.E, self.zO, self.zv, self.za = (np.zeros((1, B), complex) for _ in range(4))
        self.sq, self.sqd, self.sqdd = (np.zeros((1, nq)) for _ in range(3))
        self.x, self.xq, self.xqq = np.zeros(J), np.zeros(J), np.zeros(J)
        self.out = np.zeros(len(OUT))


class Layout:
    """A mechanism's structure and parameters as the generic kernel reads them: an int64
    array ``iv`` (a header of counts and offsets, then per joint ``(revolute, body_a,
    body_b)`` or ``(0, slider unknown, 0)``, the massive bodies, the loads' bodies,
    springs and dampers ``(point?0:1, body_a, body_b, joint)``, the motors' joints, the
    parallelogram chain), float64 ``fv`` (gravity, masses and inertias, forces and
    torques, stiffnesses and free lengths, coefficients, chain offsets) and complex
    ``cv`` (body-frame points: centres of mass, load points, element ends, chain paths)."""

    def __init__(self, iv, fv, cv):
        self.iv, self.fv, self.cv = iv, fv, cv

    @classmethod
    def empty(cls) -> Layout:
        return cls(np.zeros(24, np.int64), np.zeros(2), np.zeros(1, complex))

    @classmethod
    def of(cls, lk, chain=None) -> Layout:
        mech, topo = lk.mech, lk.topo
        # fv[0:2] gravity, fv[2] the distance under which a spring's or damper's ends
        # coincide (dynamics.COINCIDENT of the size, as the numpy path's _point_pair)
        iv, fv, cv = [0] * 24, [*map(float, mech.gravity), COINCIDENT * _size(lk)], []
        names = topo.body_names
        jidx = {j.name: k for k, j in enumerate(mech.joints)}
        iv[0], iv[1] = len(mech.joints), jidx[mech.driver.joint]
        iv[7] = len(iv)
        for k, j in enumerate(mech.joints):
            if isinstance(j, Revolute):
                iv += [1, names.index(j.body_a), names.index(j.body_b)]
            else:
                iv += [0, topo.n_groups + topo.slider_index[k], 0]
        bs, com, mass, inertia = _massive(lk)
        iv[2], iv[8], iv[14], iv[19] = len(bs), len(iv), len(fv), len(cv)
        iv += [int(b) for b in bs]
        for i in range(len(bs)):
            fv += [float(mass[i]), float(inertia[i])]
            cv.append(complex(com[i]))
        iv[3], iv[9], iv[15], iv[20] = len(mech.loads), len(iv), len(fv), len(cv)
        for ld in mech.loads:
            b = lk.body_index(ld.body)
            iv.append(b)
            fv += [float(ld.force[0]), float(ld.force[1]), float(ld.torque)]
            cv.append(cplx(topo.body_points[b][ld.point]) if ld.point is not None
                      else cplx(mech.bodies[b].com))
        fm = mech.motion
        for slot, items in ((4, fm.springs if fm else ()), (5, fm.dampers if fm else ())):
            iv[slot], iv[slot + 6], iv[slot + 12], iv[slot + 17] = (len(items), len(iv),
                                                                    len(fv), len(cv))
            for el in items:
                point = isinstance(el, PointSpring | PointDamper)
                if point:
                    ba, bb = lk.body_index(el.body_a), lk.body_index(el.body_b)
                    iv += [0, ba, bb, 0]
                    cv += [cplx(topo.body_points[ba][el.point_a]),
                           cplx(topo.body_points[bb][el.point_b])]
                else:
                    iv += [1, 0, 0, jidx[el.joint]]
                    cv += [0j, 0j]
                fv += ([float(el.stiffness), float(el.free_length if point else el.free_value)]
                       if slot == 4 else [float(el.coefficient)])
        motors = fm.motors if fm else ()
        iv[6], iv[12] = len(motors), len(iv)
        iv += [jidx[mo.joint] for mo in motors]
        iv[13], iv[18], iv[23] = len(iv), len(fv), len(cv)
        if chain is not None:
            _chain_layout(chain, iv, fv, cv)
        return cls(np.array(iv, np.int64), np.array(fv, float),
                   np.array(cv or [0j], complex))


def _chain_layout(chain, iv, fv, cv) -> None:
    """The chain's driver, windows and tree paths (see the kernel's ``_chain``)."""
    iv += [chain.drv, len(chain.windows)]
    fv.append(float(chain.sign))
    for x1, k3, d1, x2, k1, d2 in chain.windows:
        iv += [x1, k3, x2, k1]
        fv += [float(d1), float(d2)]
    rows, vals, cols, starts = chain._paths
    iv += [len(rows), len(cols), *map(int, rows), *map(int, cols), *map(int, starts)]
    cv += list(map(complex, vals))


def _mode() -> str:
    return os.environ.get("XVAL_FUSED", "1").strip().lower()


def _ready(kern, compile_now: bool):
    """``kern``'s compiled function in this process (loaded from numba's cache, or
    compiled at once when ``compile_now``), else ``None`` with a background compile
    started."""
    from ..kernels.background import start
    from ..kernels.cache import _load
    name = kern.name
    mod = _MODULES.get(name)
    fn = getattr(mod, "kernel", None)
    if fn is not None and fn.overloads:
        return fn
    if compile_now or on_disk(name):
        mod = _load(kern.source.source)
        mod.kernel(*kern.sample_args())  # loads (or compiles) the one specialisation
        from ..kernels.cache import mark_ready
        mark_ready(name, mod.kernel)
        return mod.kernel
    start(kern)
    return None


_EOM: list = []


def eom_kernel(compile_now: bool = False):
    """The generic kernel, or ``None`` (compiling in the background)."""
    if not _EOM:
        _EOM.append(_EomModule())
    return _ready(_EOM[0], compile_now)


class FastEOM:
    """The compiled evaluation of one :class:`analytic.Linkage`'s equation of motion.

    :meth:`evaluate` answers ``(x, x_q, out)`` (joint coordinates unwrapped to ``ref``,
    their rates per unit q, and the terms :data:`OUT`) for one state, or ``None`` where
    the numpy path must answer it."""

    def __init__(self, lk, eom, fk, chain):
        self.lk, self.eom, self.fk, self.chain = lk, eom, fk, chain
        self.layout = Layout.of(lk, chain)
        topo = lk.topo
        B, J = len(topo.body_names), len(lk.mech.joints)
        self.motors = lk.mech.motion.motors if lk.mech.motion else ()
        self.eff = np.array([mo.effort for mo in self.motors], float)
        self._tables = any(mo.times for mo in self.motors)
        self.chain_p = _Poses(B, J) if chain is not None else None
        self.key = None  # the q of the arrays now held, and which arrays hold it
        self.p = None
        self.new = False  # whether the last evaluate computed a new configuration
        if fk is not None:
            self._fused_setup(fk, B, J)

    def _fused_setup(self, fk, B, J):
        out = fk.alloc(1, 2, full=True)
        p = self.fused_p = _Poses(B, J, fk.nq)
        p.theta, p.omega, p.alpha = out["theta"], out["omega"], out["alpha"]
        p.E, p.zO, p.zv, p.za = out["E"], out["zO"], out["zv"], out["za"]
        p.sq, p.sqd, p.sqdd = out["q"], out["qd"], out["qdd"]
        self._outs = tuple(out.values())
        self._vals = np.zeros(1)
        self._one, self._zero = np.ones(1), np.zeros(1)
        self._carry = np.zeros(1 + 2 * self.lk.topo.n_groups)
        self._stat, self._statf = np.zeros(3, np.int64), np.zeros(1)
        self._susp = np.empty(1, np.int64)
        self._tol = self.lk.positions.tol
        self._signs_range = None
        self._held = None  # a constant schedule's (signs, one row)

    # -- one configuration ---------------------------------------------------------
    def _chain_applies(self, q: float) -> bool:
        ch = self.chain
        cps = ch._change_points(q - math.pi, q + math.pi)
        ok = ch._verified.get(bisect.bisect_left(cps, q))
        if ok is None:
            return ch.applies(np.array([q]))
        return ok

    def _signs(self, q: float):
        """The solver's branch signs at ``q`` (:meth:`FusedKernel.signs_for`): a
        constant schedule's one row, or the walk's segment holding ``q`` (the walk
        kept over a range and extended when ``q`` leaves it)."""
        ps = self.lk.positions
        held = self._held
        if held is not None and held[0] is ps.signs:
            return held[1]
        sch = getattr(ps, "schedule", None)
        if sch is None or getattr(sch, "constant", True):
            # the solver's held signs: kept while they are the same object
            self._held = (ps.signs, self.fk.signs_for(self._vals))
            return self._held[1]
        r = self._signs_range
        if r is None or not r[0] <= q <= r[1]:
            lo, hi = q - 2 * math.pi, q + 2 * math.pi
            if r is not None:
                lo, hi = min(lo, r[0]), max(hi, r[1])
            segs, _ = sch.walk(lo, hi)
            starts = [a for a, _, _ in segs]
            rows = [np.array([s], float).reshape(1, self.fk.n_branch) for _, _, s in segs]
            r = self._signs_range = (lo, hi, starts, rows)
        k = min(max(bisect.bisect_right(r[2], q) - 1, 0), len(r[3]) - 1)
        return r[3][k]

    def _fused(self, q: float) -> bool:
        """The fused kernel at ``q`` into :attr:`fused_p`; False where its answer is not
        the numpy path's (near a singular position, infeasible, loop not closed)."""
        fk = self.fk
        self._vals[0] = q
        self._carry.fill(0.0)
        self._stat.fill(0)
        self._statf.fill(0.0)
        fk.fn(2, self._vals, self._one, self._zero, self._signs(q), fk.pf, fk.pc,
              self._carry, self._stat, self._statf, self._susp, *self._outs)
        st = self._stat
        return st[0] < 0 and st[2] == 0 and (not self.lk.topo.n_loops
                                             or self._statf[0] <= self._tol)

    def evaluate(self, q: float, qd: float, t: float, ref: np.ndarray):
        """``(x, x_q, out)`` at the state, or ``None`` (the numpy path answers)."""
        new = q != self.key
        if new:
            if self.chain is not None and self._chain_applies(q):
                p, mode = self.chain_p, 1
            elif self.fk is not None and self._fused(q):
                p, mode = self.fused_p, 0
            else:
                self.key = None
                return None
        else:
            p = self.p
            mode = 0  # the poses are in place: only the sums
        if self._tables:
            self.eff[:] = [mo.at(t) for mo in self.motors]
        self.eom(mode, int(new), q, qd, self.eff, ref, self.layout.iv, self.layout.fv,
                 self.layout.cv, p.theta, p.omega, p.alpha, p.E, p.zO, p.zv, p.za, p.sq,
                 p.sqd, p.sqdd, p.x, p.xq, p.xqq, p.out)
        if new:
            self.key, self.p = q, p
        self.new = new
        return p.x, p.xq, p.out


#: How often (s of wall time) a run answered by the numpy path looks whether the
#: background compiles it waits for have finished (a file read per kernel).
RECHECK_S = 0.5


class _Pending:
    """The compiled path while its kernels compile in the background: the numpy path
    answers (:meth:`evaluate` returns ``None``) until they are in numba's cache, then
    they are loaded and the compiled path answers the rest of the run."""

    def __init__(self, lk, names: list[str]):
        self.lk, self.names = lk, names
        self.next = time.monotonic() + RECHECK_S
        self.real = None
        self.new = False

    def evaluate(self, q: float, qd: float, t: float, ref: np.ndarray):
        real = self.real
        if real is None:
            now = time.monotonic()
            if now < self.next:
                return None
            self.next = now + RECHECK_S
            if not all(on_disk(n) for n in self.names):
                return None
            real = self.real = fast_eom(self.lk, pending=False)
            if real is None:
                self.next = math.inf
                return None
        got = real.evaluate(q, qd, t, ref)
        self.new = real.new
        return got


def fast_eom(lk, pending: bool = True) -> FastEOM | _Pending | None:
    """The compiled evaluation for ``lk``, or ``None`` where the numpy path answers
    (disabled, no kernel for the structure); while a kernel compiles in the background,
    a :class:`_Pending` (the numpy path answers until it is ready).  Kept in the
    linkage's ``derived``."""
    mode = _mode()
    off = ("0", "off", "no", "false")
    if (mode in off or not fused.enabled()
            or os.environ.get("XVAL_FREE_COMPILED", "1").strip().lower() in off):
        return None
    got = lk.derived.get("free_fast")
    if got is not None:
        return got
    now = mode == "always"
    eom = eom_kernel(now)
    chain = _chain(lk)
    fk = fused.kernel_for(lk)
    fn = None
    usable = fk is not None and not fk.too_large  # A02: the chain's identities serve it
    if usable:
        fn = _ready(fk, now) if not fk.loaded else fk.fn
        if fn is not None and fk._fn is None:
            fk._fn = fn
    if eom is None or (fn is None and chain is None):
        waiting = ([] if eom is not None else [_EOM[0].name]) + (
            [fk.name] if usable and fn is None else [])
        return _Pending(lk, waiting) if pending and waiting else None
    got = lk.derived["free_fast"] = FastEOM(lk, eom, fk if fn is not None else None, chain)
    return got


def prepare(mech) -> bool:
    """Compile now (or load) the kernels that ``mech``'s release evaluates with: the
    generic kernel and the solver's fused kernel of the released coordinate (not one
    too large to compile: a parallelogram chain needs none).  For benchmarks and tests,
    which time or compare the compiled path itself; whether the compiled path serves
    the release."""
    from dataclasses import replace

    from ..kinematics import Linkage
    from ..mechanism import Driver
    if not fused.enabled():
        return False
    fm = mech.motion
    lk = Linkage(replace(mech, driver=Driver(fm.joint, fm.value, fm.rate)))
    eom_kernel(compile_now=True)
    fk = fused.kernel_for(lk)
    if fk is not None and not fk.too_large and not fk.loaded:
        fk._fn = _ready(fk, True)
    return isinstance(fast_eom(lk), FastEOM)
