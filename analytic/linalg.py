"""Batched solution of small dense linear systems, vectorised over crank angles.

``numpy.linalg.solve`` pays a per-matrix LAPACK call; for the 1x1 to 3x3
systems of single-loop linkages an explicit Cramer's rule over the batch is
several times faster and exact to rounding.  Larger systems go to LAPACK.
"""

from __future__ import annotations

import numpy as np


def det_small(A: np.ndarray) -> np.ndarray:
    """Determinants of a batch ``(N, n, n)``."""
    n = A.shape[-1]
    if n == 1:
        return A[:, 0, 0]
    if n == 2:
        return A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] * A[:, 1, 0]
    if n == 3:
        return (A[:, 0, 0] * (A[:, 1, 1] * A[:, 2, 2] - A[:, 1, 2] * A[:, 2, 1])
                - A[:, 0, 1] * (A[:, 1, 0] * A[:, 2, 2] - A[:, 1, 2] * A[:, 2, 0])
                + A[:, 0, 2] * (A[:, 1, 0] * A[:, 2, 1] - A[:, 1, 1] * A[:, 2, 0]))
    return np.linalg.det(A)


def solve_small(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve ``A x = b`` for a batch: A ``(N, n, n)``, b ``(N, n)`` -> x ``(N, n)``.

    Singular matrices give inf/nan here; callers check the determinant or the
    condition number first and raise a typed error.
    """
    n = A.shape[-1]
    if n == 1:
        return b / A[:, 0, :]
    if n == 2:
        d = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] * A[:, 1, 0]
        x0 = (b[:, 0] * A[:, 1, 1] - A[:, 0, 1] * b[:, 1]) / d
        x1 = (A[:, 0, 0] * b[:, 1] - b[:, 0] * A[:, 1, 0]) / d
        return np.stack([x0, x1], axis=1)
    if n == 3:
        d = det_small(A)
        out = np.empty_like(b)
        for k in range(3):
            Ak = A.copy()
            Ak[:, :, k] = b
            out[:, k] = det_small(Ak) / d
        return out
    return np.linalg.solve(A, b[..., None])[..., 0]


def condition(A: np.ndarray) -> np.ndarray:
    """2-norm condition numbers of a batch ``(N, n, n)`` (inf where singular)."""
    n = A.shape[-1]
    if n == 0:
        return np.ones(A.shape[0])
    if n == 1:
        return np.where(A[:, 0, 0] != 0, 1.0, np.inf)
    if n == 2:
        # singular values of a 2x2 in closed form
        a, b, c, d = A[:, 0, 0], A[:, 0, 1], A[:, 1, 0], A[:, 1, 1]
        s1 = a * a + b * b + c * c + d * d
        det = np.abs(a * d - b * c)
        disc = np.sqrt(np.maximum(s1 * s1 - 4 * det * det, 0.0))
        smax = np.sqrt((s1 + disc) / 2)
        # smax * smin = |det|
        smin = np.where(smax > 0, det / np.where(smax > 0, smax, 1.0), 0.0)
        with np.errstate(divide="ignore"):
            return np.where(smin > 0, smax / np.where(smin > 0, smin, 1.0), np.inf)
    s = np.linalg.svd(A, compute_uv=False)
    with np.errstate(divide="ignore"):
        return np.where(s[:, -1] > 0, s[:, 0] / np.where(s[:, -1] > 0, s[:, -1], 1), np.inf)


def cmatmul(z: np.ndarray, M: np.ndarray) -> np.ndarray:
    """``z @ M`` for complex ``z`` and real ``M`` through two real BLAS products
    (numpy's mixed complex @ real product falls back to a slow loop)."""
    return (z.real @ M) + 1j * (z.imag @ M)
