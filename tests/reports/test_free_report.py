"""The report's "Free motion" section: a real (short) MuJoCo free run of A01 judged and
written as a verdict table, three figures and the IFToMM rows; the work-precision
helpers on a hand-made grid whose Pareto front and cheapest settings are known."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from reports.report import free_section as report_free
from reports.report.document import Document
from reports.studies import free_studies as FS


@pytest.fixture(autouse=True)
def _headless(monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "disable")


def test_section_has_table_figures_and_iftomm_rows(tmp_path):
    res = FS.case_task("iftomm-a01-pendulum", 0.5, 20, engines=["mujoco"])
    assert not res["errors"], res["errors"]
    doc = Document(tmp_path)
    report_free.section(doc, {"cases": {"iftomm-a01-pendulum": res}, "grid": [],
                              "errors": []}, quick=True)
    md = doc.markdown("t")
    assert "# Free motion" in md and "trusted horizon" in md
    for key in ("trajectory", "error", "drift"):
        assert (tmp_path / "img" / f"free-iftomm-a01-pendulum-{key}.png").stat().st_size > 1000
    vt = pd.read_csv(tmp_path / "free_verdicts.csv")
    assert list(vt["engine"]) == ["mujoco"] and vt["verdict"][0] == "pass"
    ift = pd.read_csv(tmp_path / "free_iftomm.csv", dtype={"class": str})
    assert ift["problem"][0] == "iftomm-a01-pendulum" and ift["class"][0] == "1e-3"
    assert ift["code"][0].startswith("mujoco ")


def _row(engine, settings, cpu, err, ok=True):
    return FS.FreeRow("c", engine, 1.0, settings, "i", 1e-3, ok, ok, "", "q", err, err,
                      math.inf, "", 0.0, 0.0, cpu, 10, cpu, "", math.nan)


def test_pareto_and_cheapest_on_a_known_grid():
    g = FS.frame([_row("e", "a", 1.0, 1e-2), _row("e", "b", 2.0, 1e-4),
                  _row("e", "c", 3.0, 1e-3),   # dominated by b
                  _row("e", "d", 0.5, 1e-1), _row("e", "x", 0.1, math.inf, ok=False)])
    assert list(FS.pareto(g)["settings"]) == ["d", "a", "b"]
    ch = FS.cheapest(g, (1e-2, 1e-3, 1e-5)).set_index("tolerance")["settings"]
    assert ch[1e-2] == "a" and ch[1e-3] == "b" and ch[1e-5] == "none"


class _Ex:
    def __init__(self):
        self.calls = []

    def submit_at(self, p, fn, *args):
        self.calls.append((p, fn.__name__, args))
        return object()


class _Ph:
    def add(self, name, n):
        pass


def test_quick_report_runs_two_short_cases_and_no_grid():
    ex = _Ex()
    pending = report_free.submit(ex, True, _Ph())
    assert [c[1] for c in ex.calls] == ["case_task", "case_task"]
    assert {c[2][0] for c in ex.calls} == {"iftomm-a01-pendulum", "seed-four-bar"}
    assert max(c[2][1] for c in ex.calls) <= 2.0 and len(pending) == 2
    full = _Ex()
    report_free.submit(full, False, _Ph())
    from sim_models.runs.free import free_engine_names
    # one grid per case and installed free-motion engine (pinocchio only with its extra)
    assert sum(c[1] == "grid_task" for c in full.calls) == 2 * len(free_engine_names())


class _Done:
    def __init__(self, value):
        self.value = value

    def result(self):
        return self.value


class _Steps(_Ph):
    def step(self, name, n=1):
        pass


def test_full_report_grid_rows_become_pareto_figure_and_tables(tmp_path):
    rows = FS.grid_task("iftomm-a01-pendulum", 0.3, "mujoco", 15,
                        grid=[{"integrator": "Euler", "timestep": 2e-3}])
    assert [r.settings for r in rows] == ["recommended", "integrator=Euler timestep=0.002"]
    assert all(r.ok and r.cpu_per_s > 0 for r in rows)
    studies: dict = {}
    report_free.collect("freegrid", _Done(rows), "iftomm-a01-pendulum", studies, _Steps())
    doc = Document(tmp_path)
    report_free.section(doc, studies["free"], quick=False)
    assert (tmp_path / "img" / "free-wp-iftomm-a01-pendulum.png").stat().st_size > 1000
    assert len(pd.read_csv(tmp_path / "free_grid.csv")) == 2
    ch = pd.read_csv(tmp_path / "free_cheapest.csv")
    assert set(ch["tolerance"]) == set(FS.TOLERANCES)


def test_a_mechanism_without_a_loop_has_no_loop_drift_not_a_zero():
    """A pendulum has no cut joint: its loop drift is "no loop", never a measured 0."""
    import math
    from types import SimpleNamespace

    import numpy as np

    from analytic import load_case
    from analytic.free_motion import simulate
    from reports.comparison.free_compare import compare_free, reference_samples
    from reports.studies.free_studies import _loop_drift
    from sim_models.runs.free_run import FreeEngineRun

    traj = simulate(load_case("iftomm-a01-pendulum"), duration=0.5)
    t = np.linspace(0.0, 0.5, 11)
    ref = reference_samples(traj, t)
    run = FreeEngineRun(
        "iftomm-a01-pendulum", "exact", traj.mech, SimpleNamespace(describe=lambda: ""),
        SimpleNamespace(duration=0.5), True, None, None, t, tuple(ref.joints),
        tuple(b.name for b in traj.mech.bodies), ref.x, ref.xd, ref.theta, ref.omega,
        ref.alpha, np.full((11, 1, 2), np.nan), np.zeros(11), ref.kinetic, ref.potential,
        None, 0.0, 0, 1e-3, "exact")
    v = compare_free(run, traj, ref)
    assert not v.has_loop and v.as_json()["loop_drift"] is None
    assert math.isnan(_loop_drift(run, v))


def test_every_free_engine_has_a_work_precision_grid():
    """The full report's grid tasks run every installed free engine on
    :data:`FS.GRID_CASES`: with Pinocchio installed both tasks ended in ``KeyError:
    'pinocchio'`` (no grid for it), counted as two failed verdicts.  Every engine with a
    free run has a grid, and Pinocchio's runs (a short A01, three of its settings)."""
    from sim_models.runs.free import FREE_SESSIONS
    assert set(FS.GRID) == set(FREE_SESSIONS)
    pytest.importorskip("pinocchio")
    rows = FS.grid_task("iftomm-a01-pendulum", 0.2, "pinocchio", samples=20,
                        grid=FS.GRID["pinocchio"][:2])
    assert [r.settings for r in rows][0] == "recommended" and len(rows) == 3
    assert all(r.ok for r in rows), [r.reason for r in rows]


def test_error_figure_of_a_stopped_run_warns_nothing():
    """A run that stopped has no values from its stop on: the error figure printed numpy's
    "All-NaN slice encountered" RuntimeWarning into the full report's console."""
    import warnings
    from types import SimpleNamespace

    import numpy as np

    from reports.figures.free_report_plots import error_figure
    t = np.linspace(0.0, 1.0, 11)
    err = np.where(t < 0.5, 1e-4, np.nan)
    c = SimpleNamespace(family="joint angle", error=err)
    v = SimpleNamespace(comparisons=[c, c], times=t, engine="mujoco", horizon=0.5,
                        lost_by=None)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        png = error_figure([v], "stopped")
    assert png[:4] == b"\x89PNG"
