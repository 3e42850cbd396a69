"""Planar vector helpers: a 2-D vector as a complex number ``x + iy`` (m, world or
body frame, as the caller's), a rotation by ``theta`` (rad, counter-clockwise
positive) as the product with ``exp(i theta)``.

The solver's one place for these conversions and products, used by the position
analysis, the kinematics, the kinetostatics and the kernel's code generator.
"""

from __future__ import annotations

import math

import numpy as np


def as_xy(z: np.ndarray) -> np.ndarray:
    """View a complex array ``(...)`` as real ``(..., 2)`` (x, y), without copying."""
    z = np.ascontiguousarray(z)
    return z.view(np.float64).reshape(*z.shape, 2)


def cplx(v) -> complex:
    """The 2-D vector ``(x, y)`` as the complex ``x + iy``."""
    return complex(float(v[0]), float(v[1]))


def cross(a, b):
    """z-component of the planar cross product of complex vectors: Im(conj(a) b)."""
    return a.real * b.imag - a.imag * b.real


def rotation(angle: float) -> np.ndarray:
    """The 2x2 matrix of a rotation by ``angle`` (rad, counter-clockwise positive)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])
