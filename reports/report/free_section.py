"""The report's "Free motion" section: its pool tasks (:mod:`reports.studies.free_studies`) and
its page (verdict table, figures per case, work-precision grid, IFToMM rows).

The quick report runs :data:`reports.studies.free_studies.VERDICT_CASES` ``[True]`` (A01 and the
seed four-bar, short) with no grid; the full report every case and the grids."""

from __future__ import annotations

import math

import pandas as pd

from reports.comparison.free_compare import (
    ENERGY_DRIFT,
    FREE_DYNAMIC,
    FREE_KINEMATIC,
    LOOP_DRIFT,
)
from reports.comparison.free_limits import verdict_of
from reports.figures.free_report_plots import work_precision_figure
from reports.studies import free_studies as FS
from sim_models.runs.free import free_engine_names

#: Queue places of the free tasks (reports.studies.scheduler: lower runs first).  A case task is
#: one serial job of several seconds: started first, it runs beside the verdict runs
#: instead of after them.  The grid runs pack the end, with the other grids.
CASE_PRIORITY = 0.5
GRID_PRIORITY = 5.0


def submit(ex, quick: bool, ph) -> dict:
    """Queue the free-motion tasks: ``{future: (kind, label, source)}`` for the report's
    pending map (kinds ``free`` and ``freegrid``)."""
    pending = {}
    n = FS.SAMPLES[quick]
    for case, dur in FS.VERDICT_CASES[quick]:
        pending[ex.submit_at(CASE_PRIORITY, FS.case_task, case, dur, n)] = ("free", case, "")
    ph.add("free motion", len(pending))
    if not quick:
        k = 0
        for case, dur in FS.GRID_CASES:
            for eng in free_engine_names():
                f = ex.submit_at(GRID_PRIORITY, FS.grid_task, case, dur, eng)
                pending[f] = ("freegrid", case, eng)
                k += 1
        ph.add("free-motion grid", k)
    return pending


def collect(kind: str, fut, label: str, studies: dict, ph) -> None:
    """Store one finished free task in ``studies["free"]``."""
    free = studies.setdefault("free", {"cases": {}, "grid": [], "errors": []})
    try:
        res = fut.result()
    except Exception as e:  # noqa: BLE001 - a study failure is a line of the report
        free["errors"].append(f"{label}: task failed: {type(e).__name__}: {e}")
        res = None
    if kind == "free":
        if res is not None:
            free["cases"][label] = res
            free["errors"] += res["errors"]
        ph.step("free motion")
    else:
        if res is not None:
            free["grid"] += res
        ph.step("free-motion grid")


def _horizon(h: float, dur: float) -> str:
    return f"whole run ({dur:g} s)" if math.isinf(h) else f"{h:.4g} s"


def verdict_frame(free: dict) -> pd.DataFrame:
    """The verdict table: case, engine, verdict, worst quantity and error, trusted
    horizon, energy and loop drift, CPU per simulated second, IFToMM class."""
    rows = [r for res in free["cases"].values() for r in res["rows"]]
    judged = [verdict_of(r) for r in rows]
    out = [{"case": r.case, "engine": r.engine, "duration s": r.duration,
            "verdict": verdict, "note": note, "worst quantity": r.worst,
            "worst error / scale": r.worst_error,
            "trusted horizon": _horizon(r.horizon, r.duration), "lost by": r.lost_by,
            "energy drift": r.energy_drift,
            "loop drift": "no loop" if math.isnan(r.loop_drift) else r.loop_drift,
            "CPU s per simulated s": r.cpu_per_s, "IFToMM class": r.iftomm_level,
            "run": "ok" if r.ok else f"stopped: {r.reason}",
            "not read (not judged)": r.not_read, "settings": r.settings}
           for r, (verdict, note) in zip(rows, judged, strict=True)]
    # a case or engine that did not run is a failed verdict too (its line says why)
    out += [{"case": e.split(":")[0].split(" / ")[0], "engine": _error_engine(e),
             "verdict": "FAIL", "note": "", "run": f"not run: {e}"} for e in free["errors"]]
    return pd.DataFrame(out, columns=VERDICT_COLUMNS)


#: The verdict table's columns (``free_verdicts.csv``; ``xval report`` reads ``verdict``).
VERDICT_COLUMNS = ["case", "engine", "duration s", "verdict", "note", "worst quantity",
                   "worst error / scale", "trusted horizon", "lost by", "energy drift",
                   "loop drift", "CPU s per simulated s", "IFToMM class", "run",
                   "not read (not judged)", "settings"]


def _error_engine(line: str) -> str:
    """The engine named by a free task's error line (``case / engine: ...``), or ''."""
    head = line.split(":")[0]
    return head.split(" / ")[1] if " / " in head else ""


def section(doc, free: dict, quick: bool) -> None:
    """Write the "Free motion" section."""
    doc.h(1, "Free motion")
    doc.p("Each engine released from the exact state at t = 0 (every body's pose and rate "
          "from the exact trajectory, no drive) at its recommended free-motion settings, "
          "and judged against the exact trajectory at the same times. Errors are over each "
          "quantity's range in the run; tolerances "
          f"{FREE_KINEMATIC:g} (coordinates, angles, rates), {FREE_DYNAMIC:g} "
          f"(accelerations, reactions), energy drift {ENERGY_DRIFT:g} of the energy scale "
          f"(max KE + range of PE), loop gap {LOOP_DRIFT:g} of the size "
          "(reports/comparison/free_compare.py says why). The trusted horizon is the first "
          "time any "
          "judged quantity exceeds its tolerance. CPU time is the stepping loop's only. "
          "Built-in cases are released at rest from their driver's reference value under "
          "9.81 m/s^2." + (" Quick report: two short cases, no grid; the full report "
                           "runs every case and the work-precision grids." if quick else ""),
          intro=True)
    vt = verdict_frame(free)
    # written even when empty: ``xval report`` counts its verdicts in the exit status
    doc.table(vt.drop(columns=["settings"]), "free_verdicts",
              "free-motion verdicts at the recommended settings", data=vt,
              wide=("note", "run", "not read (not judged)"), fold=None)
    if (vt["verdict"] == "known limit").any():
        doc.p("A 'known limit' is a case an engine is measured not to follow at its "
              "recommended setting for a reason in the engine (reports/comparison/free_limits.py "
              "lists each with its measurement); it is reported, and not counted in the "
              "exit status while its run completes with its error within the measured "
              "bound. Every other failed verdict makes xval report exit with status 1.")
    for case, res in free["cases"].items():
        if not res.get("png"):
            continue
        # the released case's own name (a built-in released from its driver's value
        # is named apart from the driven one: seed-four-bar-released)
        name = res["rows"][0].case if res.get("rows") else case
        rows = vt[vt["case"].isin({r.case for r in res.get("rows", [])} | {case})]
        page = doc.page(f"free-{name}", f"{name} (free motion): case details",
                        f"{name} (free)", _about(rows))
        _case_page(page, name, res, rows)
    rows = [r for res in free["cases"].values() for r in res["rows"]] + list(free["grid"])
    if free["grid"]:
        _grid(doc, FS.frame(free["grid"]))
    if rows:
        ift = FS.iftomm_rows(FS.frame(rows))
        if len(ift):
            doc.h(2, "IFToMM rows")
            doc.p("The benchmark problems in the IFToMM library's form: error is the "
                  "reference point's largest position error over the run (A01: the "
                  "lumped mass; m) or, for A03, the largest angle error at 0.03 s "
                  "against the published values (rad); class 1e-3 or 1e-1 m where the "
                  "position rule applies; CPU is the stepping loop's.", intro=True)
            doc.table(ift, "free_iftomm", "IFToMM-style rows", fold=None)
    for e in free["errors"]:
        doc.p(f"not run: {e}")


def _about(rows: pd.DataFrame) -> str:
    """A free case's line in the list of case pages: how many pass, and the others."""
    v = rows["verdict"].astype(str)
    other = ", ".join(f"{r.engine} {r.verdict}" for r in rows[v != "pass"].itertuples())
    return f"- {int((v == 'pass').sum())}/{len(rows)} pass" + (f" ({other})" if other else "")


def _case_page(page, case: str, res: dict, rows: pd.DataFrame) -> None:
    """A free case's page: its verdict rows and its three figures."""
    page.h(1, f"{case} (free)")
    page.table(rows.drop(columns=["settings"]), "free_verdicts", f"{case}: free-motion "
               "verdicts", wide=("note", "run", "not read (not judged)"), fold=None,
               whole="free_verdicts")
    for key, cap in (("trajectory", "released joint: exact line, engine markers"),
                     ("error", "error against time, tolerance and trusted horizon"),
                     ("drift", "energy and loop-closure drift")):
        if key in res["png"]:
            page.image(res["png"][key], f"free-{case}-{key}", f"{case}: {cap}")


def _grid(doc, g: pd.DataFrame) -> None:
    doc.h(2, "Free motion: speed against error")
    doc.p("Each engine's grid of integrators, steps and loop-constraint settings on each "
          "case. Cost: the verdicts' stepping loop (FreeSession.advance) from the released "
          f"state, best of {FS.TIMING_REPEATS} bare loops of up to {FS.TIMING_STEPS} steps "
          "(other load on a shared machine only adds time). Error at the end: the largest "
          "joint-coordinate error at the last sample over its range; the Pareto front "
          "(labelled) holds the settings no other setting of the engine beats on both.",
          intro=True)
    for case, gg in g.groupby("case", sort=False):
        doc.image(work_precision_figure(gg, FS.pareto(gg), FS.TOLERANCES,
                                        f"{case}: work-precision (free motion)"),
                  f"free-wp-{case}", f"{case}: error at the end against CPU time")
    doc.table(FS.cheapest(g), "free_cheapest", "cheapest setting per tolerance", fold=None)
    cols = ["case", "engine", "settings", "integrator", "timestep", "ok", "err_end",
            "horizon", "energy_drift", "loop_drift", "cpu_per_s", "reason"]
    doc.table(g[cols], "free_grid", f"every setting of the grid ({len(g)} runs)",
              data=g)
