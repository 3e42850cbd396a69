"""Position analysis: branch choice, continuation, feasibility, and failures to close."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analytic import AssemblyError, Linkage, load_case
from analytic.positions import feasible_ranges

from .conftest_helpers import four_bar


def test_branch_follows_hint():
    """Open and crossed assembly of the S4 four-bar differ in theta4 (110.75 vs the
    mirror image of B about the line A-O4)."""
    open_ = Linkage(four_bar(0.4, 0.1, 0.3, 0.25)).kinematics()
    crossed = Linkage(four_bar(0.4, 0.1, 0.3, 0.25, open_branch=False)).kinematics()
    A = np.array([0.1 * math.cos(math.radians(60)), 0.1 * math.sin(math.radians(60))])
    O4 = np.array([0.4, 0.0])
    for kin, side in ((open_, 1), (crossed, -1)):
        B = kin.origin[0, 3] + 0.25 * np.array([math.cos(kin.theta[0, 3]),
                                                 math.sin(kin.theta[0, 3])])
        d, e = O4 - A, B - A
        assert np.sign(d[0] * e[1] - d[1] * e[0]) == side


def test_continuation_never_jumps_branch():
    """Over 3600 steps of a crank-rocker the angles change by less than the step times
    the peak speed ratio: no jump to the other assembly mode."""
    lk = Linkage(load_case("seed-four-bar"))
    x = np.radians(60) + np.linspace(0, 2 * np.pi, 3601)
    kin = lk.kinematics(x)
    dth = np.abs(np.diff(kin.theta, axis=0))
    ratio = np.max(np.abs(kin.omega / kin.velocity[:, None]))
    assert dth.max() <= ratio * (x[1] - x[0]) * 1.01


def test_non_grashof_infeasible_angle_names_range():
    """A triple-rocker (s + l > p + q) cannot reach theta2 = 180 deg; the error gives
    the feasible range, which the law of cosines gives independently: B at the limit is
    where A, B, O4 are collinear with |AO4| = coupler + rocker."""
    g, a, b, c = 0.32, 0.25, 0.2, 0.15  # s + l = 0.47 > p + q = 0.45: non-Grashof
    mech = four_bar(g, a, b, c, theta=math.radians(30), masses=None)
    lk = Linkage(mech)
    with pytest.raises(AssemblyError, match=r"cannot close at driver 'O2' = 180 deg; "
                                            r"feasible input range") as e:
        lk.kinematics(math.radians(180))
    # |A O4|^2 = a^2 + g^2 - 2 a g cos t = (b + c)^2 at the limit
    limit = math.acos((a * a + g * g - (b + c) ** 2) / (2 * a * g))
    (lo, hi), = e.value.feasible
    assert hi == pytest.approx(limit, abs=1e-9)
    assert lo == pytest.approx(-limit, abs=1e-9)


def test_slider_input_out_of_range():
    lk = Linkage(load_case("hibbeler-16-30"))
    with pytest.raises(AssemblyError, match=r"'guide' = 0.6 m.*\[-0.43947\d* m, 0.43947\d* m\]"):
        lk.kinematics(0.6)
    (lo, hi), = feasible_ranges(lk.topo)
    # the collar's reach: |A C|max = AB + CB = 0.2 + 0.2 sqrt2, C on x = -0.2
    reach = math.sqrt((0.2 + 0.2 * math.sqrt(2)) ** 2 - 0.2 ** 2)
    assert hi == pytest.approx(reach, abs=1e-9) and lo == pytest.approx(-reach, abs=1e-9)


def test_newton_fallback_matches_closed_form():
    """With user-given loops and no closed-form plan, Newton continuation from angle
    hints reproduces the dyad solution of the six-bar."""
    from dataclasses import replace

    from analytic import Assembly
    mech = load_case("six-bar")
    lk = Linkage(mech)
    x = np.radians(60) + np.linspace(0, 2 * np.pi, 37)[:-1]
    ref = lk.kinematics(x)
    hints = {b: float(ref.theta[0, lk.body_index(b)]) + 0.2
             for b in ("coupler", "rocker", "link", "output")}
    newton_mech = replace(mech, assembly=Assembly({}, hints))
    nl = Linkage(newton_mech)
    nl.topo.plan = None  # force the general path
    from analytic.position_solver import PositionSolver
    nl.positions = PositionSolver(nl.topo, nl.eqs)
    kin = nl.kinematics(x)
    np.testing.assert_allclose(kin.theta, ref.theta, atol=1e-10)
    np.testing.assert_allclose(kin.alpha, ref.alpha, rtol=1e-9, atol=1e-9)


def test_user_given_loops_match_derived_ones():
    """The six-bar with its two loops written out by the user (as joint cycles) gives the
    same kinematics and forces as with the loops derived from the joint graph."""
    from dataclasses import replace
    mech = load_case("six-bar")
    user = replace(mech, loops=(("O2", "A", "B", "O4"), ("O4", "D", "E", "O6")))
    x = np.radians(60) + np.linspace(0, 2 * np.pi, 24, endpoint=False)
    k1, k2 = Linkage(mech).kinematics(x), Linkage(user).kinematics(x)
    np.testing.assert_allclose(k2.alpha, k1.alpha, rtol=1e-12, atol=1e-12)
    f1, f2 = Linkage(mech).forces(k1), Linkage(user).forces(k2)
    np.testing.assert_allclose(f2.effort, f1.effort, rtol=1e-12, atol=1e-14)


def test_bad_user_loops_are_typed_errors():
    from dataclasses import replace

    from analytic import DescriptionError
    mech = load_case("six-bar")
    with pytest.raises(DescriptionError, match="1 loops given but the joint graph has 2"):
        Linkage(replace(mech, loops=(("O2", "A", "B", "O4"),)))
    with pytest.raises(DescriptionError, match="'A' and 'D' do not share exactly one body"):
        Linkage(replace(mech, loops=(("O2", "A", "D", "O4"), ("O4", "D", "E", "O6"))))
