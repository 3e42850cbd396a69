"""Events located on the solver (analytic/refine.py; issue 18, item 8): limit positions,
time ratios, swings and least transmission angles exact to the digits the sweep prints,
at the default 360 points, against closed forms written here (law of cosines for the
four-bars, the tangent to the crank circle for the quick-return)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from analytic import Linkage, load_case
from reports.cli.xval import main

from .conftest_helpers import four_bar

#: The events are located to 1e-12 rad (analytic.refine.INPUT_TOL = 5.7e-11 deg); the
#: closed forms below are exact to rounding (an acos near +-1 loses up to ~1e-8 of
#: its argument's relative 1e-16: 1e-8 rad only at a flat angle, none of these).  The
#: 6 printed decimals need 5e-7 deg; grid interpolation missed by 1e-3 deg.
EVENT_TOL_DEG = 1e-9
#: A ratio of two spans each good to EVENT_TOL_DEG over ~120 deg.
RATIO_TOL = 1e-10


def _events(res, kind, where):
    e = res.events
    return np.sort(e[(e.kind == kind) & (e["where"] == where)]["input"].to_numpy())


def _circ(a, b):
    """Distance of two angles (deg) on the circle."""
    d = np.mod(np.asarray(a) - np.asarray(b), 360.0)
    return np.minimum(d, 360.0 - d)


def test_crank_rocker_limits_swing_ratio_at_default_points():
    g, a, b, c = 0.4, 0.1, 0.3, 0.25   # Grashof crank-rocker, B above A-O4 (open)
    res = Linkage(four_bar(g, a, b, c, masses=None)).sweep(360, start=0.0)
    th2, th4 = [], []
    for r_ in (b + a, b - a):   # rocker limits: crank and coupler in line, |O2 B| = r_
        phi = math.acos((r_ ** 2 + g ** 2 - c ** 2) / (2 * r_ * g))
        B = r_ * np.array([math.cos(phi), math.sin(phi)])
        th4.append(math.degrees(math.atan2(B[1], B[0] - g)))
        th2.append(math.degrees(phi if r_ == b + a else phi + math.pi) % 360.0)
    got = _events(res, "limit", "rocker")
    assert len(got) == 2
    for want in th2:
        assert np.min(_circ(got, want)) < EVENT_TOL_DEG, (got, th2)
    (rk,) = [s for s in res.summary.strokes if s.kind == "rocker"]
    assert rk.low == pytest.approx(min(th4), abs=EVENT_TOL_DEG)
    assert rk.high == pytest.approx(max(th4), abs=EVENT_TOL_DEG)
    span = (th2[1] - th2[0]) % 360
    slow, quick = max(span, 360 - span), min(span, 360 - span)
    assert rk.slow_span == pytest.approx(slow, abs=2 * EVENT_TOL_DEG)
    assert rk.quick_span == pytest.approx(quick, abs=2 * EVENT_TOL_DEG)
    assert rk.time_ratio == pytest.approx(slow / quick, rel=RATIO_TOL)


def test_least_transmission_between_samples():
    """A grid that misses the flat positions (from 0.3 rad): the least transmission angle
    is located at theta2 = 180 deg (|A O4| = g + a), its value by the law of cosines."""
    g, a, b, c = 0.4, 0.1, 0.3, 0.25
    res = Linkage(four_bar(g, a, b, c, masses=None)).sweep(360, start=0.3)
    mu = {th: math.degrees(math.acos((b * b + c * c - D * D) / (2 * b * c)))
          for th, D in ((0.0, g - a), (180.0, g + a))}
    folded = {th: min(m, 180 - m) for th, m in mu.items()}
    at = min(folded, key=folded.get)
    (tr,) = res.summary.transmission
    assert _circ(tr.at, at) < EVENT_TOL_DEG
    assert tr.least_deg == pytest.approx(folded[at], abs=1e-9)
    (ev,) = _events(res, "min_transmission", "B")
    assert _circ(ev, at) < EVENT_TOL_DEG


def test_input_limits_of_a_non_grashof_crank():
    """A triple-rocker whose crank swings between +-theta_L: |A O4| = coupler + rocker."""
    g, a, b, c = 0.4, 0.3, 0.3, 0.25   # s + l = 0.65 > p + q = 0.6
    res = Linkage(four_bar(g, a, b, c, theta=0.0, masses=None)).sweep(360)
    lim = math.degrees(math.acos((a * a + g * g - (b + c) ** 2) / (2 * a * g)))
    np.testing.assert_allclose(_events(res, "limit", "O2"), [-lim, lim], atol=EVENT_TOL_DEG)


def test_quick_return_exact_two_to_one_at_default_points(capsys):
    """Crank r = 100 mm, pivots d = 200 mm apart: the rocker's limits are where O4A is
    tangent to the crank circle, sin(phi) = -r/d (phi = 210, 330 deg); the strokes span
    180 +- 2 asin(r/d) deg: 240 and 120, a time ratio of exactly 2."""
    r, d = 0.1, 0.2
    beta = math.degrees(math.asin(r / d))
    limits = sorted(((180 + beta) % 360, (360 - beta) % 360))
    res = Linkage(load_case("quick-return")).sweep(360, start=0.0)
    for where in ("ram", "block"):
        np.testing.assert_allclose(_events(res, "limit", where), limits, atol=EVENT_TOL_DEG)
    for s in res.summary.strokes:
        if s.name in ("ram", "rocker"):
            assert s.slow_span == pytest.approx(180 + 2 * beta, abs=2 * EVENT_TOL_DEG)
            assert s.time_ratio == pytest.approx((180 + 2 * beta) / (180 - 2 * beta),
                                                 rel=RATIO_TOL)
    assert main(["sweep", "quick-return"]) == 0
    out = capsys.readouterr().out
    ratios = re.findall(r"(ram|rocker): .*?time ratio (\d+\.\d+)", out.replace("\n    ", " "))
    assert sorted(ratios) == [("ram", "2.0000"), ("rocker", "2.0000")], out
    assert "rocker rocker" not in out


@pytest.mark.parametrize("case", ["seed-four-bar", "quick-return"])
def test_peak_effort_between_samples(case):
    """The peak drive torque at the default points is the peak of the curve, not of the
    samples: no configuration of a dense scan around it (1e-5 deg apart) exceeds it,
    and the densest sample is within the scan's own sampling error of it."""
    lk = Linkage(load_case(case))
    s = lk.sweep(360, start=0.0).summary
    at = math.radians(s.peak_effort_at)
    t = at + np.radians(np.linspace(-0.02, 0.02, 4001))
    d = lk.kinematics(t, on_singular="flag")
    dense = np.abs(lk.forces(d).effort)
    # rounding of the torque (~1e-15 relative) on the located side
    assert np.max(dense) <= s.peak_effort * (1 + 1e-12)
    # a sample 5e-6 deg from the peak misses it by curvature x h^2: < 1e-10 relative
    assert np.max(dense) == pytest.approx(s.peak_effort, rel=1e-10)
    assert abs(math.degrees(t[int(np.argmax(dense))]) - s.peak_effort_at) < 2e-5


def test_singular_positions_between_samples():
    """A parallelogram (ground = coupler, crank = rocker) is flat, its loop Jacobian
    singular, at theta2 = 0 and 180 deg: the determinant's sign changes are located
    there from a grid that misses both (the solver sets the dyad exactly onto its
    toggle within ~1e-6 rad of it: the middle of that band is the position)."""
    lk = Linkage(four_bar(0.4, 0.1, 0.4, 0.1, theta=math.radians(30), masses=None))
    res = lk.sweep(361, start=0.3)
    sing = _events(res, "singular", "loop Jacobian")
    assert len(sing) == 2
    assert np.all(np.minimum(_circ(sing, 0.0), _circ(sing, 180.0)) < EVENT_TOL_DEG), sing


def test_events_of_inputs_given_in_decreasing_order():
    """Explicit inputs from 359.5 down to 0.5 deg locate the same events (the brackets
    are ordered, whatever the order of the samples)."""
    lk = Linkage(load_case("seed-four-bar"))
    up = lk.sweep(360, start=0.0)
    down = lk.sweep(values=np.radians(np.arange(359.5, 0, -1.0)))
    for kind, where in (("limit", "rocker"), ("limit", "coupler"), ("min_transmission", "B")):
        np.testing.assert_allclose(_events(down, kind, where), _events(up, kind, where),
                                   atol=EVENT_TOL_DEG)
    assert down.summary.peak_effort_at == pytest.approx(up.summary.peak_effort_at, abs=1e-6)
