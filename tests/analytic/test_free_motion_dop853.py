"""The compiled DOP853 loop (issue 34) against SciPy's DOP853.

Two kinds of expectation, neither from the loop itself: SciPy's own DOP853 stepping the
same closed-form ODE (the step sizes, states and dense-output coefficients it takes),
together with the ODE's closed-form solution; and, for the mechanisms, the trajectory
``solve_ivp`` gives with the loop switched off (``XVAL_FREE_LOOP=0``: the implementation
before it), whose independent checks (elliptic period, published Andrews reference,
absolute coordinates, energy balance) are in ``test_free_motion*.py``.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest

from analytic.free_motion import WallLimitError, compiled, dop853, simulate

from .test_free_motion_compiled import CHANGE_REL, _cases, assert_same_run, largest_change

pytest.importorskip("numba")

#: Step times, states and dense-output coefficients of the kernel against SciPy's, as a
#: fraction of their scale: the same operations in the same order (numba's np.dot
#: calls BLAS as numpy's does), so rounding apart.  At the loose tolerances used here
#: the error estimate is far above rounding, so a different summation order in another
#: BLAS moves a step size by ~1e-16 relative, not more.
STEP_REL = 1e-12


@pytest.fixture(scope="module")
def loop():
    compiled.eom_kernel(compile_now=True)
    mod = dop853.loop_kernel(compile_now=True)
    assert mod is not None
    return mod


# --- the kernel on closed-form ODEs: y = (q, q', ∫q'^2, ∫q^2, ∫q q') ---------------------
def _fakes(mod):
    """A fused kernel that accepts every state and an equation of motion
    ``q'' = fv[0] q + fv[1] q'`` (M = 1), with ``x = q, x_q = q`` (the event then fires
    where |q| reaches the switching ratio), compiled for the kernel's function types."""
    from numba import njit

    @njit(mod.FUSED.signature)
    def fused(level, vals, one, zero, signs, pf, pc, carry, stat, statf, susp, q, qd, qdd,
              theta, omega, alpha, E, zO, zv, za, A, det, trv, jp, jf, nm, sc):
        stat[0] = -1
        stat[2] = 0
        statf[0] = 0.0

    @njit(mod.EOM.signature)
    def eom(mode, new, q, qd, eff, ref, iv, fv, cv, theta, omega, alpha, E, zO, zv, za,
            sq, sqd, sqdd, x, xq, xqq, out):
        out[0] = 1.0
        out[3] = qd * qd
        out[4] = q * q
        out[5] = q * qd
        out[8] = fv[0] * q + fv[1] * qd
        x[0] = q
        xq[0] = q

    return fused, eom


def _kernel_args(mod, a: float, b: float):
    f2, c2 = np.zeros((1, 1)), np.zeros((1, 1), complex)
    fa = (np.zeros(1), np.ones(1), np.zeros(1), np.ones((1, 1)), np.zeros(1),
          np.zeros(1, complex), np.zeros(1), np.zeros(3, np.int64), np.zeros(1),
          np.zeros(1, np.int64))
    fo = (f2, f2, f2, f2, f2, f2, c2, c2, c2, c2, np.zeros((1, 1, 1)), np.zeros(1), c2, c2,
          np.zeros((1, 1, 2)), np.zeros((1, 1, 2)), f2)
    ea = (np.zeros(0), np.zeros(1), np.zeros(1, np.int64), np.array([a, b]),
          np.zeros(1, complex), np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(9))
    return fa, fo, ea


def _rhs(a, b):
    return lambda t, y: np.array([y[1], a * y[0] + b * y[1], y[1] ** 2, y[0] ** 2,
                                  y[0] * y[1]])


def _kernel_run(mod, a, b, y0, T, rtol, atol, ratio, steps=100_000):
    """Steps of the kernel from SciPy's first step size; ``(ts, ys, F, status)``."""
    from scipy.integrate._ivp.rk import DOP853
    start = DOP853(_rhs(a, b), 0.0, y0, T, rtol=rtol, atol=atol)
    fused, eom = _fakes(mod)
    fa, fo, ea = _kernel_args(mod, a, b)
    g0 = abs(y0[0]) - ratio
    st = np.array([0.0, T, start.h_abs, rtol, math.nan, g0, 1.0, -math.inf, math.inf, 0.0,
                   ratio])
    ist = np.array([steps, 0, 0, 0], np.int64)
    ts, ys, F = np.empty(steps), np.empty((steps, 5)), np.empty((steps, 7, 5))
    tab = (np.zeros(0), np.zeros(0), np.zeros(1, np.int64))
    mod.kernel(fused, fa, fo, eom, ea, tab, dop853._scipy().co, st, ist, np.array(y0, float),
               np.array(start.f, float), np.full(5, atol), np.ones(1), ts, ys, F)
    n = int(ist[1])
    return ts[:n], ys[:n], F[:n], int(ist[2])


def _scipy_run(a, b, y0, T, rtol, atol, n):
    from scipy.integrate._ivp.rk import DOP853
    s = DOP853(_rhs(a, b), 0.0, y0, T, rtol=rtol, atol=atol)
    ts, ys, F = [], [], []
    while s.status == "running" and len(ts) < n:
        s.step()
        ts.append(s.t)
        ys.append(s.y.copy())
        F.append(s.dense_output().F)
    return np.array(ts), np.array(ys), np.array(F)


@pytest.mark.parametrize("rtol", [1e-6, 1e-10])
@pytest.mark.parametrize("ode", ["harmonic", "exponential"])
def test_kernel_takes_scipys_steps(loop, ode, rtol):
    """Every step of the kernel is SciPy's: time, state, dense-output coefficients; and
    the state is the closed form's to the integration's tolerance."""
    a, b, T = (-1.0, 0.0, 20.0) if ode == "harmonic" else (0.0, 1.0, 5.0)
    y0 = np.array([0.0, 1.0, 0.0, 0.0, 0.0])
    atol = rtol * 1e-3
    ts, ys, F, status = _kernel_run(loop, a, b, y0, T, rtol, atol, ratio=1e9)
    assert status == loop.ST_FINISHED and ts[-1] == T
    ts0, ys0, F0 = _scipy_run(a, b, y0, T, rtol, atol, 10 ** 6)
    assert len(ts) == len(ts0) > 10
    assert np.max(np.abs(ts - ts0)) <= STEP_REL * T
    yscale = np.max(np.abs(ys0), axis=0)
    assert np.max(np.abs(ys - ys0) / yscale) <= STEP_REL
    assert np.max(np.abs(F - F0) / yscale[None, None]) <= STEP_REL
    q, qd = (np.sin(ts), np.cos(ts)) if ode == "harmonic" else (np.expm1(ts), np.exp(ts))
    work = (ts / 2 + np.sin(2 * ts) / 4) if ode == "harmonic" else np.expm1(2 * ts) / 2
    err = max(np.max(np.abs(ys[:, 0] - q)) / np.max(np.abs(q)),
              np.max(np.abs(ys[:, 1] - qd)) / np.max(np.abs(qd)),
              np.max(np.abs(ys[:, 2] - work)) / np.max(np.abs(work)))
    assert err <= 1e3 * rtol  # DOP853's global error over these spans: well within


def test_kernel_returns_at_the_step_where_the_event_changes_sign(loop):
    """The switching event ``|q| - ratio`` on q = sin t: the kernel stops after the
    step that contains t = asin(ratio), as solve_ivp's event check does."""
    y0 = np.array([0.0, 1.0, 0.0, 0.0, 0.0])
    ts, ys, F, status = _kernel_run(loop, -1.0, 0.0, y0, 20.0, 1e-10, 1e-13, ratio=0.5)
    assert status == loop.ST_EVENT
    assert math.asin(0.5) <= ts[-1] and (len(ts) == 1 or ts[-2] < math.asin(0.5))
    ts2, ys2, F2, status2 = _kernel_run(loop, -1.0, 0.0, y0, 20.0, 1e-10, 1e-13, ratio=0.5,
                                        steps=len(ts) - 1)
    assert status2 == loop.ST_STEPS and len(ts2) == len(ts) - 1


# --- the free motion with the loop and without ------------------------------------------
def _both(mech, T, monkeypatch):
    """``(with the loop, without it, chunks the kernel ran)``."""
    runs = []
    real = dop853._Loop.run

    def counting(self, *a):
        got = real(self, *a)
        runs.append(len(got[0]))
        return got

    monkeypatch.setattr(dop853._Loop, "run", counting)
    assert compiled.prepare(mech)
    # every coordinate's fused kernel now (the switching rocker drives four joints in
    # turn; each other one would compile in the background while SciPy steps)
    monkeypatch.setenv("XVAL_FUSED", "always")
    fast = simulate(mech, duration=T)
    monkeypatch.setenv("XVAL_FREE_LOOP", "0")
    ref = simulate(mech, duration=T)
    return fast, ref, runs


#: cases whose evaluations need Python per state: solve_ivp answers them (a
#: parallelogram chain's verified stretches)
NOT_LOOPED = {"a02-n8"}


@pytest.mark.parametrize("name", list(_cases()))
def test_loop_matches_solve_ivp(name, loop, monkeypatch):
    make, T, tol = _cases()[name]
    fast, ref, runs = _both(make(), T, monkeypatch)
    if name not in NOT_LOOPED:  # every step the compiled equation of motion serves
        served = [s for s in fast.segments
                  if isinstance(s.lk.derived.get("free_fast"), compiled.FastEOM)]
        assert served and sum(runs) > 0.9 * sum(len(s.ts) - 1 for s in served), \
            "the kernel took few of the steps"
    assert_same_run(fast, ref, T, tol)


def test_steps_by_scipy_while_the_loop_compiles(loop, monkeypatch):
    """The kernel not yet compiled: this module's copy of solve_ivp's loop steps with
    SciPy's solver, and gives solve_ivp's trajectory."""
    make, T, tol = _cases()["rocker-switching"]
    mech = make()
    monkeypatch.setenv("XVAL_FUSED", "always")
    monkeypatch.setattr(dop853, "loop_kernel", lambda compile_now=False: None)
    fast = simulate(mech, duration=T)
    monkeypatch.setenv("XVAL_FREE_LOOP", "0")
    ref = simulate(mech, duration=T)
    assert fast.nfev == ref.nfev and len(fast.switches) == len(ref.switches)
    worst = largest_change(fast, ref, np.linspace(0.0, T, 101))
    assert max(worst.values()) <= CHANGE_REL, worst


def test_wall_limit_stops_a_looped_run(loop):
    """A 1e4 s run of the seed four-bar, all of it in the kernel, stops at a 1 s limit:
    the clock is read between chunks of :data:`dop853.CHUNK` steps (milliseconds)."""
    import time

    from analytic import load_case
    from sim_models.builders.free_cases import released
    mech = released(load_case("seed-four-bar"), duration=1e4)
    assert compiled.prepare(mech)
    t0 = time.monotonic()
    with pytest.raises(WallLimitError, match=r"wall-clock limit of 1 s at t = .* of 10000 s"):
        simulate(mech, duration=1e4, wall_limit=1.0)
    # the limit plus one chunk, the error's message and a loaded machine's scheduling
    assert time.monotonic() - t0 < 1.0 + 2.0


def test_first_call_waits_for_no_compile_of_the_loop(tmp_path):
    """Empty caches: solve_ivp answers, the loop's kernel is neither compiled nor loaded
    in the calling process, and its background compile was asked for (turned off here,
    so nothing outlives the test)."""
    code = (
        "from analytic import load_case\n"
        "from analytic.free_motion import simulate, dop853\n"
        "from analytic.kernels import background, cache\n"
        "from sim_models.builders.free_cases import released\n"
        "m = released(load_case('seed-four-bar'), duration=0.2)\n"
        "tr = simulate(m, duration=0.2)\n"
        "assert tr.nfev > 0\n"
        "name = dop853._LOOP[0].name\n"
        "assert name not in cache._MODULES, list(cache._MODULES)\n"
        "assert name in background._STARTED\n"
        "print('ok')\n")
    env = dict(os.environ, XVAL_KERNEL_CACHE=str(tmp_path / "k"),
               NUMBA_CACHE_DIR=str(tmp_path / "n"), XVAL_BACKGROUND_COMPILE="0")
    for k in ("XVAL_FUSED", "XVAL_FREE_LOOP", "XVAL_FREE_COMPILED"):
        env.pop(k, None)
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    r = subprocess.run([sys.executable, "-c", code], env=env, cwd=root, capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr[-2000:]
