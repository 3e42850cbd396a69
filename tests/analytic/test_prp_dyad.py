"""A PRP dyad (two sliders pinned together, each on its own guide): the closed form
against the hand solution, and the branch schedule of a plan holding one.

The mechanism (``data/prp-dyad.toml``): a crank of 0.1 m turns about O; block ``b1``
slides on the ground's horizontal line y = 0.3 m; block ``b2`` is pinned to ``b1`` at P
and guides the crank's tip L along its own line, at 90 deg to the crank.  The guide
fixes ``b2``'s angle to the crank's, so P = (s, 0.3) with L - P along (-sin, cos) of
the crank angle theta: s = L_x + (L_y - 0.3) tan theta.  At theta = 90 and 270 deg
the two guides are parallel and the linkage cannot be assembled.

A PRP dyad has a discriminant column (its guides' crossing) but no branch sign; the
branch schedule read the columns as the signs' indices, so a sweep raised IndexError
(a traceback for ``xval sweep``) before this file's last test was written.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from analytic import AssemblyError, Linkage, load_case

FILE = Path(__file__).parent / "data" / "prp-dyad.toml"
R, Y = 0.1, 0.3  # m: crank length, height of b1's guide
#: The hand formulas and the solver each take a few rounded operations; near the
#: parallel guides (10 deg away) 1/cos^3 amplifies rounding ~200x: 1e-13 of the peak.
TOL = 1e-13


def _s(theta):
    """Hand solution: b1's travel along its guide (m) at crank angle theta (rad), and
    its first and second derivatives in theta (m/rad, m/rad^2)."""
    c, sn = np.cos(theta), np.sin(theta)
    s = R * c + (R * sn - Y) * sn / c
    ds = (R * sn - Y) / c ** 2                      # the R sin terms cancel
    d2s = R / c + 2 * (R * sn - Y) * sn / c ** 3
    return s, ds, d2s


@pytest.fixture(scope="module")
def linkage():
    return Linkage(load_case(str(FILE)))


def test_positions_rates_and_accelerations_match_the_hand_solution(linkage):
    theta = np.radians([10.0, 30.0, 60.0, 100.0, 200.0, 260.0])
    w, a = 1.0, 0.5  # the description's driver rate and acceleration
    kin = linkage.kinematics(theta)
    p, v, acc = kin.point("b1", "P")
    sx, ds, d2s = _s(theta)
    for got, want in ((p[:, 0], sx), (v[:, 0], ds * w), (acc[:, 0], d2s * w ** 2 + ds * a)):
        np.testing.assert_allclose(got, want, rtol=0, atol=TOL * np.max(np.abs(want)))
    np.testing.assert_allclose(p[:, 1], Y, rtol=0, atol=TOL)
    b2 = linkage.body_index("b2")
    np.testing.assert_allclose(kin.theta[:, b2], theta, rtol=0, atol=TOL)


def test_a_full_turn_names_where_the_guides_are_parallel(linkage):
    """The crank cannot turn through 90 deg (parallel guides): a sweep over the turn is
    refused with the typed assembly error at that input, not an IndexError."""
    with pytest.raises(AssemblyError, match=r"at driver = (90|270) deg"):
        linkage.sweep(361)
