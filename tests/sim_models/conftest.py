"""Shared settings of the engine tests (all fast: the whole directory runs in seconds)."""

from __future__ import annotations

import pytest

from analytic import tolerances

#: Engine runs: accelerations, drive effort and pin forces relative to their peak (issue 3).
ENGINE_RELATIVE = getattr(tolerances, "ENGINE_RELATIVE", 1e-3)
#: MuJoCo mj_forward at the exact analytic state (issue 3).
MUJOCO_INSTANTANEOUS = getattr(tolerances, "MUJOCO_INSTANTANEOUS", 1e-4)


def assert_within(errors: dict, keys, tol, what=""):
    bad = {k: errors[k] for k in keys if k in errors and not errors[k] <= tol}
    every = ", ".join(f"{k}={v:.2g}" for k, v in errors.items())
    assert not bad, f"{what}: errors above {tol:g} of peak: " + ", ".join(
        f"{k}={v:.3g}" for k, v in bad.items()) + f" (all: {every})"


@pytest.fixture(autouse=True)
def _no_mujoco_log(tmp_path, monkeypatch):
    """MuJoCo's default warning handler writes MUJOCO_LOG.TXT into the working directory."""
    monkeypatch.chdir(tmp_path)
