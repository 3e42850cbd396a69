"""Small dense linear algebra for the fused kernels, one matrix at a time.

The same formulas as :mod:`analytic.linalg` (explicit Cramer's rule up to 3x3, so
the compiled and numpy paths agree to rounding); larger systems by LU with partial
pivoting, as LAPACK's ``getrf``/``getrs`` do for ``numpy.linalg.solve``.  Scratch
matrices are passed in, so nothing is allocated per configuration.
"""

from __future__ import annotations

import math

from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic


@intrinsic
def _fma(typingctx, a, b, c):
    """``a * b + c`` rounded once (LLVM's fma)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        d = ir.DoubleType()
        fn = builder.module.declare_intrinsic("llvm.fma", [d], ir.FunctionType(d, [d, d, d]))
        return builder.call(fn, args)
    return sig, codegen


# The scalar helpers (cmul_*, cabs) are called at a hundred sites of a kernel: with
# numba's IR-level inline="always" on them the four-bar's kernel compiled in 11 s, the
# six-bar's in 19 s and the quick-return's in 20 s; without, 8, 14 and 14 s (load ~1).
# LLVM inlines them anyway: the kernels run at the same speed.  The matrix helpers,
# called a few times with arrays, keep it (without it the six-bar ran 13% slower).
@njit(cache=True, error_model="numpy", nogil=True)
def cmul_fused(a, b):
    """``a * b`` for complex ``a, b`` bit for bit as numpy's SIMD loop on an FMA machine
    computes it for arrays: ``re = fma(ar, br, -(ai bi))``, ``im = fma(ar, bi, ai br)``.
    (numba's ``*`` rounds each of the four products: it differs from numpy in the last
    bit for ~40% of the inputs, which the rates amplify near a limit position.)"""
    return complex(_fma(a.real, b.real, -(a.imag * b.imag)),
                   _fma(a.real, b.imag, a.imag * b.real))


@njit(cache=True, error_model="numpy", nogil=True)
def cmul_plain(a, b):
    """``a * b`` with four rounded products: numpy's complex multiply without FMA."""
    return complex(a.real * b.real - a.imag * b.imag, a.real * b.imag + a.imag * b.real)


# the probe is numba-free (analytic.kernels.probe): generating a kernel's source, and
# so knowing whether it is cached, does not import numba
from .probe import complex_multiply_reproduced, numpy_complex_multiply  # noqa: E402,F401


@njit(cache=True, error_model="numpy", nogil=True)
def cabs(x, y):
    """``|x + iy|`` bit for bit as numpy 2's (SIMD) complex absolute value computes it:
    the larger magnitude times ``sqrt(1 + r^2)``, ``r`` the ratio, ``1 + r^2`` fused.
    (libm's hypot differs in the last bit for a third of the inputs; near a limit
    position the rates amplify that by the Jacobian's condition number.)"""
    x, y = abs(x), abs(y)
    if math.isinf(x) or math.isinf(y):
        return math.inf
    if x != x or y != y:
        return math.nan
    hi, lo = max(x, y), min(x, y)
    if hi == 0.0:
        return 0.0
    r = lo / hi
    return hi * math.sqrt(_fma(r, r, 1.0))


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _det3(A00, A01, A02, A10, A11, A12, A20, A21, A22):
    return (A00 * (A11 * A22 - A12 * A21)
            - A01 * (A10 * A22 - A12 * A20)
            + A02 * (A10 * A21 - A11 * A20))


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def lu_factor(A, n, lu, piv):
    """LU factors of ``A[:n, :n]`` in ``lu`` (unit lower L below the diagonal), row
    pivots in ``piv``; returns the permutation's sign."""
    for r in range(n):
        for c in range(n):
            lu[r, c] = A[r, c]
    sign = 1.0
    for j in range(n):
        p = j
        big = abs(lu[j, j])
        for r in range(j + 1, n):
            if abs(lu[r, j]) > big:
                big = abs(lu[r, j])
                p = r
        piv[j] = p
        if p != j:
            sign = -sign
            for c in range(n):
                t = lu[j, c]
                lu[j, c] = lu[p, c]
                lu[p, c] = t
        d = lu[j, j]
        if d != 0.0:
            for r in range(j + 1, n):
                lu[r, j] = lu[r, j] / d
                f = lu[r, j]
                for c in range(j + 1, n):
                    lu[r, c] -= f * lu[j, c]
    return sign


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def det_small(A, n, lu, piv):
    """Determinant of ``A[:n, :n]``."""
    if n == 1:
        return A[0, 0]
    if n == 2:
        return A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    if n == 3:
        return _det3(A[0, 0], A[0, 1], A[0, 2], A[1, 0], A[1, 1], A[1, 2],
                     A[2, 0], A[2, 1], A[2, 2])
    d = lu_factor(A, n, lu, piv)
    for j in range(n):
        d *= lu[j, j]
    return d


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def solve_small(A, b, n, out, lu, piv):
    """Solve ``A[:n, :n] x = b[:n]`` into ``out[:n]`` (inf/nan where singular)."""
    if n == 0:
        return
    if n == 1:
        out[0] = b[0] / A[0, 0]
        return
    if n == 2:
        d = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
        out[0] = (b[0] * A[1, 1] - A[0, 1] * b[1]) / d
        out[1] = (A[0, 0] * b[1] - b[0] * A[1, 0]) / d
        return
    if n == 3:
        d = _det3(A[0, 0], A[0, 1], A[0, 2], A[1, 0], A[1, 1], A[1, 2],
                  A[2, 0], A[2, 1], A[2, 2])
        out[0] = _det3(b[0], A[0, 1], A[0, 2], b[1], A[1, 1], A[1, 2],
                       b[2], A[2, 1], A[2, 2]) / d
        out[1] = _det3(A[0, 0], b[0], A[0, 2], A[1, 0], b[1], A[1, 2],
                       A[2, 0], b[2], A[2, 2]) / d
        out[2] = _det3(A[0, 0], A[0, 1], b[0], A[1, 0], A[1, 1], b[1],
                       A[2, 0], A[2, 1], b[2]) / d
        return
    lu_factor(A, n, lu, piv)
    lu_solve(lu, piv, b, n, out)


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def lu_det(lu, n, sign):
    """Determinant from the factors of :func:`lu_factor` and its sign."""
    d = sign
    for j in range(n):
        d *= lu[j, j]
    return d


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def lu_solve(lu, piv, b, n, out):
    """Solve with the factors of :func:`lu_factor` (one factorisation, many right-hand
    sides: the rates and the accelerations share their matrix)."""
    for r in range(n):
        out[r] = b[r]
    for j in range(n):  # apply the row swaps, then forward substitution (unit L)
        p = piv[j]
        if p != j:
            t = out[j]
            out[j] = out[p]
            out[p] = t
    for r in range(n):
        s = out[r]
        for c in range(r):
            s -= lu[r, c] * out[c]
        out[r] = s
    for r in range(n - 1, -1, -1):
        s = out[r]
        for c in range(r + 1, n):
            s -= lu[r, c] * out[c]
        out[r] = s / lu[r, r]
