"""Shared settings of the engine tests (all fast: the whole directory runs in seconds)."""

from __future__ import annotations

import pytest

from analytic import tolerances

#: Engine runs: accelerations, drive effort and pin forces relative to their peak (issue 3).
ENGINE_RELATIVE = getattr(tolerances, "ENGINE_RELATIVE", 1e-3)
#: MuJoCo mj_forward at the exact analytic state (issue 3).
MUJOCO_INSTANTANEOUS = getattr(tolerances, "MUJOCO_INSTANTANEOUS", 1e-4)


def assert_run_within(run_, tol, what=""):
    """Every quantity this project computes from the run within ``tol`` of its peak
    (against ``run_.linkage``, the compiled Linkage it was made from; the engines' own
    readings, flagged ``[engine]``, are reported separately)."""
    from reports.comparison.compare import compare_run
    comps = [c for c in compare_run(run_, tolerance=tol) if not c.quantity.endswith("[engine]")]
    assert comps, f"{what}: nothing compared"
    bad = [str(c) for c in comps if not c.passed]
    assert not bad, f"{what}: " + "; ".join(bad)
    return comps


def engine_reading(run_, quantity):
    """The comparison of one of the engine's own readings, e.g. ``O4.force[engine]``."""
    from reports.comparison.compare import compare_run
    return next(c for c in compare_run(run_) if c.quantity == quantity)


@pytest.fixture(autouse=True)
def _no_mujoco_log(tmp_path, monkeypatch):
    """MuJoCo's default warning handler writes MUJOCO_LOG.TXT into the working directory."""
    monkeypatch.chdir(tmp_path)
