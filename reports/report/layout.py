"""The report's pages, top-down: title, the first screen (what passed, what failed and
why, prescribed and free, one overview figure, links to the details:
:mod:`reports.report.first_screen`), then one section per subject, each opening with a
paragraph that says what it shows and how to read it.  Each case's figures are on a
page of their own (``cases/<case>.html``), linked from the "Cases" and "Free motion"
sections, so that ``index.html`` opens fast.

Called by :func:`reports.report.build.build_report` with the task results; writes
``index.html``, ``cases/*.html``, ``report.md`` (one file: the case pages in place),
the figures in ``img/`` and the CSV files (all under the output directory).

Measured on ``xval report --quick`` (10 cases, 5 engines, 2 free cases; 2 cores, load
6.6-9.8): ``index.html`` 251 kB and 321 kB with what it loads first (the overview
figure), 15,400 px tall at 1280 px wide, the folder 11.1 MB with 84 figures on 13 pages;
before the case pages (figures inline as base64): 14.1 MB, 37,300 px, folder 24.7 MB.
"""

from __future__ import annotations

import time

import pandas as pd

from analytic import Linkage, load_case
from reports.figures.case_figures import motion_text
from reports.report import first_screen
from reports.report.console import margin_rows, sig2
from reports.report.document import Document
from reports.report.free_section import section as free_section
from reports.report.free_section import verdict_frame as free_verdict_frame
from reports.report.tables import (
    accepted,
    input_unit,
    instantaneous_floors,
    seed_comparison,
    summary_for_reading,
    summary_table,
    verdict_table,
    verdicts_for_reading,
)
from reports.report.tune_section import section as tune_section

#: Figures of a case, in page order, with what each shows.
CASE_FIGURES = {
    "linkage": "the linkage at four inputs (colour key: input value); bodies and joints "
               "named",
    "angle": "body angles: line = analytic solution along the engines' prescribed motion, "
             "markers = each engine's samples (both on one angle convention)",
    "omega": "body angular velocities (line: analytic; markers: engines)",
    "alpha": "body angular accelerations (judged; line: analytic; markers: engines)",
    "slider": "slider accelerations s'' (judged)",
    "drive": "drive effort (judged)",
    "forces": "joint force magnitudes |F| (the verdict judges the force vector)",
    "error": "|engine - analytic| / peak of every judged quantity family, per engine, "
             "with the tolerance; the worst quantity named above each panel",
}

HARD_CAPTIONS = {
    "high_speed": "seed slider-crank at 200 rad/s: errors per engine and setting",
    "high_speed_plot": "seed slider-crank at 200 rad/s: error over the cycle",
    "near_toggle": "near-toggle four-bar (and the seed four-bar at the same settings)",
    "near_toggle_plot": "near-toggle four-bar: error over the cycle, with the transmission "
                        "angle",
    "change_point": "parallelogram four-bar through its change points: the branch each "
                    "engine follows",
    "change_point_plot": "parallelogram four-bar: rocker minus crank angle; lines: the two "
                         "analytic assembly modes",
    "long_run": "long run: per-revolution diagnostics",
    "long_run_summary": "long run: summary per engine",
    "long_run_plot": "long run: diagnostics per revolution",
    "long_run_timeseries": "long run: diagnostics against time",
}

#: Columns of the hard-case tables shown on the page (the CSV files keep all).
HARD_COLUMNS = {
    "high_speed": ["engine", "label", "steps_per_rev", "seconds_per_rev", "accel_error",
                   "force_error", "worst_quantity", "ok", "reason"],
    "near_toggle": ["case", "transmission_extreme_deg", "engine", "label", "accel_error",
                    "force_error", "error_vs_seed_four_bar", "ok", "reason"],
    "change_point": ["engine", "label", "timestep", "branch_after_singular", "final_branch",
                     "flips", "max_deviation_deg", "max_loop_violation", "ok", "reason"],
    "long_run": ["engine", "revolution", "loop_violation", "speed_deviation", "phase_drift",
                 "energy_balance", "alpha_error", "effort_error"],
}

#: Display names of study columns (with units); ``ok`` is whether the run finished.
STUDY_COLUMNS = {
    "engine": "engine", "label": "setting", "family": "family", "integrator": "integrator",
    "timestep": "timestep (s)", "steps_per_rev": "steps/rev run",
    "steps_per_second": "steps/s", "seconds_per_rev": "time per rev (s)",
    "run_seconds_per_rev": "run time per rev (s)", "accel_error": "accel error (-)",
    "force_error": "force error (-)", "error": "error (-)", "worst_quantity": "worst quantity",
    "ok": "run finished", "reason": "why it stopped", "tolerance": "tolerance (-)",
    "case": "case", "omega2": "omega2 (rad/s)",
    "transmission_extreme_deg": "transmission extreme (deg)",
    "toggle_margin_deg": "toggle margin (deg)", "at_input_deg": "at input (deg)",
    "error_vs_seed_four_bar": "error / seed four-bar's (-)",
    "branch_after_singular": "branch after singular", "final_branch": "final branch",
    "branches": "branches", "flips": "flips", "max_deviation_deg": "max deviation (deg)",
    "max_loop_violation": "max loop gap / size (-)", "revolutions": "revolutions",
    "variant": "variant", "slowdown": "slowdown (-)", "ngeom": "geoms",
    "revolution": "revolution", "loop_violation": "loop gap / size (-)",
    "speed_deviation": "crank rate error / omega (-)", "phase_drift": "phase drift (rad)",
    "energy_balance": "energy balance / work per rev (-)", "alpha_error": "alpha error (-)",
    "effort_error": "effort error (-)",
    "max_contacts": "max contacts", "notes": "notes",
}


def study_view(df: pd.DataFrame, drop=("settings", "samples", "worst_at")) -> pd.DataFrame:
    """A study table for reading: without the long settings strings (the CSV has them),
    columns named with units."""
    d = df.drop(columns=[c for c in drop if c in df.columns])
    return d.rename(columns={c: STUDY_COLUMNS.get(c, c) for c in d.columns})


def write_page(out, cfg, cases, engines, results, figures, studies, meta, ph) -> None:
    doc = Document(out)
    order = {label: i for i, (label, _) in enumerate(cases)}
    eorder = {e: i for i, e in enumerate(engines)}
    results = sorted(results, key=lambda r: (order.get(r["case"], 99),
                                             eorder.get(r["engine"], 99)))
    mechs = {label: load_case(src) for label, src in cases}
    units = {label: input_unit(m) for label, m in mechs.items()}
    revolute = {label: u == "deg" for label, u in units.items()}
    runs = [r for r in results if r["mode"] == "run"]
    verdicts = verdict_table(runs)
    summary = summary_table(verdicts, units) if len(verdicts) else pd.DataFrame()
    meta["wall_seconds"] = round(time.perf_counter() - ph.t0, 1)
    free = studies.get("free")
    first_screen.lead(doc, summary, free_verdict_frame(free) if free else None, free,
                      len(cases), engines)
    _verdict_section(doc, verdicts, summary, runs, revolute, cfg)
    times = {}  # each case's sample times (one plan per case: every engine's is the same)
    for r in runs:
        if r["run"] is not None:
            times.setdefault(r["case"], r["run"].times)
    _cases_section(doc, cases, mechs, figures, times, summary)
    seeds = seed_comparison(runs, engines)
    if len(seeds):
        doc.h(1, "Seed comparison (course notes)")
        doc.p("The notes' numbers, SolidWorks Motion's (where the notes give them), the exact "
              "analytic value and each engine's, at the notes' crank angle (the first "
              "sample of every run). The last column says why a printed number differs from "
              "the exact one.", intro=True)
        doc.table(seeds, "seed_comparison", digits=7, wide=("why the notes differ",))
    if studies.get("free"):
        free_section(doc, studies["free"], cfg.quick)
    if studies.get("tune"):
        tune_section(doc, studies["tune"], cfg.quick)
    if studies.get("grids"):
        _speed_section(doc, studies["grids"], cfg)
    if "hard" in studies:
        _hard_section(doc, studies["hard"])
    if "scene" in studies:
        _scene_section(doc, studies["scene"])
    floors = instantaneous_floors(results, units)
    if len(floors):
        doc.h(1, "MuJoCo instantaneous mode: the regularisation floor")
        doc.p("mj_forward at the exact analytic state (positions and velocities) at every "
              "sampled input: only MuJoCo's constraint regularisation separates its "
              "accelerations and forces from the exact ones. Rows: stock MuJoCo, stock with "
              "the mjENBL_DIAGEXACT flag, and this project's model (inverse weights scaled "
              "by 1e-3 after compiling, see sim_models/builders/mjcf.py). The floor is the largest "
              "error / peak over all judged quantities.", intro=True)
        doc.table(floors, "instantaneous_floors", "regularisation floor per case and variant")
    _run_section(doc, meta, ph)
    title = f"linkage-xval validation report ({meta['mode']}, {meta['date']})"
    doc.write_html(title, _run_line(meta, engines, cfg))
    (out / "report.md").write_text(doc.markdown(title))


def _run_line(meta, engines, cfg) -> str:
    """The line under the title: the engines and how the run went."""
    load = meta.get("load average at start (1, 5, 15 min)", "")
    return (f"Engines {', '.join(engines)}; {meta['mode']} report, {cfg.samples} samples per "
            f"revolution, {meta['wall_seconds']:.0f} s on {meta['cpu']}, {meta['cores']} "
            f"cores" + (f" (load at start {load.split()[0]})" if load else "") + ".")


def _verdict_section(doc, verdicts, summary, runs, revolute, cfg):
    doc.h(1, "Verdict")
    doc.p(f"One row per case and engine. Each engine runs the case at its recommended "
          f"settings for {cfg.revolutions} revolutions of the input, the last one sampled "
          f"at {cfg.samples} inputs; at every sample its body angular accelerations, slider "
          "accelerations, drive effort, joint forces and the sliders' normal forces and "
          "moments are compared with the analytic "
          "solution at the same input, rate and acceleration. The error is the largest "
          "|engine - analytic| over the samples divided by the quantity's peak; a run "
          "passes when every quantity is within the tolerance. 'error / tolerance' below 1 "
          "is the margin.", intro=True)
    if not len(summary):
        doc.p("no engine ran")
        return
    doc.table(summary_for_reading(summary), "verdict_summary", "verdict per case and engine",
              data=summary, fold=None, wide=("note",), digits=2)
    doc.p("Every compared quantity, with its unit. Rows 'not judged' are an engine's own "
          "readings (PyBullet's jointReactionForces and motor torque), reported but not "
          "judged: the judged forces are rebuilt by Newton-Euler from the engine's motion.")
    doc.table(verdicts_for_reading(verdicts, revolute), "verdicts",
              "every compared quantity", data=verdicts, wide=("why the run stopped",),
              digits=3)
    rows = {}
    for r in runs:
        if r["run"] is not None and r["engine"] not in rows:
            rows[r["engine"]] = {"engine": r["engine"], "settings": r["run"].settings_text}
    if rows:
        doc.table(pd.DataFrame(list(rows.values())), "engine_settings",
                  "engine settings of the verdict runs", wide=("settings",), fold=None)


def _cases_section(doc, cases, mechs, figures, times=None, summary=None):
    doc.h(1, "Cases")
    doc.p("Each case has a page of its own: how its input moves, its verdict rows, the "
          "linkage, then each quantity over the sampled input range (lines: the analytic "
          "solution along the motion the engines were driven at; markers: each engine's "
          "samples, grey where the verdict does not judge them), then the error panels, "
          "which are the verdict's numbers sample by sample. A limited-range input shows "
          "the range the engines covered, the rest shaded, and its limit positions as "
          "dashed lines; an axis clipped around a spike says so on the figure.", intro=True)
    for label, _ in cases:
        rows = (summary[summary["case"] == label] if summary is not None and len(summary)
                else pd.DataFrame())
        page = doc.page(label, f"{label}: case details", label, _case_about(rows))
        _case_page(page, label, mechs[label], figures.get(label, {}),
                   (times or {}).get(label, []), rows)


def _case_about(rows: pd.DataFrame) -> str:
    """A case's line in the list of case pages: passes, and its smallest margin."""
    if not len(rows):
        return "(no engine ran)"
    ok = accepted(rows)
    w = margin_rows(rows).sort_values("ratio", kind="stable").iloc[-1]
    worst = (f"worst {sig2(w['ratio'])} of tolerance ({w['engine']} "
             f"{w['worst quantity'] or 'run'})")
    return f"- {int(ok.sum())}/{len(rows)} pass; {worst}"


def _case_page(page, label, mech, figs, times, rows):
    """One case's page: its motion, verdict rows and figures."""
    page.h(1, label)
    # in the figures' units (deg), with the rate reached over the plotted samples
    page.p(motion_text(Linkage(mech), times) + ".")
    if len(rows):
        page.table(summary_for_reading(rows), "verdict_summary", f"{label}: verdict per "
                   "engine", fold=None, wide=("note",), digits=2, whole="verdict_summary")
    if "error" in figs and isinstance(figs["error"], str):
        page.p(f"figures failed: {figs['error']}")
        return
    for name, cap in CASE_FIGURES.items():
        if name in figs:
            page.image(figs[name], f"{label}-{name}", f"{label}: {cap}")


def _speed_section(doc, grids, cfg):
    doc.h(1, "Speed against error")
    doc.p("Each engine setting of a grid (integrator, constraint family, steps per "
          "revolution) runs the case like a verdict run; its error is the largest error / "
          "peak over accelerations and forces, its cost the wall-clock time of a bare "
          "stepping loop per simulated revolution (timed while the report's other tasks "
          "run, so compare points within one plot). The Pareto plot labels only the "
          "settings no other setting beats on both; the dotted lines are the tolerances of "
          "the cheapest-setting table. The vertical line is the analytic solver's time "
          f"for one revolution at the engines' {cfg.samples} samples.", intro=True)
    for case, res in grids.items():
        doc.h(2, case)
        if "grid" not in res:
            doc.p(f"study failed: {res.get('error')}")
            continue
        if "png" in res:
            doc.image(res["png"], f"pareto-{case}", f"{case}: speed against error")
        doc.table(study_view(res["cheapest"]), f"cheapest_{case}",
                  "cheapest setting meeting each tolerance", data=res["cheapest"], fold=None)
        g = res["grid"]
        doc.table(study_view(g.drop(columns=["case"])), f"speed_error_{case}",
                  f"every setting of the grid ({len(g)} runs)", data=g)
        if "analytic_s_per_rev" in res:
            doc.p(f"analytic solver: {res['analytic_s_per_rev'] * 1e3:.3g} ms per revolution "
                  f"of {cfg.samples} samples, with forces (best of 5).")


def _hard_section(doc, hard):
    doc.h(1, "Hard cases")
    doc.p("Cases that stress the engines: a fast slider-crank, a four-bar near its toggle "
          "position, a parallelogram through its change points (which branch does each "
          "engine follow?), and a long run (drift of loop closure, crank speed and energy). "
          "Full tables, with every setting string, are in the linked CSV files.", intro=True)
    if "error" in hard and len(hard) == 1:
        doc.p(f"study failed: {hard['error']}")
        return
    for key, val in hard.items():
        cap = HARD_CAPTIONS.get(key, key.replace("_", " "))
        if isinstance(val, pd.DataFrame):
            if key == "long_run_summary":
                view = val.drop(columns=[c for c in ("settings",) if c in val]).set_index(
                    "engine").T.reset_index().rename(columns={"index": "quantity"})
                doc.table(view, f"hard_{key}", cap, data=val, fold=None)
            else:
                cols = [c for c in HARD_COLUMNS.get(key, val.columns) if c in val.columns]
                doc.table(study_view(val[cols]), f"hard_{key}", cap, data=val,
                          wide=("why it stopped",))
        elif isinstance(val, bytes | bytearray):
            doc.image(bytes(val), f"hard-{key}", cap)
        elif isinstance(val, str) and key == "notes":
            doc.p("notes: " + val)


def _scene_section(doc, scene):
    doc.h(1, "Scene economy")
    doc.p("The seed four-bar in MuJoCo with parts a validation scene does not need "
          "(contacts, extra geoms, gravity): what each costs in time per revolution and "
          "whether it changes the error.", intro=True)
    if "table" not in scene:
        doc.p(f"study failed: {scene.get('error')}")
        return
    doc.table(study_view(scene["table"]), "scene_economy", "scene variants",
              data=scene["table"], wide=("notes",), fold=None)
    if "png" in scene:
        doc.image(scene["png"], "scene-economy", "scene variants: speed against error")


def _run_section(doc, meta, ph):
    doc.h(1, "Run")
    doc.p("The machine, the versions and the wall time of each phase of this run (phases "
          "overlap: they share one process pool).", intro=True)
    doc.table(pd.DataFrame([{"key": k, "value": str(v)} for k, v in meta.items()]),
              "run_metadata", "machine, versions, settings", fold=None)
    doc.table(pd.DataFrame([{"phase": k, "wall time (s)": v}
                            for k, v in ph.seconds().items()]), "phase_times",
              "wall time of each phase so far", fold=None)


__all__ = ["CASE_FIGURES", "write_page"]
