"""Planar vector helpers of the Exudyn sessions, in the analytic conventions (angles
counter-clockwise, offsets in the body frame, ``(x, y)`` arrays): one vector, or rows of
them."""

from __future__ import annotations

import math

import numpy as np


def _rot(a: float, v) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def _perp(v) -> np.ndarray:
    return np.array([-v[1], v[0]])


def _cross(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def _world(theta, r) -> np.ndarray:
    """(K, 2): body offset ``r`` (2,) turned by each angle of ``theta`` (K,)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([c * r[0] - s * r[1], s * r[0] + c * r[1]], axis=1)


def _world_many(theta, r) -> np.ndarray:
    """(K, B, 2): offsets ``r`` (B, 2) turned by angles ``theta`` (K, B)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([c * r[:, 0] - s * r[:, 1], s * r[:, 0] + c * r[:, 1]], axis=2)


def _perp_rows(v) -> np.ndarray:
    return np.stack([-v[:, 1], v[:, 0]], axis=1)


def _dot(a, b) -> np.ndarray:
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1]


def _cross_rows(a, b) -> np.ndarray:
    return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]

