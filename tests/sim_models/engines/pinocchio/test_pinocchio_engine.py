"""The Pinocchio engine (issue 24): prescribed runs against the analytic solution, the
treatment of the redundant z rows of its 3D loop constraints, and the registry's handling
of an engine whose optional library is missing.

Independent expectations: the analytic solver (:mod:`analytic`) for accelerations, joint
reactions and drive effort; the rank of a planar loop's constraint rows from the joint
count (two in-plane rows per loop); nothing is pasted back from the engine.
"""

from __future__ import annotations

import numpy as np
import pytest

from analytic import load_case
from analytic.sweep import input_values
from sim_models import compile_linkage
from sim_models.engines.registry import (
    _REGISTRY,
    EngineUnavailableError,
    available_engines,
    get_engine,
    register_engine,
    skipped_engines,
)
from sim_models.runs.driven import instantaneous, run

from ...conftest import assert_run_within

#: At the exact analytic state the dynamics is one factorisation and proximal iterations
#: to 1e-12 (``prox_accuracy``): round-off of a 3-6 joint model, measured 1e-15..6e-12 of
#: peak over the built-in cases; 1e-9 leaves 100x for other CPUs/BLAS.
PINOCCHIO_EXACT = 1e-9
#: A prescribed run at the recommended settings (RK4, 180 steps a revolution): RK4's
#: global error is of order (omega h)^4 = (2 pi / 180)^4 = 1.5e-6 of the motion, times
#: the case's constants; measured 2.3e-7 (seed four-bar) and 2.1e-7 (seed slider-crank)
#: of peak.  1e-5 leaves 40x, and a first-order scheme (semi-implicit Euler: 2e-3 of
#: peak at 1440 steps a revolution) fails it.
PINOCCHIO_RUN = 1e-5
#: The z multiplier of a planar loop's 3D point constraint: its Jacobian row is exactly
#: zero, so the proximal iterations never move it from its start (0).
LAMBDA_Z = 0.0


@pytest.fixture
def pin():
    return pytest.importorskip(
        "pinocchio", reason="the pinocchio engine needs pin: pip install 'linkage-xval[pinocchio]'")


@pytest.mark.parametrize("case", ["seed-four-bar", "seed-slider-crank", "six-bar",
                                  "quick-return"])
def test_exact_state_matches_analytic(pin, case):
    """Accelerations, every joint reaction and the drive effort at the analytic state
    (the instantaneous mode).  Fails when the joints are not added depth first (crba
    then drops the crank-coupler coupling: drive torque -0.41 N m for 0.67 N m)."""
    tree = compile_linkage(load_case(case))
    r = instantaneous(tree, "pinocchio", None, input_values(tree.linkage, 12)[0])
    assert r.ok, r.reason
    assert_run_within(r, PINOCCHIO_EXACT, case)


@pytest.mark.parametrize("case", ["seed-four-bar", "seed-slider-crank"])
def test_prescribed_run_matches_analytic(pin, case):
    """A prescribed run (RK4, Baumgarte) against the analytic accelerations, joint
    reactions and drive effort."""
    tree = compile_linkage(load_case(case))
    r = run(tree, "pinocchio", revolutions=2, samples=12)
    assert r.ok, r.reason
    assert_run_within(r, PINOCCHIO_RUN, case)
    assert r.extra["max_lambda_z"] == LAMBDA_Z


def _state(tree, value):
    """The analytic tree state ``q, v`` at input ``value`` and the analytic forces."""
    kin = tree.linkage.kinematics(np.array([value]))
    q, qd, _ = tree.coords(kin)
    return q[0], qd[0], tree.linkage.forces(kin)


def test_redundant_z_rows_carry_nothing(pin):
    """The six-bar's two loops as 3D point constraints: 6 rows, rank 4 (the z rows are
    exactly zero, the Delassus matrix singular); the proximal solver leaves the z
    multipliers at 0 and the in-plane ones equal the analytic reactions, whatever the
    proximal weight: only x, y are read (and judged), and they do not depend on how the
    redundant direction is regularised."""
    from sim_models.engines.pinocchio.driven import PinocchioSession, PinocchioSettings
    tree = compile_linkage(load_case("six-bar"))
    value = float(input_values(tree.linkage, 12)[0][5])
    q, qd, frc = _state(tree, value)
    acc = float(tree.mech.driver.acceleration)
    assert len(tree.chords) == 2
    for mu in (1e-8, 1e-2):
        s = PinocchioSession(tree, PinocchioSettings(prox_mu=mu, prox_max_iter=200))
        s.set_baumgarte(0.0)
        Q, V = np.zeros(s.model.nq), np.zeros(s.nv)
        Q[s.vidx], V[s.vidx] = q, qd
        a, lam, _ = s.dynamics(Q, V, acc)
        J = pin.getConstraintsJacobian(s.model, s.data, s.cmodels, s.cdatas)
        assert J.shape[0] == 3 * len(tree.chords)
        assert np.all(J[2::3] == 0.0)                       # the z rows, exactly
        assert np.linalg.matrix_rank(J) == 2 * len(tree.chords)
        M = pin.crba(s.model, s.data, Q)
        M = np.triu(M) + np.triu(M, 1).T
        D = J @ np.linalg.solve(M, J.T)
        assert np.linalg.matrix_rank(D) == 2 * len(tree.chords)  # singular: 4 of 6
        L = lam.reshape(-1, 3)
        assert np.all(L[:, 2] == LAMBDA_Z)
        for c, ch in enumerate(tree.chords):
            want = frc.joint_force[ch.name][0]
            got = s.chord_sign[c] * L[c, :2]
            peak = max(np.abs(want).max(), 1e-12)
            assert np.abs(got - want).max() < PINOCCHIO_EXACT * peak, (mu, ch.name)


def test_missing_optional_library_is_skipped_and_explained(capsys):
    """An engine whose optional library is missing: left out of ``--engine all`` and the
    report with one line, and asked for by name (``xval compare CASE --engine NAME``) it
    says how to install it, status 2 (an ImportError as well, for library callers).  The
    pinocchio entry is pointed at a library that does not exist (the command line's
    ``--engine`` choices are built once per process, from the registered names)."""
    from reports.cli.compare import note_skipped_engines
    from reports.cli.xval import main
    keep = _REGISTRY["pinocchio"]
    register_engine("pinocchio", keep.module, keep.session, keep.description,
                    "no_such_library_xval", "pip install 'linkage-xval[nolib]'")
    try:
        assert "pinocchio" not in available_engines()
        why = skipped_engines()["pinocchio"]
        assert "no_such_library_xval" in why and "pip install" in why and "\n" not in why
        with pytest.raises(EngineUnavailableError, match=r"pip install 'linkage-xval\[nolib\]'"):
            get_engine("pinocchio")
        with pytest.raises(ImportError):
            get_engine("pinocchio")
        note_skipped_engines()
        err = capsys.readouterr().err.splitlines()
        assert [ln for ln in err if "pinocchio" in ln] == [f"xval: note: {why}; skipped"]
        assert main(["compare", "seed-four-bar", "--engine", "pinocchio"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert err == [f"xval: error: {why}"]
    finally:
        _REGISTRY["pinocchio"] = keep
