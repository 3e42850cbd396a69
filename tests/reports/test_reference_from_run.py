"""The compiled Linkage travels down and back up (issue 19): an engine run carries the
very :class:`analytic.Linkage` its :class:`sim_models.SimTree` was compiled with, and the
comparison, the studies' errors and the case figures take their reference from it,
never building another.

Independent check: ``Linkage.__init__`` is made to raise while a finished run is judged
(so any rebuild fails the test), and the comparisons must equal those against a Linkage
built separately from the same description before the patch.
"""

from __future__ import annotations

import dataclasses
import pickle

import numpy as np
import pytest

import analytic.kinematics
from analytic import Linkage, load_case

pytest.importorskip("mujoco")

#: The case: masses given (forces judged), a full-turn crank, a four-bar's single loop.
CASE = "seed-four-bar"


@pytest.fixture(scope="module")
def tree_and_run():
    from sim_models import compile_linkage
    from sim_models.runs.driven import run
    tree = compile_linkage(load_case(CASE))
    return tree, run(tree, "mujoco", samples=8)


def _forbid_rebuilding(monkeypatch):
    """From here on, building a Linkage raises (the comparison must not build one)."""
    def rebuilt(self, *a, **k):
        raise AssertionError("the comparison rebuilt the analytic Linkage")
    monkeypatch.setattr(analytic.kinematics.Linkage, "__init__", rebuilt)


def _numbers(comps) -> list[tuple]:
    return [(c.quantity, c.max_abs, c.peak, c.normalised, c.at) for c in comps]


def test_a_run_carries_the_linkage_of_its_compiled_tree(tree_and_run):
    tree, r = tree_and_run
    assert r.linkage is tree.linkage and r.mechanism is tree.mech is r.linkage.mech


def test_the_comparison_never_rebuilds_the_reference(tree_and_run, monkeypatch):
    """compare_run, reference_of, analytic_at and the studies' errors of a finished run
    read ``run.linkage``: with Linkage construction forbidden they give the numbers a
    separately built Linkage of the same description gives."""
    from reports.comparison.compare import analytic_at, compare_run
    from reports.comparison.reference import reference_of
    from reports.studies.speed_accuracy import run_errors, sample_errors
    _, r = tree_and_run
    separate = compare_run(r, linkage=Linkage(load_case(CASE)))  # before the patch
    _forbid_rebuilding(monkeypatch)
    with pytest.raises(AssertionError, match="rebuilt"):  # the patch does catch a rebuild
        Linkage(r.mechanism)
    comps = compare_run(r)
    assert comps and _numbers(comps) == _numbers(separate)
    ref = reference_of(r)
    lk, kin, _ = analytic_at(r)
    assert ref.linkage is r.linkage and lk is r.linkage
    np.testing.assert_array_equal(ref.kin.alpha, kin.alpha)
    assert np.isfinite(run_errors(r)["error"]) and sample_errors(r)


def test_a_pickled_run_is_judged_on_the_linkage_it_carries(tree_and_run, monkeypatch):
    """The report's pool workers send runs back pickled: the Linkage travels with the
    run (its mechanism the run's own object) and judges it without being rebuilt."""
    from reports.comparison.compare import compare_run
    _, r = tree_and_run
    expected = _numbers(compare_run(r))
    back = pickle.loads(pickle.dumps(r))
    _forbid_rebuilding(monkeypatch)
    assert back.linkage.mech is back.mechanism
    assert _numbers(compare_run(back)) == expected


def test_the_case_figures_read_the_runs_own_reference(tree_and_run, monkeypatch):
    """The report's case figures (the drawing, lines, markers, error panel) of a case
    with a run take the run's Linkage; none is built for them."""
    from reports.comparison.compare import compare_run
    from reports.figures.case_figures import render_case
    _, r = tree_and_run
    comps = compare_run(r)
    _forbid_rebuilding(monkeypatch)
    pngs = render_case(CASE, {"mujoco": r}, {"mujoco": comps}, r.mechanism, 1e-3)
    assert {"linkage", "error"} <= set(pngs) and len(pngs) > 4
    assert all(png.startswith(b"\x89PNG") for png in pngs.values())


def test_another_linkage_is_an_explicit_choice(tree_and_run):
    """Judging a run against another description is one typed argument: the same
    gravity-free run judged against the description with gravity keeps its
    accelerations (gravity does not change a prescribed motion's kinematics) and fails
    its forces (the weights are missing from the engine's)."""
    from reports.comparison.compare import compare_run
    _, r = tree_and_run
    heavy = Linkage(dataclasses.replace(r.mechanism, gravity=(0.0, -9.81)))
    own = {c.quantity: c for c in compare_run(r)}
    other = {c.quantity: c for c in compare_run(r, linkage=heavy)}
    alpha = [q for q in own if q.endswith(".alpha")]
    assert alpha and all(other[q].normalised == own[q].normalised for q in alpha)
    assert all(c.passed for c in own.values() if not c.quantity.endswith("[engine]"))
    assert not other["drive.effort"].passed
    with pytest.raises(TypeError):
        compare_run(r, heavy)  # no positional reference of any type any more
