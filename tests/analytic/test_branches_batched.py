"""The branch schedule's batched evaluations (issue 34: A02's one-time setup) against
one evaluation at a time, and the change points against the N four-bar's geometry.

The closed form is elementwise in its input values, so evaluating many values (and
many branch-sign choices, one per value) at once must give what one value at a time
gives; the plan's first steps place their bodies from nothing later in the plan.
"""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from analytic import Linkage, load_case
from analytic.free_motion.iftomm import n_four_bar_toml
from analytic.toml_io import mechanism_from_dict

#: Batched against one at a time: the same arithmetic per value; rounding in a
#: vectorised library call may differ in the last bit (rad, m, relative discriminant).
SAME = 1e-14
#: The change points of the N four-bar are where its crank is horizontal (a window folds
#: flat); the refined minimum of a double root is located to ~1e-11 rad.
CHANGE_POINT = 1e-9


@pytest.fixture(scope="module")
def n8():
    return Linkage(mechanism_from_dict(tomllib.loads(n_four_bar_toml(8)), "A02"))


def test_refined_candidates_batched_as_one_at_a_time(n8):
    sch = n8.positions.schedule
    dx = 2 * math.pi / 3600
    cands = [(math.pi + 0.3 * dx * (k % 3 - 1), k) for k in range(8)]
    cands += [(2 * math.pi - 0.2 * dx, k) for k in range(8)]
    batched = sch._refined(cands, dx, sch.signs0)
    single = [r for c in cands for r in sch._refined([c], dx, sch.signs0)]
    assert [k for _, k in batched] == [k for _, k in single]
    np.testing.assert_allclose([x for x, _ in batched], [x for x, _ in single],
                               rtol=0, atol=SAME)


def test_change_points_where_the_crank_is_horizontal(n8):
    sch = n8.positions.schedule
    got = [c.value for c in sch.crossings(-7.0, 7.0)]
    want = [math.pi, 2 * math.pi, 0.0, -math.pi, -2 * math.pi]
    np.testing.assert_allclose(got, want, rtol=0, atol=CHANGE_POINT)
    assert all(c.switched and c.rule == "velocity" for c in sch.crossings(-7.0, 7.0))


@pytest.mark.parametrize("case", ["six-bar", "seed-slider-crank", "a02-n8"])
def test_closed_form_signs_per_value_and_part_of_the_plan(case, n8):
    from analytic.positions import ClosedForm
    lk = n8 if case == "a02-n8" else Linkage(load_case(case))
    cf = ClosedForm(lk.topo)
    K = cf.n_branch
    x = np.linspace(0.3, 1.3, 4)
    rng = np.random.default_rng(5)
    per = rng.choice([-1.0, 1.0], size=(K, len(x)))
    th, E, O, disc, _ = cf.run(x, per)
    for i in range(len(x)):
        th1, E1, O1, d1, _ = cf.run(x[i:i + 1], [int(s) for s in per[:, i]])
        np.testing.assert_allclose(th[i], th1[0], rtol=0, atol=SAME, equal_nan=True)
        np.testing.assert_allclose(O[i], O1[0], rtol=0, atol=SAME, equal_nan=True)
        np.testing.assert_allclose(disc[i], d1[0], rtol=0, atol=SAME, equal_nan=True)
    # the plan's first steps: the bodies they place as the whole plan places them
    for steps in range(1, len(cf.plan) + 1):
        th2, _, O2, d2, _ = cf.run(x, per, steps)
        placed = sorted({b for st in cf.plan[:steps] for b in st.bodies})
        np.testing.assert_allclose(th2[:, placed], th[:, placed], rtol=0, atol=SAME,
                                   equal_nan=True)
        np.testing.assert_allclose(O2[:, placed], O[:, placed], rtol=0, atol=SAME,
                                   equal_nan=True)
        np.testing.assert_allclose(d2, disc[:, :d2.shape[1]], rtol=0, atol=SAME,
                                   equal_nan=True)


@pytest.mark.parametrize("case", ["seed-four-bar", "six-bar", "seed-slider-crank", "a02-n8"])
def test_loop_determinant_from_positions_alone(case, n8, monkeypatch):
    """:meth:`Linkage.loop_determinant` (no rates, no condition number) is the numpy
    path's ``Kinematics.determinant``, near singular positions too (the N four-bar's
    change points at a horizontal crank)."""
    monkeypatch.setenv("XVAL_FUSED", "0")
    lk = n8 if case == "a02-n8" else Linkage(load_case(case))
    v0 = lk.mech.driver.value
    x = v0 + np.linspace(-0.5, 0.5, 9) if case == "seed-slider-crank" else \
        np.concatenate([np.linspace(0.05, 6.2, 13), [math.pi + 1e-9, math.pi - 1e-6]])
    want = lk.kinematics(x, 1.0, 0.0, on_singular="flag").determinant
    np.testing.assert_allclose(lk.loop_determinant(x), want, rtol=SAME, atol=SAME)
