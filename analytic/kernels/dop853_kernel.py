"""SciPy's DOP853 steps, many per call, in compiled code (the free motion's integrator).

Not imported: :mod:`analytic.free_motion.dop853` reads this file's text and loads it as a
kernel module (:func:`analytic.kernels.cache._load`), like the generic equation of motion
(:mod:`analytic.kernels.free_eom_kernel`).  ``kernel`` has one explicit signature, so it
is compiled (or loaded from numba's on-disk cache) when the module is imported: the
structure's two compiled functions (the solver's fused kernel and the generic equation
of motion) come in as first-class function arguments of fixed types, so one compile
serves every mechanism.

Each step is ``scipy.integrate._ivp.rk.DOP853._step_impl`` (with ``rk_step``) term by
term: the same Butcher tableau (passed in from ``dop853_coefficients``), the same error
norm (the fifth- and third-order estimates blended), the same step-size controller
(safety 0.9, factors 0.2..10, exponent -1/8, no growth after a rejection), the same
minimum step; after each accepted step the dense output's three extra stages and its
coefficients ``F`` (``_dense_output_impl``), then the switching event at the new state
(``solve_ivp`` evaluates events after the dense output).  The right-hand side at a stage
is :meth:`analytic.free_motion.compiled.FastEOM.evaluate` and
:class:`analytic.free_motion.integrate._System`'s use of it, in the same order: a new
configuration runs the fused kernel (its answer checked as ``FastEOM._fused`` does) and
unwraps the joint coordinates to the last ones (``ref``, updated), a repeated one only
the sums.

A call returns (``ist[2]``, see ``ST_*``) after ``ist[0]`` steps, at the end of the
interval, after a step whose event changed sign (located by the caller from the step's
dense output, as ``solve_ivp`` does), or before a step it cannot take as the Python path
would: a stage the compiled evaluation declines (branch signs outside their range, a
state the fused kernel rejects, a non-finite value, no inertia), or a step below the
minimum.  That step is then undone (``ref`` and the stage state restored) and the
caller takes it with SciPy's solver and the Python right-hand side.
"""

import math

import numpy as np
from numba import njit, types

F1 = types.float64[::1]
F2 = types.float64[:, ::1]
F3 = types.float64[:, :, ::1]
C1 = types.complex128[::1]
C2 = types.complex128[:, ::1]
I1 = types.int64[::1]
#: the solver's fused kernel (:mod:`analytic.fused`): level, values, rates,
#: accelerations, signs, pf, pc, carry, stat, statf, suspects, then its 17 outputs
FUSED = types.FunctionType(types.none(types.int64, F1, F1, F1, F2, F1, C1, F1, I1, F1, I1,
                                      F2, F2, F2, F2, F2, F2, C2, C2, C2, C2, F3, F1, C2,
                                      C2, F3, F3, F2))
#: the generic equation of motion (:mod:`analytic.kernels.free_eom_kernel`)
EOM = types.FunctionType(types.none(types.int64, types.int64, types.float64, types.float64,
                                    F1, F1, I1, F1, C1, F2, F2, F2, C2, C2, C2, C2, F2, F2,
                                    F2, F1, F1, F1, F1))
#: the fused kernel's inputs: values, rates, accelerations, signs, pf, pc, carry, stat,
#: statf, suspects
FARGS = types.Tuple((F1, F1, F1, F2, F1, C1, F1, I1, F1, I1))
#: the fused kernel's 17 outputs (q, qd, qdd, theta, omega, alpha, E, zO, zv, za, A,
#: det, trv, jp, jf, nm, sc)
FOUT = types.Tuple((F2, F2, F2, F2, F2, F2, C2, C2, C2, C2, F3, F1, C2, C2, F3, F3, F2))
#: the equation's other arguments: efforts, ref, iv, fv, cv, x, x_q, x_qq, out
EARGS = types.Tuple((F1, F1, I1, F1, C1, F1, F1, F1, F1))
#: the motors' effort tables: times, efforts (all motors' rows, one after the other) and
#: each motor's first row (n_motors + 1 entries); a motor without a table has no rows
TABLES = types.Tuple((F1, F1, I1))
#: DOP853's tableau: A (16, 16), B (12), C (16), E3 (13), E5 (13), D (4, 16)
COEF = types.Tuple((F2, F1, F1, F1, F1, F2))

# ``st`` (float64): the integrator's state and settings, updated in place
S_T, S_TB, S_H, S_RTOL, S_KEY, S_G, S_TOL, S_LO, S_HI, S_LOOPS, S_RATIO = range(11)
# ``ist`` (int64): [steps allowed, steps taken, status, evaluations]
ST_STEPS, ST_FINISHED, ST_EVENT, ST_PYTHON = 0, 1, 2, 3

N_STAGES = 12
SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
EXPONENT = -1.0 / 8.0  # -1 / (error estimator order 7 + 1)


@njit(cache=True, nogil=True)
def _config(fused, fa, fo, eom, ea, tab, st, t, q, qd):
    """The equation of motion at ``(q, qd)`` and time ``t`` into ``ea[8]``
    (``FastEOM.evaluate`` and ``_System._fast``); False where the Python path must
    answer."""
    new = not q == st[S_KEY]  # a NaN key: nothing held
    if new:
        if not (st[S_LO] <= q < st[S_HI]):  # another row of branch signs
            return False
        vals, one, zero, signs, pf, pc, carry, stat, statf, susp = fa
        vals[0] = q
        carry[:] = 0.0
        stat[:] = 0
        statf[:] = 0.0
        fused(2, vals, one, zero, signs, pf, pc, carry, stat, statf, susp, fo[0], fo[1],
              fo[2], fo[3], fo[4], fo[5], fo[6], fo[7], fo[8], fo[9], fo[10], fo[11], fo[12],
              fo[13], fo[14], fo[15], fo[16])
        if not (stat[0] < 0 and stat[2] == 0 and (st[S_LOOPS] == 0.0
                                                  or statf[0] <= st[S_TOL])):
            st[S_KEY] = np.nan
            return False
    eff, ref, iv, fv, cv, x, xq, xqq, out = ea
    tt, te, row0 = tab
    for m in range(row0.shape[0] - 1):  # Motor.at: np.interp in the table, if any
        if row0[m + 1] > row0[m]:
            eff[m] = np.interp(t, tt[row0[m]:row0[m + 1]], te[row0[m]:row0[m + 1]])
    eom(0, 1 if new else 0, q, qd, eff, ref, iv, fv, cv, fo[3], fo[4], fo[5], fo[6], fo[7],
        fo[8], fo[9], fo[0], fo[1], fo[2], x, xq, xqq, out)
    if new:
        st[S_KEY] = q
        ref[:] = x
    return True


@njit(cache=True, nogil=True)
def _rhs(fused, fa, fo, eom, ea, tab, st, t, yv, k, row):
    """``K[row] = (q', q'', motor power, load power, damper power)`` at ``(t, yv)``;
    False where the Python path answers (it would take the numpy path or raise)."""
    if not _config(fused, fa, fo, eom, ea, tab, st, t, yv[0], yv[1]):
        return False
    out = ea[8]
    if not (math.isfinite(out[8]) and out[0] > 0):
        return False
    k[row, 0] = yv[1]
    k[row, 1] = out[8]
    k[row, 2] = out[3]
    k[row, 3] = out[4]
    k[row, 4] = out[5]
    for i in range(5):
        if not math.isfinite(k[row, i]):
            return False
    return True


@njit(cache=True, nogil=True)
def _stage(k, a, s, h, y):
    """``y + np.dot(K[:s].T, a[:s]) * h`` (``rk_step``; numba's ``np.dot`` calls the
    same BLAS routine as numpy's, so the sums are SciPy's to the bit where both use
    one BLAS)."""
    return y + np.dot(k[:s].T, a[:s]) * h


@njit(cache=True, nogil=True)
def _error_norm(k, co, h, y, y_new, atol, rtol):
    """``DOP853._estimate_error_norm`` with ``scale = atol + max(|y|, |y_new|) rtol``."""
    E3, E5 = co[3], co[4]
    scale = atol + np.maximum(np.abs(y), np.abs(y_new)) * rtol
    kk = k[:N_STAGES + 1].T
    err5 = np.dot(kk, E5) / scale
    err3 = np.dot(kk, E3) / scale
    n5 = math.sqrt(np.dot(err5, err5)) ** 2  # np.linalg.norm(err5) ** 2
    n3 = math.sqrt(np.dot(err3, err3)) ** 2
    if n5 == 0 and n3 == 0:
        return 0.0
    denom = n5 + 0.01 * n3
    return abs(h) * n5 / math.sqrt(denom * scale.shape[0])


@njit(cache=True, nogil=True)
def _attempt(fused, fa, fo, eom, ea, tab, co, st, t, h, y, k):
    """One try of ``rk_step`` from ``(t, y)`` (``K[0]`` holds ``f``) over ``h``: the
    stages into ``K[1:13]``; the new state, or None where a stage goes to the Python
    path."""
    A, B, C = co[0], co[1], co[2]
    for s in range(1, N_STAGES):
        if not _rhs(fused, fa, fo, eom, ea, tab, st, t + C[s] * h, _stage(k, A[s], s, h, y),
                    k, s):
            return None
    y_new = y + h * np.dot(k[:N_STAGES].T, B)
    if not _rhs(fused, fa, fo, eom, ea, tab, st, t + h, y_new, k, N_STAGES):
        return None
    return y_new


@njit(cache=True, nogil=True)
def _dense(fused, fa, fo, eom, ea, tab, co, st, t_old, h, y_old, y_new, k, F):
    """``DOP853._dense_output_impl``: the three extra stages, then ``F`` (7, n)."""
    A, C, D = co[0], co[2], co[5]
    for s in range(N_STAGES + 1, 16):
        if not _rhs(fused, fa, fo, eom, ea, tab, st, t_old + C[s] * h,
                    _stage(k, A[s], s, h, y_old), k, s):
            return False
    f_old = k[0]
    delta_y = y_new - y_old
    F[0] = delta_y
    F[1] = h * f_old - delta_y
    F[2] = 2 * delta_y - h * (k[N_STAGES] + f_old)
    F[3:] = h * np.dot(D, k)
    return True


@njit(cache=True, nogil=True)
def _switch(fused, fa, fo, eom, ea, tab, st, scale, q):
    """``_System.switch``: the largest joint rate per unit rate of ``q``, less the
    switching ratio (NaN where the Python path answers); evaluated at rest and t = 0,
    as ``_System.ratios``."""
    if not _config(fused, fa, fo, eom, ea, tab, st, 0.0, q, 0.0):
        return np.nan
    xq = ea[6]
    r = -np.inf
    for j in range(xq.shape[0]):
        v = abs(xq[j]) * scale[j]
        if v > r:
            r = v
    return r - st[S_RATIO]


@njit(cache=True, nogil=True)
def _step(fused, fa, fo, eom, ea, tab, co, st, y, f, atol, k):
    """``_step_impl`` from ``(st[S_T], y)`` with ``f``: returns ``(evaluations, h,
    y_new)`` of the accepted step (``K[12]`` its derivative, ``st[S_H]`` the next step
    size), or ``(-1, 0, y)`` where the Python path takes it."""
    t, t_bound, rtol = st[S_T], st[S_TB], st[S_RTOL]
    min_step = 10 * abs(np.nextafter(t, np.inf) - t)
    h_abs = st[S_H]
    if h_abs < min_step:
        h_abs = min_step
    rejected = False
    nfev = 0
    while True:
        if h_abs < min_step:
            return -1, 0.0, y
        t_new = t + h_abs
        if t_new - t_bound > 0:
            t_new = t_bound
        h = t_new - t
        h_abs = abs(h)
        k[0] = f
        y_new = _attempt(fused, fa, fo, eom, ea, tab, co, st, t, h, y, k)
        if y_new is None:
            return -1, 0.0, y
        nfev += N_STAGES
        err = _error_norm(k, co, h, y, y_new, atol, rtol)
        if err < 1:
            factor = MAX_FACTOR if err == 0 else min(MAX_FACTOR, SAFETY * err ** EXPONENT)
            if rejected:
                factor = min(1.0, factor)
            st[S_H] = h_abs * factor
            return nfev, h, y_new
        if not math.isfinite(err):
            return -1, 0.0, y
        h_abs *= max(MIN_FACTOR, SAFETY * err ** EXPONENT)
        rejected = True


#: ``kernel``'s one signature (compiled at import)
SIG = types.void(FUSED, FARGS, FOUT, EOM, EARGS, TABLES, COEF, F1, I1, F1, F1, F1, F1, F1,
                 F2, F3)


@njit(SIG, cache=True, nogil=True)
def kernel(fused, fa, fo, eom, ea, tab, co, st, ist, y, f, atol, scale, ts, ys_out,
           F_out):
    """Up to ``ist[0]`` steps from ``(st[S_T], y)`` with derivative ``f`` (both updated):
    step ``i``'s time, state and dense-output coefficients into ``ts[i]``, ``ys_out[i]``,
    ``F_out[i]``; ``ist[1]`` steps taken, ``ist[2]`` why it returned, ``ist[3]`` the
    evaluations of the steps taken."""
    n = y.shape[0]
    ref = ea[1]
    ref0 = ref.copy()
    k = np.empty((16, n))
    ist[1] = 0
    ist[3] = 0
    while ist[1] < ist[0]:
        ref0[:] = ref
        h0 = st[S_H]
        nfev, h, y_new = _step(fused, fa, fo, eom, ea, tab, co, st, y, f, atol, k)
        i = ist[1]
        t_old = st[S_T]
        if nfev < 0 or not _dense(fused, fa, fo, eom, ea, tab, co, st, t_old, h, y, y_new,
                                  k, F_out[i]):
            g = np.nan
        else:
            g = _switch(fused, fa, fo, eom, ea, tab, st, scale, y_new[0])
        if not math.isfinite(g):  # undone: the Python path takes this step
            ref[:] = ref0
            st[S_KEY] = np.nan  # the poses held are a later stage's: computed anew
            st[S_H] = h0
            ist[2] = ST_PYTHON
            return
        t = t_old + h
        ts[i] = t
        for j in range(n):
            ys_out[i, j] = y_new[j]
            y[j] = y_new[j]
            f[j] = k[N_STAGES, j]
        st[S_T] = t
        ist[1] = i + 1
        ist[3] += nfev + 3
        g_old = st[S_G]
        st[S_G] = g
        if g_old <= 0 and g >= 0:  # solve_ivp's find_active_events, direction +1
            ist[2] = ST_EVENT
            return
        if t - st[S_TB] >= 0:
            ist[2] = ST_FINISHED
            return
    ist[2] = ST_STEPS
