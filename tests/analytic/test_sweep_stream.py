"""The streamed sweep holds nothing per point (issue 23, item 5): its input values, events
and summary are made block by block, and must be those of the whole series.

The references are the whole-array computations: ``np.linspace`` and the in-memory
:func:`analytic.sweep.input_values` for the inputs, :func:`analytic.refine.sign_brackets`
and numpy's ``argmin``/``argmax`` for the reductions, and the in-memory sweep
(:func:`analytic.sweep.sweep`, arrays of every point) for the events and the summary.
Block sizes are chosen small and odd so that sign changes, extremes and their
neighbours fall on block boundaries.
"""

from __future__ import annotations

import io
import math
import tracemalloc
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from analytic import Linkage, load_case
from analytic.refine import sign_brackets
from analytic.stream import sweep_csv
from analytic.sweep import InputGrid, input_grid, input_values, range_grid
from analytic.sweep_facts import Extremes, SignTracker, array_stats

BUGS = Path(__file__).resolve().parents[1] / "data" / "bugs"
#: a streamed sweep's peak memory may grow by this fraction when the points grow 8-fold
#: (allocator rounding, the events list); per-point storage would grow it ~8-fold
FLAT = 0.15
#: the power balance error is rounding: 1e-16 a term, summed over a few terms, times
#: the growth of the rates near a limit position; measured 1e-15
POWER_ROUND_OFF = 1e-12


def _blocks(n, sizes):
    """Consecutive ``(i, k)`` covering ``range(n)`` with the given sizes, cycled."""
    i, j = 0, 0
    while i < n:
        k = min(n, i + sizes[j % len(sizes)])
        yield i, k
        i, j = k, j + 1


@pytest.mark.parametrize("grid", [
    InputGrid("turn", math.radians(60.0), 0.0, 1001, True),
    InputGrid("turn", 0.0, 0.0, 360, True),
    InputGrid("linspace", -0.3, 1.7, 977, True, -0.31, 1.71),
    InputGrid("linspace", 0.01, 0.25, 500, False),
])
def test_grid_blocks_are_the_values(grid):
    whole = grid.values()
    parts = np.concatenate([grid.block(i, k) for i, k in _blocks(grid.n, [7, 64, 1, 300])])
    np.testing.assert_array_equal(parts, whole)
    np.testing.assert_array_equal(grid.at([0, 5, -1]), whole[[0, 5, -1]])
    if grid.kind == "linspace":  # numpy's own linspace before the snapping
        np.testing.assert_array_equal(InputGrid("linspace", grid.a, grid.b, grid.n, False)
                                      .block(0, grid.n), np.linspace(grid.a, grid.b, grid.n))


@pytest.mark.parametrize("case", ["seed-four-bar", "hibbeler-16-30", "six-bar",
                                  str(BUGS / "limited-sweep-zeroed-forces.toml")])
def test_sweep_grid_is_input_values(case):
    lk = Linkage(load_case(case))
    grid, full, feas = input_grid(lk, 777)
    x, full0, feas0 = input_values(lk, 777)
    assert full == full0 and feas == feas0
    np.testing.assert_array_equal(np.concatenate([grid.block(i, k) for i, k in
                                                  _blocks(777, [50, 3])]), x)
    r = range_grid(lk, (0.1, 2.0), 99)
    np.testing.assert_array_equal(r.block(0, 40), r.values()[:40])


def _series(rng, n):
    """A series with sign changes, exact zeros, round-off runs and a late peak."""
    t = np.linspace(0, 6 * np.pi, n)
    y = np.sin(t) * (1 + 0.5 * rng.standard_normal(n))
    y[rng.integers(0, n, n // 20)] = 0.0
    y[n // 3:n // 3 + 25] = 1e-14 * rng.standard_normal(25)  # round-off, not sign
    return y


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("periodic", [False, True])
def test_sign_tracker_is_sign_brackets(seed, periodic):
    rng = np.random.default_rng(seed)
    n = 600
    x = np.linspace(0.0, 1.0, n)
    y = _series(rng, n)
    if seed % 2:  # tiny first blocks, the peak late: the first judgement is too lax
        y[:200] *= 1e-12
        y[-5] = 1e3
    scale = 0.0 if seed < 3 else 0.5
    sizes = list(rng.integers(1, 90, 5))
    t = SignTracker(scale)
    for i, k in _blocks(n, sizes):
        t.feed(x[i:k], y[i:k])
    if not t.exact:  # the second pass, against the final peak
        t = SignTracker(t.final_scale)
        for i, k in _blocks(n, sizes):
            t.feed(x[i:k], y[i:k])
        assert t.exact
    period = 1.0 + x[1]
    want = [(x[i], x[k] if k > i else x[k] + period, y[i], y[k])
            for i, k in sign_brackets(x, y, periodic, scale)]
    got = [p[:4] for p in t.brackets(periodic, period)]
    assert got == want
    d = np.diff(np.concatenate([y, y[:1]]))  # the reversals' steps, the last one back
    r = SignTracker(0.0, keep=False)
    r.feed(None, d)
    s = np.sign(d[np.abs(d) > 1e-9 * np.max(np.abs(d))])
    assert r.reversals() == int(np.sum(s != np.roll(s, 1)))


@pytest.mark.parametrize("seed", range(5))
def test_extremes_are_argmin_and_argmax(seed):
    rng = np.random.default_rng(seed)
    n = 500
    y = np.round(rng.standard_normal(n), 1)  # ties: the first one counts
    y[rng.integers(0, n, 20)] = np.nan
    if seed == 0:  # the least sample first, the greatest last: the cyclic neighbours
        y[0], y[-1] = -9.0, 9.0
    e = Extremes()
    for i, k in _blocks(n, list(rng.integers(1, 70, 4))):
        e.feed(y[i:k])
    st = e.stats()
    for (i, v, prev, nxt), arg in ((st.low, np.nanargmin), (st.high, np.nanargmax)):
        assert i == int(arg(y)) and v == y[i]
        np.testing.assert_array_equal([prev, nxt], [y[(i - 1) % n], y[(i + 1) % n]])
    assert (st.first, st.last, st.second_last, st.n) == (y[0], y[-1], y[-2], n) or \
        np.isnan([st.first, st.last, st.second_last]).any()
    np.testing.assert_array_equal(array_stats(y).low, st.low)


@pytest.mark.parametrize("case, start", [
    ("seed-four-bar", None), ("quick-return", 0.0), ("offset-slider-crank", None),
    ("six-bar", 0.0), ("hibbeler-16-30", None), ("inverted-slider-crank", None),
    ("parallelogram-four-bar", 0.0), ("near-toggle-four-bar", None),
    (str(BUGS / "limited-sweep-zeroed-forces.toml"), None)])
@pytest.mark.parametrize("block", [7, 64])
def test_streamed_events_and_summary_are_the_whole_sweeps(case, start, block):
    """Events and summary gathered block by block equal the in-memory sweep's, which
    reads every array whole."""
    lk = Linkage(load_case(case))
    n = 500
    whole = lk.sweep(n, start=start)
    got = sweep_csv(lk, n, io.StringIO(), start=start, block=block)
    pd.testing.assert_frame_equal(got.events, whole.events)
    assert got.notes == whole.notes
    assert got.summary.lines() == whole.summary.lines()
    # rounding level, from a path that may differ (kernel blocks, numpy whole): both tiny
    pb = (got.summary.power_balance, whole.summary.power_balance)
    assert (pb[0] is None) == (pb[1] is None)
    if pb[0] is not None:
        assert max(pb) <= POWER_ROUND_OFF
    assert got.kinematics.n == n and got.frame is None


def test_streamed_newton_path_and_range_are_the_whole_sweeps():
    """The same on the numpy path (a Newton-path mechanism: no kernel) and over a
    ``--range`` that crosses the seam."""
    lk = Linkage(load_case(Path(__file__).parent / "data" / "stephenson-limited.toml"))
    whole = lk.sweep(300)
    got = sweep_csv(lk, 300, io.StringIO(), block=37)
    pd.testing.assert_frame_equal(got.events, whole.events)
    assert got.notes == whole.notes and got.summary.lines() == whole.summary.lines()
    lk = Linkage(load_case("seed-four-bar"))
    rng = (math.radians(-100.0), math.radians(250.0))
    whole = lk.sweep(400, input_range=rng)
    got = sweep_csv(lk, 400, io.StringIO(), block=29, input_range=rng)
    pd.testing.assert_frame_equal(got.events, whole.events)
    assert got.summary.lines() == whole.summary.lines()


@pytest.mark.slow
def test_streamed_sweep_memory_does_not_grow_with_points():
    """Peak traced memory of a streamed sweep at 8x the points stays within FLAT: the
    values, events and summary hold nothing per point (before issue 23's fix the
    values and several whole series were held, ~45-85 B a point)."""
    lk = Linkage(load_case("seed-four-bar"))
    sweep_csv(lk, 4096, io.StringIO(), block=2048)  # warm: kernel, imports, caches
    peaks = []
    for n in (12_000, 96_000):
        sink = _Null()
        tracemalloc.start()
        sweep_csv(lk, n, sink, block=2048)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
        assert sink.rows == n + 1
    assert peaks[1] <= (1 + FLAT) * peaks[0], peaks


class _Null(io.TextIOBase):
    """A text sink that counts lines and keeps nothing."""

    rows = 0

    def write(self, s):
        self.rows += s.count("\n")
        return len(s)
