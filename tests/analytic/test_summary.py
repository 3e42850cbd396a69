"""The sweep's engineering summary against closed forms: stroke and time ratio of an
offset slider-crank, swing and time ratio of a crank-rocker, its transmission angle
(law of cosines at the flat positions), and the near-limit sweep's events."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from analytic import Linkage
from reports.cli.xval import main

from .conftest_helpers import four_bar, slider_crank

#: The summary interpolates the extremes between samples (parabola through three), so at
#: 3600 points the input spans are good to ~1e-4 deg and the travel to ~1e-9 relative.
SPAN_TOL_DEG = 1e-3


def test_offset_slider_crank_stroke_and_time_ratio():
    r, L, e = 0.05, 0.2, 0.02
    lk = Linkage(slider_crank(r, L, offset=e, theta=0.1, omega=10.0, masses=None))
    s = lk.sweep(3600, start=0.0).summary
    (st,) = [x for x in s.strokes if x.kind == "slider"]
    assert st.travel == pytest.approx(math.sqrt((L + r) ** 2 - e ** 2)
                                      - math.sqrt((L - r) ** 2 - e ** 2), rel=1e-9)
    a_out = math.degrees(math.asin(e / (L + r)))           # outer dead centre
    a_in = 180 + math.degrees(math.asin(e / (L - r)))      # inner dead centre
    spans = sorted([a_in - a_out, 360 - (a_in - a_out)])
    assert st.slow_span == pytest.approx(spans[1], abs=SPAN_TOL_DEG)
    assert st.quick_span == pytest.approx(spans[0], abs=SPAN_TOL_DEG)
    assert st.time_ratio == pytest.approx(spans[1] / spans[0], rel=1e-5)


def test_crank_rocker_swing_time_ratio_and_transmission():
    g, a, b, c = 0.4, 0.1, 0.3, 0.25   # the notes' S4 four-bar
    lk = Linkage(four_bar(g, a, b, c, masses=None))
    s = lk.sweep(3600, start=0.0).summary
    (rk,) = [x for x in s.strokes if x.kind == "rocker"]
    th2, th4 = [], []
    for r_ in (b + a, b - a):   # extended and folded: |O2 B| = r_
        phi = math.acos((r_ ** 2 + g ** 2 - c ** 2) / (2 * r_ * g))
        B = r_ * np.array([math.cos(phi), math.sin(phi)])
        th4.append(math.degrees(math.atan2(B[1], B[0] - g)))
        th2.append(math.degrees(phi if r_ == b + a else phi + math.pi))
    assert rk.travel == pytest.approx(abs(th4[0] - th4[1]), abs=1e-6)
    span = (th2[1] - th2[0]) % 360
    assert rk.time_ratio == pytest.approx(max(span, 360 - span) / min(span, 360 - span),
                                          rel=1e-5)
    # transmission angle mu at B: cos mu = (b^2 + c^2 - |A O4|^2) / (2 b c), extreme
    # at theta2 = 0 (|A O4| = g - a) and 180 deg (g + a); folded into 0..90 deg
    mus = [math.degrees(math.acos((b * b + c * c - D * D) / (2 * b * c))) for D in (g - a, g + a)]
    least = min(min(m, 180 - m) for m in mus)
    (tr,) = s.transmission
    assert tr.least_deg == pytest.approx(least, abs=1e-9)
    assert tr.largest_deviation_deg == pytest.approx(90 - least, abs=1e-9)
    assert tr.at == pytest.approx(180.0)


def test_sweep_cli_summary_and_options(capsys, tmp_path):
    csv = tmp_path / "t.csv"
    assert main(["sweep", "seed-four-bar", "--csv", str(csv)]) == 0
    out = capsys.readouterr().out
    flat = " ".join(out.split())  # the summary wraps to the terminal (80 columns in xdist)
    df = pd.read_csv(csv)
    assert df["input [deg]"].iloc[0] == 0.0 and df["input [deg]"].iloc[-1] == 359.0
    assert "input 0 to 359 deg (one full turn); reference value 60 deg" in flat
    assert "least 49.458 deg" in flat and "largest deviation from 90 deg 40.542 deg" in flat
    assert "swing" in out and "time ratio" in out
    ev = [float(v) for v in __import__("re").findall(r"limit\s+\w+\s+(\d+\.\d+)", out)]
    assert ev and all(0 <= v < 360 for v in ev)
    assert main(["sweep", "seed-four-bar", "--omega", "-3", "--range", "10", "50",
                 "--points", "5", "--csv", str(csv)]) == 0
    capsys.readouterr()
    df = pd.read_csv(csv)
    np.testing.assert_allclose(df["input [deg]"], [10, 20, 30, 40, 50])
    assert (df["input_velocity [rad/s]"] == -3.0).all()
    assert main(["sweep", "seed-four-bar", "--range", "50", "10"]) == 2
    assert "--range" in capsys.readouterr().err


def test_near_limit_crank_rocker_shows_its_limits():
    """A crank-rocker whose coupler is too short for a full turn: the sweep's ends are
    the input's limit positions (law of cosines: |A O4| = coupler + rocker), listed as
    events, and the huge drive effort at the ends is reported beside them."""
    g, a, b, c = 0.4, 0.1, 0.24, 0.25
    lk = Linkage(four_bar(g, a, b, c))
    res = lk.sweep(360)
    limit = math.degrees(math.acos((a * a + g * g - (b + c) ** 2) / (2 * a * g)))
    ends = res.events[(res.events.kind == "limit") & (res.events["where"] == "O2")]["input"]
    np.testing.assert_allclose(sorted(ends), [-limit, limit], atol=1e-7)
    ev = res.summary.peak_event
    assert ev is not None and ev.kind == "limit" and ev.distance < 1e-3
    assert any("from the input limit position (O2)" in line for line in res.summary.lines())
