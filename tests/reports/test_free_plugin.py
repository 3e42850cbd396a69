"""The pytest plugin's free-motion check, ``xval.assert_free_agrees``: a passing MuJoCo
run of A01 returns its verdict; MuJoCo's semi-implicit Euler at 0.02 s (0.089 rad per
step at the fastest) fails with a message naming the horizon, the failing quantities
and the step."""

from __future__ import annotations

from pathlib import Path

import pytest

from reports.regression.pytest_plugin import Xval


@pytest.fixture(autouse=True)
def _headless(monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "disable")


def test_assert_free_agrees_passes_and_fails():
    x = Xval(Path.cwd(), 2.0)
    v = x.assert_free_agrees("iftomm-a01-pendulum", "mujoco", duration=0.5, samples=20)
    assert v.passed and v.engine == "mujoco"
    with pytest.raises(AssertionError) as e:
        x.assert_free_agrees("iftomm-a01-pendulum", "mujoco", duration=2.0, samples=100,
                             settings={"integrator": "Euler", "timestep": 0.02})
    msg = str(e.value)
    assert "trusted horizon" in msg and "FAIL" in msg and "--timestep" in msg
