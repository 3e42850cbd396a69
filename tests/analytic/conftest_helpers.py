"""Helpers importable by the analytic tests (fixtures live in tests/conftest.py)."""

from __future__ import annotations

import numpy as np

from analytic.sweep import input_values
from tests.conftest import four_bar, slider_crank  # noqa: F401  (re-exported)


def cycle_values(lk, n, margin=0.05):
    """``n`` input values over the case's full cycle; for an input that cannot turn
    fully, over its feasible range less ``margin`` of it at each end (at the limit
    positions the rates are singular, so differences there measure nothing)."""
    x, full, _ = input_values(lk, n)
    if full:
        return x
    span = x[-1] - x[0]
    return np.linspace(x[0] + margin * span, x[-1] - margin * span, n)
