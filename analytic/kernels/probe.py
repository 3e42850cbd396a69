"""Which complex multiply numpy's array loop computes on this machine (no numba here:
the kernel's source, and so its cache key, is generated without importing it)."""

from __future__ import annotations

import functools


def numpy_complex_multiply() -> str:
    """Which of the two helpers reproduces numpy's complex array multiply on this
    machine (``"cmul_fused"`` or ``"cmul_plain"``; ``"cmul_fused"`` when neither does:
    :func:`complex_multiply_reproduced` then says False), by exact rational arithmetic
    on inputs where the two differ.  numpy dispatches its loop at run time by CPU, so
    the answer is a property of the machine, and it is part of the kernel's source."""
    return _probe()[0]


def complex_multiply_reproduced() -> bool:
    """Whether a helper reproduces numpy's complex multiply bit for bit here (the
    compiled and numpy paths are then the same arithmetic; on a machine where neither
    does, they differ by rounding, amplified near limit positions)."""
    return _probe()[1]


@functools.cache
def _probe() -> tuple[str, bool]:
    from fractions import Fraction

    import numpy as np

    def fma(x, y, z):  # correctly rounded, as the FMA instruction
        return float(Fraction(x) * Fraction(y) + Fraction(z))

    # Python's generator, not numpy.random: importing that took 0.1 s of a process's
    # first call (the probe runs when a kernel's source is first generated)
    import random
    rng = random.Random(20261123)
    a, b = (np.array([complex(rng.gauss(0, 1), rng.gauss(0, 1)) for _ in range(64)])
            for _ in range(2))
    got = a * b
    pairs = list(zip(a.tolist(), b.tolist(), strict=True))
    fused = np.array([complex(fma(x.real, y.real, -(x.imag * y.imag)),
                              fma(x.real, y.imag, x.imag * y.real)) for x, y in pairs])
    plain = np.array([complex(x.real * y.real - x.imag * y.imag,
                              x.real * y.imag + x.imag * y.real) for x, y in pairs])
    if np.array_equal(got, fused):
        return "cmul_fused", True
    if np.array_equal(got, plain):
        return "cmul_plain", True
    return "cmul_fused", False
