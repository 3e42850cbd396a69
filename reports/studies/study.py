"""The whole speed/accuracy study: the grids, the hard cases and the scene economy run
together (:func:`run_study`) and written as CSV tables and PNG figures
(:func:`write_study`)."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pandas as pd

from reports.studies.hard_cases import hard_cases
from reports.studies.scene import scene_economy, scene_figure
from reports.studies.speed_accuracy import (
    FULL_CASES,
    QUICK_CASES,
    _gather,
    _grid_frame,
    _grid_futures,
    analytic_seconds_per_rev,
    cheapest_settings,
    executor,
    pareto_figure,
)


def run_study(quick: bool, pool=None, cases=None, workers: int | None = None) -> dict:
    """Everything: the grids of :data:`QUICK_CASES` / :data:`FULL_CASES` with their
    Pareto figures and cheapest-setting tables, the analytic times, the hard cases and
    the scene economy; ``timings`` holds the wall time of each part."""
    cases = list(cases or (QUICK_CASES if quick else FULL_CASES))
    out: dict = {"quick": quick, "timings": {}}
    t00 = time.perf_counter()
    with executor(pool, workers) as ex:
        t0 = time.perf_counter()
        futs = {c: _grid_futures(ex, c, quick) for c in cases}
        grids = {c: _grid_frame(_gather(f)) for c, f in futs.items()}
        out["timings"]["grids"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        out["hard"] = hard_cases(quick, ex)
        out["timings"]["hard_cases"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    out["scene_economy"] = scene_economy(quick)
    out["scene_economy_plot"] = scene_figure(out["scene_economy"])
    out["timings"]["scene_economy"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    out["grids"] = grids
    out["grid"] = pd.concat(grids.values(), ignore_index=True)
    out["cheapest"] = cheapest_settings(out["grid"])
    out["analytic_seconds_per_rev"] = {c: analytic_seconds_per_rev(c) for c in cases}
    out["pareto_plots"] = {c: pareto_figure(g, c, out["analytic_seconds_per_rev"][c])
                           for c, g in grids.items()}
    out["timings"]["figures"] = time.perf_counter() - t0
    out["timings"]["total"] = time.perf_counter() - t00
    return out


def write_study(res: dict, out_dir: Path) -> list[Path]:
    """CSV tables and PNG figures of :func:`run_study` into ``out_dir``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []

    def csv(name, df):
        p = out_dir / f"{name}.csv"
        df.to_csv(p, index=False)
        written.append(p)

    def png(name, data):
        p = out_dir / f"{name}.png"
        p.write_bytes(data)
        written.append(p)

    csv("grid", res["grid"])
    csv("cheapest", res["cheapest"])
    for c, b in res["pareto_plots"].items():
        png(f"pareto-{c}", b)
    h = res["hard"]
    for k in ("high_speed", "near_toggle", "change_point", "long_run", "long_run_summary"):
        csv(k, h[k])
    for k in ("high_speed_plot", "near_toggle_plot", "change_point_plot", "long_run_plot",
              "long_run_timeseries"):
        if k in h:
            png(k, h[k])
    csv("scene_economy", res["scene_economy"])
    png("scene_economy", res["scene_economy_plot"])
    p = out_dir / "timings.json"
    p.write_text(json.dumps({"quick": res["quick"], **res["timings"],
                             "analytic_seconds_per_rev": res["analytic_seconds_per_rev"]},
                            indent=1))
    written.append(p)
    return written
