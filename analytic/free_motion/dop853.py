"""One segment's integration with SciPy's DOP853 stepped in compiled code.

:func:`solve` answers what ``solve_ivp(sysm, span, y0, method="DOP853", rtol=rtol,
atol=atol, dense_output=True, events=[sysm.switch])`` answers, with the same numbers to
rounding: the steps are SciPy's (:mod:`analytic.kernels.dop853_kernel` repeats
``DOP853._step_impl`` and ``_dense_output_impl`` term by term with SciPy's tableau, and
evaluates the right-hand side through the compiled equation of motion of
:mod:`.compiled` from nopython code), while this module is ``solve_ivp``'s loop: the
solver object is SciPy's ``DOP853`` (its first step, its steps that the compiled path
hands back), each step's dense output is SciPy's ``Dop853DenseOutput`` over the
kernel's coefficients, and an event that changes sign is located by SciPy's
``handle_events`` on that step's dense output.

The kernel runs :data:`CHUNK` steps per call, so the wall clock (:mod:`.clock`) is
checked and progress reported between calls (a few milliseconds apart), not at every
evaluation.  A step the compiled evaluation cannot answer as the Python path would (see
the kernel) is taken by SciPy's solver with :class:`.integrate._System`, the next ones
by the kernel again.

As for the equation of motion, no call waits for a compile: the kernel (one for every
mechanism) is loaded from numba's on-disk cache, or compiled by a background process
while ``solve_ivp`` answers (``XVAL_FUSED=always``: compiled at once).  It serves a
mechanism whose compiled equation of motion runs on the solver's fused kernel (not a
parallelogram chain: its verified stretches are Python's).
``XVAL_FREE_COMPILED=0`` turns it off with the compiled equation of motion,
``XVAL_FREE_LOOP=0`` only this loop.
"""

from __future__ import annotations

import math
import os
import time
from functools import cache
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from scipy.integrate import solve_ivp

from .compiled import FastEOM, _mode, _Pending

#: Steps per compiled call: a few milliseconds of work (16 evaluations of 1-10 us per
#: step), so the wall-clock limit is checked that often.
CHUNK = 128
#: How often (s of wall time) a run answered by SciPy looks whether the background
#: compile of the kernel has finished.
RECHECK_S = 0.5


@cache
def _scipy():
    """SciPy's DOP853 pieces this loop drives; None where this SciPy lacks them (then
    ``solve_ivp`` answers)."""
    try:
        from scipy.integrate._ivp import dop853_coefficients as dc
        from scipy.integrate._ivp.common import OdeSolution
        from scipy.integrate._ivp.ivp import (
            MESSAGES,
            OdeResult,
            find_active_events,
            handle_events,
            prepare_events,
        )
        from scipy.integrate._ivp.rk import DOP853, Dop853DenseOutput
    except ImportError:
        return None
    if (dc.N_STAGES, dc.N_STAGES_EXTENDED, dc.INTERPOLATOR_POWER) != (12, 16, 7):
        return None
    co = tuple(np.ascontiguousarray(a, float) for a in (dc.A, dc.B, dc.C, dc.E3, dc.E5, dc.D))
    return SimpleNamespace(co=co, OdeSolution=OdeSolution, MESSAGES=MESSAGES,
                           OdeResult=OdeResult, find_active_events=find_active_events,
                           handle_events=handle_events, prepare_events=prepare_events,
                           DOP853=DOP853, Dense=Dop853DenseOutput)


@cache
def loop_source() -> str:
    """The kernel module's text (read, not imported: it imports numba)."""
    return (Path(__file__).resolve().parents[1] / "kernels" / "dop853_kernel.py").read_text()


class _LoopModule:
    """The kernel as :func:`analytic.kernels.background.start` takes one; its explicit
    signature compiles it at import, so there are no sample arguments."""

    def __init__(self):
        from ..kernels.cache import module_name
        self.source = SimpleNamespace(source=loop_source())
        self.name = module_name(self.source.source)

    def sample_args(self):
        return None


_LOOP: list = []


def _off() -> bool:
    """``XVAL_FREE_LOOP=0``: ``solve_ivp`` steps every segment."""
    return os.environ.get("XVAL_FREE_LOOP", "1").strip().lower() in ("0", "off", "no",
                                                                     "false")


def loop_kernel(compile_now: bool = False):
    """The compiled loop, or ``None`` (compiling in the background, or turned off)."""
    if _off() or _scipy() is None:
        return None
    if not _LOOP:
        _LOOP.append(_LoopModule())
    return _ready(_LOOP[0], compile_now or _mode() == "always")


def _ready(kern, compile_now: bool):
    """The kernel module loaded in this process (from numba's cache, or compiled at once
    when ``compile_now``), else ``None`` with a background compile started
    (:func:`analytic.free_motion.compiled._ready`, for a module compiled at import)."""
    from ..kernels.background import start
    from ..kernels.cache import _MODULES, _load, mark_ready, on_disk
    mod = _MODULES.get(kern.name)
    if mod is not None:
        return mod
    if compile_now or on_disk(kern.name):
        mod = _load(kern.source.source)  # its explicit signature: loaded or compiled
        mark_ready(kern.name, mod.kernel)
        return mod
    start(kern)
    return None


def _tables(motors) -> tuple:
    """The motors' effort tables as the kernel reads them (``TABLES``)."""
    tt, te, row0 = [], [], [0]
    for mo in motors:
        if mo.times:
            ts, es = mo._table
            tt.append(ts)
            te.append(es)
        row0.append(row0[-1] + (len(mo.times) if mo.times else 0))
    cat = (lambda a: np.ascontiguousarray(np.concatenate(a), float)) if tt else (
        lambda a: np.zeros(0))
    return cat(tt), cat(te), np.array(row0, np.int64)


class _Loop:
    """The kernel's arguments for one :class:`.compiled.FastEOM` (its arrays, shared:
    the kernel leaves them as ``FastEOM.evaluate`` would)."""

    def __init__(self, mod, fe: FastEOM, sysm, rtol: float, atol, ratio: float):
        self.mod, self.fe, self.sysm = mod, fe, sysm
        fk, p, lay = fe.fk, fe.fused_p, fe.layout
        self.fa = [fe._vals, fe._one, fe._zero, None, fk.pf, fk.pc, fe._carry, fe._stat,
                   fe._statf, fe._susp]
        self.fo = fe._outs
        self.ea = [fe.eff, None, lay.iv, lay.fv, lay.cv, p.x, p.xq, p.xqq, p.out]
        self.tab = _tables(fe.motors)
        loops = 1.0 if fe.lk.topo.n_loops else 0.0
        self.st = np.array([0.0, 0.0, 0.0, rtol, math.nan, 0.0, fe._tol, -math.inf,
                            math.inf, loops, ratio])
        self.ist = np.zeros(4, np.int64)
        self.atol = np.ascontiguousarray(atol, float)
        self.scale = np.ascontiguousarray(sysm.scale, float)

    def _signs(self, q: float):
        """The branch signs at ``q`` (``FastEOM._signs``) and the range of ``q`` where
        they are the Python path's: everywhere for held signs, the walk's segment."""
        fe = self.fe
        row = fe._signs(q)
        r = fe._signs_range
        if fe._held is not None and fe._held[1] is row or r is None:
            return row, -math.inf, math.inf
        lo, hi, starts, rows = r
        k = next(i for i, v in enumerate(rows) if v is row)
        return (row, lo if k == 0 else max(lo, starts[k]),
                hi if k + 1 == len(starts) else min(hi, starts[k + 1]))

    def run(self, solver, g: float):
        """Up to :data:`CHUNK` steps from the solver's state; returns ``(ts, ys, F,
        status)`` of the steps taken, the solver left after the last of them."""
        m = self.mod
        S_G, S_H, S_HI, S_KEY, S_LO, S_T, S_TB = (m.S_G, m.S_H, m.S_HI, m.S_KEY, m.S_LO,
                                                  m.S_T, m.S_TB)
        fe, st, sysm = self.fe, self.st, self.sysm
        y = np.array(solver.y, float)
        f = np.array(solver.f, float)
        self.fa[3], st[S_LO], st[S_HI] = self._signs(float(y[0]))
        if not isinstance(sysm.last, np.ndarray) or sysm.last.dtype != float:
            sysm.last = np.array(sysm.last, float)
        self.ea[1] = sysm.last = np.ascontiguousarray(sysm.last)
        st[S_T], st[S_TB], st[S_H], st[S_G] = solver.t, solver.t_bound, solver.h_abs, g
        st[S_KEY] = fe.key if fe.key is not None and fe.p is fe.fused_p else math.nan
        self.ist[0] = CHUNK
        ts = np.empty(CHUNK)
        ys = np.empty((CHUNK, len(y)))
        F = np.empty((CHUNK, 7, len(y)))
        m.kernel(fe.fk.fn, tuple(self.fa), self.fo, fe.eom, tuple(self.ea), self.tab,
                 _scipy().co, st, self.ist, y, f, self.atol, self.scale, ts, ys, F)
        fe.key = None if math.isnan(st[S_KEY]) else float(st[S_KEY])
        fe.p = fe.fused_p
        n = int(self.ist[1])
        sysm.nfev += int(self.ist[3])
        solver.nfev += int(self.ist[3])
        if n:
            t_old = float(ts[n - 2]) if n > 1 else solver.t
            solver.y_old = ys[n - 2].copy() if n > 1 else solver.y
            solver.t_old, solver.t, solver.y, solver.f = t_old, float(ts[n - 1]), y, f
            solver.h_previous = solver.t - t_old
            solver.h_abs = float(st[S_H])
            if solver.direction * (solver.t - solver.t_bound) >= 0:
                solver.status = "finished"
        return ts[:n], ys[:n], F[:n], int(self.ist[2]), float(st[S_G])


def _fast_of(sysm) -> FastEOM | None:
    """The segment's compiled equation of motion where the kernel can call it."""
    fe = sysm.fast
    if isinstance(fe, _Pending):
        fe = fe.real
    if isinstance(fe, FastEOM) and fe.fk is not None and fe.chain is None:
        return fe
    return None


def _compatible(mod, fe: FastEOM) -> bool:
    """Whether the kernel's function types are the compiled signatures of ``fe``'s two
    functions (a kernel edited without this loop's types: SciPy steps, not a crash)."""
    def has(fn, ftype) -> bool:
        return any(tuple(s.args) == tuple(ftype.signature.args) for s in fn.nopython_signatures)
    return has(fe.eom, mod.EOM) and has(fe.fk.fn, mod.FUSED)


def solve(sysm, span, y0, rtol: float, atol, ratio: float):
    """``solve_ivp(sysm, span, y0, method="DOP853", rtol=rtol, atol=atol,
    dense_output=True, events=[sysm.switch])``, the steps in compiled code where it can
    (``ratio``: the switching ratio the event subtracts, for the kernel's event)."""
    if _scipy() is None or sysm.fast is None or _off():
        return solve_ivp(sysm, span, y0, method="DOP853", rtol=rtol, atol=atol,
                         dense_output=True, events=[sysm.switch])
    return _Run(sysm, span, y0, rtol, atol, ratio).result()


class _Run:
    """``solve_ivp``'s loop for one terminal event with dense output, each step taken
    by the kernel (in chunks) or by SciPy's solver."""

    def __init__(self, sysm, span, y0, rtol, atol, ratio):
        sp = self.sp = _scipy()
        t0, tf = map(float, span)
        self.sysm, self.rtol, self.atol, self.ratio = sysm, rtol, atol, ratio
        self.solver = sp.DOP853(sysm, t0, y0, tf, rtol=rtol, atol=atol)
        events, self.max_events, self.event_dir = sp.prepare_events([sysm.switch])
        self.event = events[0]
        self.count = np.zeros(1)
        self.g = self.event(t0, y0)
        self.ts, self.ys, self.interps = [t0], [y0], []
        self.t_events, self.y_events = [], []
        self.loop = None
        self.next_check = 0.0

    def _loop(self):
        """The kernel for this segment, looked for again every :data:`RECHECK_S` while
        it compiles (or the compiled equation of motion does)."""
        if self.loop is None and time.monotonic() >= self.next_check:
            self.next_check = time.monotonic() + RECHECK_S
            mod = loop_kernel()  # its background compile starts with the equation's
            fe = _fast_of(self.sysm)
            if mod is not None and fe is not None and _compatible(mod, fe):
                self.loop = _Loop(mod, fe, self.sysm, self.rtol, self.atol, self.ratio)
        return self.loop

    def result(self):
        solver, status, message = self.solver, None, None
        while status is None:
            loop = self._loop()
            if loop is not None and solver.status == "running" and solver.t != solver.t_bound:
                status, python = self._chunk(loop)
                if status is not None or not python:
                    continue
            status, message = self._python_step()
        sp = self.sp
        ts = np.array(self.ts)
        return sp.OdeResult(
            t=ts, y=np.vstack(self.ys).T, sol=sp.OdeSolution(ts, self.interps),
            t_events=[np.asarray(self.t_events)], y_events=[np.asarray(self.y_events)],
            nfev=solver.nfev, njev=0, nlu=0, status=status,
            message=sp.MESSAGES.get(status, message), success=status >= 0)

    def _python_step(self):
        """One pass of ``solve_ivp``'s loop: SciPy's step, dense output and event."""
        solver = self.solver
        message = solver.step()
        if solver.status == "failed":
            return -1, message
        status = 0 if solver.status == "finished" else None
        sol = solver.dense_output()
        self.interps.append(sol)
        g_new = self.event(solver.t, solver.y)
        return self._after(solver.t_old, solver.t, solver.y, sol, g_new, status), message

    def _after(self, t_old, t, y, sol, g_new, status):
        """``solve_ivp``'s event handling and bookkeeping after a step."""
        sp = self.sp
        active = sp.find_active_events([self.g], [g_new], self.event_dir)
        if active.size > 0:
            self.count[active] += 1
            idx, roots, terminate = sp.handle_events(sol, [self.event], active, self.count,
                                                     self.max_events, t_old, t)
            for te in roots:
                self.t_events.append(te)
                self.y_events.append(sol(te))
            if terminate:
                status = 1
                t = roots[-1]
                y = sol(t)
        self.g = g_new
        if not (len(self.ts) > 1 and self.ts[-1] == t):
            self.ts.append(t)
            self.ys.append(y)
        elif self.interps:
            self.interps.pop()
        return status

    def _chunk(self, loop):
        """Steps by the kernel; ``(status, whether the next step is SciPy's)``."""
        solver, sp = self.solver, self.sp
        t_prev, y_prev = float(solver.t), solver.y
        ts, ys, F, code, g_last = loop.run(solver, self.g)
        n = len(ts)
        status = None
        for i in range(n):
            t_old = t_prev if i == 0 else float(ts[i - 1])
            y_old = y_prev if i == 0 else ys[i - 1]
            sol = sp.Dense(t_old, float(ts[i]), y_old, F[i])
            self.interps.append(sol)
            if i < n - 1:
                self.ts.append(float(ts[i]))
                self.ys.append(ys[i])
            else:
                done = 0 if solver.status == "finished" else None
                status = self._after(t_old, float(ts[i]), ys[i], sol, g_last, done)
        clock = self.sysm.clock
        if clock is not None:
            clock.check(float(solver.t))
        return status, code == loop.mod.ST_PYTHON
