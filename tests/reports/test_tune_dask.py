"""``xval tune --dask``: the search's candidates run on a real Dask cluster (a
``distributed.LocalCluster`` started here, two single-threaded worker processes) and
the search chooses what the serial search chooses: the runs are the same picklable
tasks, judged the same way, gathered in submission order.  Skipped when
``distributed`` is not installed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from reports.tune import TuneCase, tune

from .cli_run import run

distributed = pytest.importorskip("distributed")
pytest.importorskip("mujoco")

MODEL = str(Path(__file__).resolve().parents[2] / "docs" / "examples" / "user-four-bar.xml")


@pytest.fixture(scope="module")
def cluster():
    """Two worker processes (process CPU clocks of their own, as local workers have:
    threads would share one and blur the cost model), no dashboard."""
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as c:
        yield c


def test_dask_search_chooses_the_serial_answer(cluster):
    """Built-in case, two knobs, a budget the search does not reach: same family, same
    steps, same settings; a candidate run by both has the same error (which candidates
    the cost bound prunes depends on the measured per-step CPU, so the two sets of runs
    may differ at their expensive end)."""
    with distributed.Client(cluster) as client:
        d = tune(TuneCase("seed-four-bar"), "mujoco", 1e-3, budget=30, pool=client.get_executor(),
                 workers=2, knob_limit=2, verify=False, seed=3)
    s = tune(TuneCase("seed-four-bar"), "mujoco", 1e-3, budget=30, pool=False, workers=2,
             knob_limit=2, verify=False, seed=3)
    assert not d.search.budget_hit and not s.search.budget_hit
    assert d.answer is not None
    assert (d.answer.family, d.answer.steps) == (s.answer.family, s.answer.steps)
    assert d.settings == s.settings
    both = set(d.search.points) & set(s.search.points)
    assert len(both) >= 5
    for k in both:
        p = s.search.points[k]
        assert d.search.points[k].error == pytest.approx(p.error, rel=1e-9, abs=1e-15)


def test_cli_dask_on_a_user_model_gives_the_serial_choice(cluster):
    """``xval tune MODEL.xml --dask ADDRESS --json`` against ``--workers 1``: the same
    chosen levels and steps, both verified PASS."""
    argv = ["tune", MODEL, "--budget", "30", "--json"]
    code_d, out_d = run(*argv, "--dask", cluster.scheduler_address)
    code_s, out_s = run(*argv, "--workers", "1")
    d, s = json.loads(out_d), json.loads(out_s)
    assert code_d == code_s == 0
    assert not d["search"]["budget_hit"] and not s["search"]["budget_hit"]
    assert (d["answer"]["levels"], d["answer"]["steps_per_unit"]) == \
        (s["answer"]["levels"], s["answer"]["steps_per_unit"])
    assert d["verification"]["passed"] and s["verification"]["passed"]
