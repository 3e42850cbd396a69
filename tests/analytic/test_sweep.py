"""Sweeps: cycle coverage, events against closed forms, Grashof classification."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analytic import Linkage

from .conftest_helpers import four_bar, slider_crank


def test_slider_crank_dead_centres_closed_form():
    """Offset slider-crank (r, L, e): the dead centres are where crank and rod are
    collinear, theta = asin(e / (L + r)) and pi + asin(e / (L - r))."""
    r, L, e = 0.05, 0.2, 0.02
    lk = Linkage(slider_crank(r, L, offset=e, theta=0.1, omega=10.0, masses=None))
    res = lk.sweep(3600)
    ev = res.events[(res.events.kind == "limit") & (res.events["where"] == "slide")]
    got = sorted(np.mod(ev["input"].to_numpy(), 360))
    want = sorted(np.mod(np.degrees([math.asin(e / (L + r)), math.pi + math.asin(e / (L - r))]),
                         360))
    np.testing.assert_allclose(got, want, atol=1e-3)


def test_four_bar_rocker_limits_closed_form():
    """Crank-rocker limit positions: crank and coupler collinear, |O4 B| = rocker with
    |O2 B| = coupler +- crank (law of cosines for theta2)."""
    a, b, c, d = 0.1, 0.3, 0.25, 0.4
    lk = Linkage(four_bar(d, a, b, c, masses=None))
    res = lk.sweep(3600)
    ev = res.events[(res.events.kind == "limit") & (res.events["where"] == "rocker")]
    got = sorted(np.mod(ev["input"].to_numpy(), 360))
    want = []
    for r_ in (b + a, b - a):  # extended / folded: O2B = r_, along the crank (or opposite)
        phi = math.acos((r_ ** 2 + d ** 2 - c ** 2) / (2 * r_ * d))  # angle of O2B
        want.append(math.degrees(phi if r_ == b + a else phi + math.pi) % 360)
    np.testing.assert_allclose(got, sorted(want), atol=1e-3)


def test_grashof_classes():
    assert Linkage(four_bar(0.4, 0.1, 0.3, 0.25)).sweep(36).grashof == "Grashof crank-rocker"
    assert Linkage(four_bar(0.1, 0.3, 0.35, 0.3, masses=None)).sweep(36).grashof == \
        "Grashof double-crank"
    assert Linkage(four_bar(0.32, 0.25, 0.2, 0.15, theta=0.5, masses=None)).sweep(36).grashof \
        == "non-Grashof triple-rocker"
    para = Linkage(four_bar(0.4, 0.1, 0.4, 0.1, theta=0.5, masses=None))
    assert para.sweep(36).grashof == "change point"


def test_limited_range_sweep_reports_its_range():
    lk = Linkage(four_bar(0.32, 0.25, 0.2, 0.15, theta=math.radians(30), masses=None))
    res = lk.sweep(100)
    assert not res.full_cycle and res.notes and "feasible range" in res.notes[0]
    limit = math.degrees(math.acos((0.25 ** 2 + 0.32 ** 2 - 0.35 ** 2) / (2 * 0.25 * 0.32)))
    assert res.frame["input"].max() == pytest.approx(limit, abs=1e-3)


@pytest.mark.parametrize("theta_deg", [60.0, 300.0, 100.0, -60.0])
def test_range_across_the_seam_holds_the_reference(theta_deg):
    """A limited crank whose feasible range straddles the reference angle + 180 deg (the
    search span's seam): the range is reported on the turn that holds the reference,
    and the sweep runs over it.  Ground 0.4, crank 0.25, coupler 0.25, rocker 0.5: the
    loop closes where |O4 A| >= rocker - coupler, i.e. 0.2225 - 0.2 cos(theta) >= 0.0625,
    cos(theta) <= 0.8 (law of cosines): theta in [acos 0.8, 360 deg - acos 0.8].
    (Found by the random four-bars of test_fused: at 60 deg the range came back one
    turn below the reference and the sweep said the reference was not feasible.)"""
    lk = Linkage(four_bar(0.4, 0.25, 0.25, 0.5, theta=math.radians(theta_deg), masses=None))
    lim = math.degrees(math.acos(0.8))
    (lo, hi), = lk.feasible_ranges()
    v0 = lk.mech.driver.value
    assert lo <= v0 <= hi
    k = round((math.radians(180.0) - 0.5 * (lo + hi)) / (2 * math.pi))  # same turn as 180
    np.testing.assert_allclose(np.degrees([lo, hi]) + 360.0 * k, [lim, 360.0 - lim],
                               atol=1e-9)
    res = lk.sweep(50)
    assert not res.full_cycle
    span = np.ptp(res.frame["input"].to_numpy())
    assert span == pytest.approx(360.0 - 2 * lim, abs=1e-3)


def test_change_point_is_flagged_singular_without_noise():
    """The parallelogram passes flat configurations at 0 and 180 deg: singular events
    there.  Continued through them it stays a parallelogram, whose coupler translates
    (omega = 0 to round-off): its round-off must not make limit events (before the fix:
    about 100; the held dyad sign, which alternates with the anti-parallelogram, made
    as many)."""
    lk = Linkage(four_bar(0.4, 0.1, 0.4, 0.1, theta=math.radians(30), masses=None))
    res = lk.sweep(360)
    sing = np.mod(res.events[res.events.kind == "singular"]["input"].to_numpy(), 360)
    assert len(sing) >= 2
    assert np.all(np.minimum(np.abs(sing - 180), np.minimum(sing, 360 - sing)) < 1.5)
    coupler = (res.events.kind == "limit") & (res.events["where"] == "coupler")
    assert coupler.sum() <= 4


def test_nearest_event_wraps_a_full_cycle():
    """The crank-rocker's limit positions (law of cosines, as above); an input 2 deg past
    one of them, given one turn later, is 2 deg from it."""
    from analytic.sweep import nearest_event
    a, b, c, d = 0.1, 0.3, 0.25, 0.4
    lk = Linkage(four_bar(d, a, b, c, masses=None))
    res = lk.sweep(3600, start=0.0)
    phi = math.acos(((b + a) ** 2 + d ** 2 - c ** 2) / (2 * (b + a) * d))  # extended
    ev = nearest_event(res, math.degrees(phi) + 362.0, kinds=("limit",))
    assert ev.where == "rocker" and ev.distance == pytest.approx(2.0, abs=1e-3)
    assert nearest_event(res, 10.0, kinds=("singular",)) is None
