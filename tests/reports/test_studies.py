"""The speed/accuracy studies (reports.studies): quick grids, the cheapest-setting logic,
change-point branch detection, the long-run loop and the scene economy.  Fast (~20 s)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from analytic import Linkage
from reports.studies import hard_cases as hard_cases_module
from reports.studies import speed_accuracy as S
from reports.studies.hard_cases import hard_cases
from reports.studies.scene import SCENE_VARIANTS, scene_economy

pytest.importorskip("mujoco")
pytest.importorskip("pybullet")

PNG = b"\x89PNG"
#: The same quotient computed twice (the curve's sample and the verdict's maximum):
#: round-off only.
SAME_QUOTIENT = 1e-12
BRANCHES = {"parallelogram", "anti-parallelogram", "diverged"}


@pytest.fixture(autouse=True)
def _no_mujoco_log(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


@pytest.fixture(scope="module")
def grid():
    return S.speed_error_grid("seed-four-bar", quick=True)


def test_quick_grid_rows_are_finite(grid):
    assert list(grid.columns[:len(S.GRID_COLUMNS)]) == S.GRID_COLUMNS
    from sim_models.engines.registry import available_engines
    assert set(grid["engine"]) == set(available_engines())  # every installed engine's family
    assert len(grid) == len(S.grid_plan("seed-four-bar", True))
    ok = grid[grid["ok"]]
    assert len(ok) >= 0.6 * len(grid)
    for col in ("timestep", "steps_per_rev", "steps_per_second", "seconds_per_rev",
                "accel_error", "force_error", "error"):
        assert np.isfinite(ok[col].astype(float)).all(), col
    assert (ok["seconds_per_rev"] > 0).all() and (ok["steps_per_second"] > 0).all()
    assert np.allclose(ok["error"], np.maximum(ok["accel_error"], ok["force_error"]))
    # the steps per second and the time per revolution describe the same loop
    assert np.allclose(ok["seconds_per_rev"] * ok["steps_per_second"], ok["steps_per_rev"])
    # the project's default-like settings reach 1e-4 in every engine
    for eng in ("mujoco", "pybullet", "exudyn"):
        assert ok[ok["engine"] == eng]["error"].min() < 1e-4, eng
    # failed runs are rows with a reason, never exceptions
    bad = grid[~grid["ok"]]
    assert (bad["reason"].str.len() > 0).all()
    assert np.isinf(bad["error"].astype(float)).all()


def test_cheapest_settings_from_the_grid(grid):
    table = S.cheapest_settings(grid)
    assert len(table) == grid["engine"].nunique() * len(S.TOLERANCES)
    for r in table.itertuples():
        if r.label != "none":
            assert r.error <= r.tolerance
            rows = grid[(grid["engine"] == r.engine) & grid["ok"]
                        & (grid["error"] <= r.tolerance)]
            assert r.seconds_per_rev == pytest.approx(rows["seconds_per_rev"].min())


def test_cheapest_settings_synthetic():
    g = pd.DataFrame([
        # engine, label, seconds, error, ok
        ("a", "fast-bad", 0.001, 5e-3, True),
        ("a", "mid", 0.01, 5e-4, True),
        ("a", "slow-good", 0.1, 5e-5, True),
        ("a", "cheap-but-failed", 0.0001, 1e-6, False),
        ("a", "cheap-but-inf", 0.0002, math.inf, True),
        ("b", "only", 0.05, 2e-3, True),
    ], columns=["engine", "label", "seconds_per_rev", "error", "ok"])
    t = S.cheapest_settings(g).set_index(["engine", "tolerance"])
    assert t.loc[("a", 1e-2), "label"] == "fast-bad"
    assert t.loc[("a", 1e-3), "label"] == "mid"
    assert t.loc[("a", 1e-4), "label"] == "slow-good"
    assert t.loc[("b", 1e-2), "label"] == "only"
    assert t.loc[("b", 1e-3), "label"] == "none"
    assert t.loc[("b", 1e-4), "label"] == "none"
    assert math.isnan(t.loc[("b", 1e-4), "seconds_per_rev"])


@pytest.mark.parametrize("case, engine", [("seed-four-bar", "pybullet"),
                                          ("seed-slider-crank", "mujoco")])
def test_sample_error_curves_peak_at_the_rows_errors(case, engine):
    """The hard-case figures' per-sample curves are the verdict's errors sample by sample:
    their largest values are the row's accel_error and force_error (one normalisation,
    each quantity by its own verdict peak), to round-off."""
    r = S.grid_task(case, engine, {}, "default", 2, 36, timing_steps=50, timing_repeats=1,
                    keep_samples=True)
    assert r["ok"], r["reason"]
    smp = r["samples"]
    assert len(smp["alpha"]) == len(smp["input_deg"]) == 36
    assert np.nanmax(smp["alpha"]) == pytest.approx(r["accel_error"], rel=SAME_QUOTIENT)
    assert np.nanmax(smp["force"]) == pytest.approx(r["force_error"], rel=SAME_QUOTIENT)


def test_divergence_and_bad_settings_are_rows():
    r = S.grid_task("seed-four-bar", "pybullet", {"timestep": 1e-2}, "coarse",
                    timing_steps=50, timing_repeats=1)
    assert r["ok"] is False and "loop violation" in r["reason"]
    assert math.isinf(r["error"])
    r = S.grid_task("seed-four-bar", "mujoco", {"integrator": "leapfrog"}, "bogus")
    assert r["ok"] is False and "leapfrog" in r["reason"]
    r = S.grid_task("no-such-case", "mujoco", {}, "x")
    assert r["ok"] is False and r["reason"]


def test_hard_case_files():
    nt = Linkage(S.load("near-toggle-four-bar"))
    res = nt.sweep(3600, forces=False)
    assert res.grashof == "Grashof crank-rocker" and res.full_cycle
    tr = next(iter(nt.kinematics(np.radians([180.0])).transmission.values()))
    assert tr[0] == pytest.approx(174.773, abs=1e-3)
    pg = Linkage(S.load("parallelogram-four-bar"))
    assert pg.sweep(360, forces=False).grashof == "change point"
    assert S.singular_inputs(pg) == pytest.approx([0.0, 180.0], abs=1e-6)


def test_branch_classification_synthetic():
    mech = S.load("parallelogram-four-bar")
    x = np.radians(30.0 + np.arange(0, 361, 5.0))
    modes = S.assembly_modes(mech, x)
    # the parallelogram's rocker is parallel to the crank
    assert np.allclose(S._wrap(modes["parallelogram"] - x), 0.0, atol=1e-9)
    segs = S.classify_branch(x, modes["parallelogram"], modes, [0.0, 180.0])
    assert [s["branch"] for s in segs] == ["parallelogram"] * 3
    flip = np.where(np.degrees(x) > 180, modes["anti-parallelogram"], modes["parallelogram"])
    segs = S.classify_branch(x, flip, modes, [0.0, 180.0])
    assert [s["branch"] for s in segs] == ["parallelogram", "anti-parallelogram",
                                           "anti-parallelogram"]
    off = modes["parallelogram"] + np.radians(20.0)
    assert {s["branch"] for s in S.classify_branch(x, off, modes, [0.0, 180.0])} == \
        {"diverged"}
    # the analytic reference continues the branch the physical linkage (and the engines)
    # follow through the change point (issue 8)
    if not hasattr(Linkage, "branch_crossings"):
        pytest.skip("this solver holds its dyad signs through change points")
    an = S.analytic_branch("parallelogram-four-bar")
    assert an["branch_after_singular"] == "parallelogram"
    assert an["flips"] == 0


@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])
def test_change_point_engine_label(engine):
    sd = {"timestep": 1e-3} if engine == "mujoco" else {"timestep": 3e-4}
    r = S.change_point_task("parallelogram-four-bar", engine, sd, revolutions=1)
    assert r["branch_after_singular"] in BRANCHES
    assert r["ok"], r["reason"]
    assert r["branch_after_singular"] == "parallelogram"
    # a run that cannot even start is labelled, not raised
    r = S.change_point_task("parallelogram-four-bar", engine, {"bogus": 1.0}, 1)
    assert r["branch_after_singular"] == "diverged" and not r["ok"]


def test_long_run_loop_short():
    from dataclasses import asdict

    from sim_models.builders.mjcf import MujocoSettings
    res = hard_cases_module.long_run_task("seed-four-bar", "mujoco", asdict(MujocoSettings()), 3)
    per = pd.DataFrame(res["per_rev"])
    assert list(per["revolution"]) == [1, 2, 3]
    assert res["summary"]["ok"] and res["summary"]["revolutions_done"] == 3
    assert (per["loop_violation"] < 1e-6).all()
    assert (per["speed_deviation"] < 1e-6).all()
    assert (per["alpha_error"] < 1e-4).all() and (per["effort_error"] < 1e-4).all()
    assert (per["energy_balance"].abs() < 1e-4).all()
    res = hard_cases_module.long_run_task("seed-four-bar", "pybullet", {"timestep": 1e-4}, 2)
    assert res["summary"]["ok"] and len(res["per_rev"]["revolution"]) == 2


@pytest.mark.slow
def test_hard_cases_quick():
    h = hard_cases(quick=True)
    assert h["long_run_revolutions"] == S.LONG_RUN_REVOLUTIONS[True]
    assert f"{h['long_run_revolutions']} revolutions" in h["notes"]
    for k in ("high_speed_plot", "near_toggle_plot", "change_point_plot", "long_run_plot",
              "long_run_timeseries"):
        assert h[k].startswith(PNG), k
    hs = h["high_speed"]
    assert (hs["omega2"] == 200.0).all() and hs["ok"].all()
    assert set(hs["engine"]) == {"mujoco", "pybullet"}
    nt = h["near_toggle"]
    assert nt["transmission_extreme_deg"].max() == pytest.approx(174.773, abs=1e-3)
    assert nt["ok"].all()
    assert set(h["change_point"]["branch_after_singular"]) <= BRANCHES
    lr = h["long_run"]
    assert set(lr["engine"]) == {"mujoco", "pybullet"}
    assert lr.groupby("engine")["revolution"].max().min() == h["long_run_revolutions"]
    assert h["long_run_summary"]["ok"].all()


def test_no_nested_pool_inside_a_worker():
    from concurrent.futures import ProcessPoolExecutor
    with ProcessPoolExecutor(1) as ex:
        assert ex.submit(_executor_kind).result() == "_SerialExecutor"
    assert _executor_kind() == "ProcessPoolExecutor"


def _executor_kind():
    with S.executor(None, workers=1) as ex:
        return type(ex).__name__


def test_scene_economy_rows():
    df = scene_economy(quick=True)
    assert list(df["variant"]) == list(SCENE_VARIANTS)
    assert {"variant", "seconds_per_rev", "accel_error", "force_error", "notes"} <= \
        set(df.columns)
    v = df.set_index("variant")
    assert v.loc["minimal", "ok"] and v.loc["minimal", "error"] < 1e-4
    assert (v["seconds_per_rev"].dropna() > 0).all()
    # contacts that never touch cost time only; the accuracy is unchanged
    assert v.loc["contacts", "max_contacts"] == 0
    assert v.loc["contacts", "error"] == pytest.approx(v.loc["minimal", "error"], rel=1e-3)
    assert v.loc["extra-visual", "ngeom"] > v.loc["minimal", "ngeom"]
    # gravity is compared with the matching (gravity) description
    assert v.loc["gravity", "ok"] and v.loc["gravity", "error"] < 1e-4
    assert "gravity-free" in v.loc["gravity", "notes"]
    # careless contacts (links overlapping at the pins) break the run: a row, no exception
    assert not v.loc["contacts-no-excludes", "ok"]
    assert v.loc["contacts-no-excludes", "reason"]


def test_studies_time_and_run_the_verdict_session(monkeypatch):
    """A grid row's errors and its timing both step the engine's protocol session (the
    verdict runs' MujocoSession.advance, through engine_base.drive / time_steps)."""
    from sim_models.engines.mujoco.driven import MujocoSession
    calls = []
    real = MujocoSession.advance

    def counted(self, t, h, n):
        calls.append(n)
        return real(self, t, h, n)

    monkeypatch.setattr(MujocoSession, "advance", counted)
    from dataclasses import asdict

    from sim_models.builders.mjcf import MujocoSettings
    row = S.grid_task("seed-four-bar", "mujoco", asdict(MujocoSettings()), "default",
                      samples=12, timing_steps=400, timing_repeats=1)
    assert row["ok"], row["reason"]
    # the run's steps (to the last sample, 1 + 11/12 revolutions) plus the timing loop's 400
    assert sum(calls) == pytest.approx(400 + (1 + 11 / 12) * row["steps_per_rev"], abs=2)
