"""The report's "Tuned settings" section: per engine, the cheapest settings whose
verdict passes at 1e-3 and 1e-4 of peak, found by ``xval tune``'s search
(:mod:`reports.tune`) on the report's pool.

Quick report: the seed four-bar (prescribed) and A01 (free, 2 s), the step alone
searched (:data:`QUICK_KNOBS`) within a small budget per search, so the section adds
seconds, not minutes; the full report searches every knob on the seed four-bar and
the seed slider-crank (prescribed) and on A01 and the seed four-bar (free, 2 s)."""

from __future__ import annotations

import math

import pandas as pd

from sim_models.engines.registry import available_engines
from sim_models.runs.free import free_engine_names

#: Tolerances of the table (of peak, prescribed; of scale, free).
TOLERANCES = (1e-3, 1e-4)
#: (case, free, duration s) per mode.
CASES = {True: (("seed-four-bar", False, None), ("iftomm-a01-pendulum", True, 2.0)),
         False: (("seed-four-bar", False, None), ("seed-slider-crank", False, None),
                 ("iftomm-a01-pendulum", True, 2.0), ("seed-four-bar", True, 2.0))}
#: Free runs judged at the report's quick free verdicts' samples (reports.studies.
#: free_studies.SAMPLES[True]): A01's own 4001 make each run seconds of readout.
FREE_SAMPLES = 100
#: Knobs searched besides the step (quick: none; full: all) and CPU s per search.
#: Measured (quick: 8 searches in 2 tasks, one per case, the 1e-3 rows read from the
#: 1e-4 searches, on 2 workers, load 1.4-1.8): 8.5 CPU s, 7.9 s wall; the seed
#: four-bar's full searches take 2-6 CPU s (prescribed) and 8-23 CPU s (free) each.
QUICK_KNOBS, QUICK_BUDGET, FULL_BUDGET = 0, 3.0, 15.0
#: Engines of the table (MuJoCo Warp left out: its float32 floor is the free section's).
ENGINES = ("mujoco", "pybullet", "exudyn", "pinocchio")
#: Queue place: after the verdict runs and figures, with the grids.
PRIORITY = 4.5
COLUMNS = ["case", "mode", "engine", "tolerance", "verdict", "steps per unit",
           "worst error", "model CPU ms per unit", "recommended model CPU ms", "ratio",
           "changed", "knob", "search runs", "search CPU s", "note"]


def tune_task(case: str, free: bool, duration, engine: str, tolerance: float,
              knob_limit, budget: float, also=()) -> list[dict]:
    """One search, serial in this worker (``verify=False``: the answer is a measured run
    that passed): its row, then one row per tolerance of ``also`` read from the same
    runs (:func:`reports.tune.tune.retarget`); never an exception."""
    from reports.tune import TuneCase, tune
    from reports.tune.tune import retarget
    row = {"case": case, "mode": "free" if free else "prescribed", "engine": engine,
           "tolerance": tolerance}
    try:
        res = tune(TuneCase(case, free, duration, FREE_SAMPLES if free else None), engine,
                   tolerance, budget=budget,
                   pool=False, knob_limit=knob_limit, verify=False)
    except Exception as e:  # noqa: BLE001 - a study failure is a row of the report
        return [{**row, "verdict": "not run", "note": f"{type(e).__name__}: {e}"}]
    rows = [_row(row, res)]
    for tol in also:
        try:
            rows.append({**_row({**row, "tolerance": tol}, retarget(res, tol)),
                         "note": f"read from the {tolerance:g} search's runs: the "
                                 "cheapest of them that passes; a coarser step, not run, "
                                 "may pass too"})
        except Exception as e:  # noqa: BLE001 - a study failure is a row of the report
            rows.append({**row, "tolerance": tol, "verdict": "not run",
                         "note": f"{type(e).__name__}: {e}"})
    return rows


def _row(row: dict, res) -> dict:
    """The table's row of one :class:`reports.tune.tune.TuneResult`."""
    s = res.search
    row.update({"search runs": s.runs, "search CPU s": s.spent})
    if res.answer is None:
        return {**row, "verdict": "none passes", "note": res.limit_text}
    a, r = res.cost(res.answer), res.cost(res.recommended) if res.recommended else math.nan
    row.update({"verdict": "pass", "steps per unit": res.answer.steps,
                "worst error": res.answer.error, "model CPU ms per unit": a * 1e3,
                "recommended model CPU ms": r * 1e3, "ratio": a / r if r > 0 else math.nan,
                "changed": ", ".join(f"{k}={_fmt(b)}" for k, (_a, b) in res.changed.items())
                or "recommended", "knob": res.knob_text,
                "note": "budget spent" if s.budget_hit else ""})
    return row


def case_task(case: str, free: bool, duration, engines, tolerances, knob_limit,
              budget: float) -> list[dict]:
    """Every engine's and tolerance's search of one case in this worker (a free case's
    exact reference is computed once per worker).  Quick (``knob_limit`` 0): one search
    per engine at the tightest tolerance, the others read from its runs."""
    if knob_limit == 0:
        tight = min(tolerances)
        return [r for e in engines
                for r in tune_task(case, free, duration, e, tight, knob_limit, budget,
                                   [t for t in tolerances if t != tight])]
    return [r for e in engines for t in tolerances
            for r in tune_task(case, free, duration, e, t, knob_limit, budget)]


def _fmt(v) -> str:
    if isinstance(v, tuple):
        return "(" + ",".join(f"{x:.4g}" for x in v) + ")"
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def submit(ex, quick: bool, ph) -> dict:
    """Queue the searches: ``{future: ("tune", label, "")}``."""
    pending = {}
    have = set(available_engines())
    free_ok = set(free_engine_names())
    knobs = QUICK_KNOBS if quick else None
    budget = QUICK_BUDGET if quick else FULL_BUDGET
    for case, free, dur in CASES[quick]:
        engines = [e for e in ENGINES if e in have and (not free or e in free_ok)]
        if engines:
            f = ex.submit_at(PRIORITY, case_task, case, free, dur, engines, TOLERANCES,
                             knobs, budget)
            pending[f] = ("tune", f"{case}{' (free)' if free else ''}", "")
    ph.add("tuned settings", len(pending))
    return pending


def collect(fut, label: str, studies: dict, ph) -> None:
    rows = studies.setdefault("tune", [])
    try:
        rows.extend(fut.result())
    except Exception as e:  # noqa: BLE001 - a study failure is a row of the report
        rows.append({"case": label, "verdict": "not run", "note": f"task failed: {e}"})
    ph.step("tuned settings")


def section(doc, rows: list[dict], quick: bool) -> None:
    """Write the "Tuned settings" section."""
    doc.h(1, "Tuned settings (xval tune)")
    doc.p("Per engine, the cheapest settings found whose verdict passes at each "
          "tolerance on every judged quantity (prescribed: of peak; free: of each "
          "quantity's scale), by xval tune's search over measured runs "
          "(reports/tune/search.py). Cost: steps per revolution (prescribed) or per "
          "simulated second (free) times the per-step process CPU of the bare stepping "
          "loop, against the recommended settings' cost by the same model. "
          + ("Quick report: the step alone is searched, "
             f"{QUICK_BUDGET:g} CPU s per search, at {min(TOLERANCES):g}; the other "
             "tolerance's rows are read from its runs (see their note); the full report "
             "searches every knob at each tolerance. "
             if quick else f"Every knob searched, {FULL_BUDGET:g} CPU s per search. ")
          + "Reproduce one row, with its verification run and Pareto table: xval tune "
          "CASE --engine NAME --tolerance T [--free --duration 2].", intro=True)
    df = pd.DataFrame(rows, columns=COLUMNS).sort_values(["case", "mode", "engine",
                                                          "tolerance"], kind="stable")
    doc.table(df, "tuned_settings", "cheapest passing settings per engine and tolerance",
              wide=("changed", "knob", "note"), fold=None)


__all__ = ["CASES", "COLUMNS", "TOLERANCES", "case_task", "collect", "section", "submit",
           "tune_task"]
