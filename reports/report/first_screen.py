"""The report's first screen: what passed, what failed and why, for the prescribed and
the free runs, with one overview figure and links to the details.

Read from the same tables the page and the exit status read: the prescribed summary
(:func:`reports.report.tables.summary_table`) and the free verdicts
(:func:`reports.report.free_section.verdict_frame`, with each run's worst quantity's
tolerance from its :class:`reports.comparison.free_compare.FreeVerdict`).  Every run
that did not pass is a line with its reason; the figure
(:func:`reports.figures.overview.overview_figure`) shows every run's worst error over its
tolerance.
"""

from __future__ import annotations

import math

import pandas as pd

from reports.figures.overview import OverviewCell, overview_figure
from reports.report.console import counts_line, free_counts_line, margin_rows, sig2
from reports.report.tables import LIMIT_PREFIX, accepted

#: Name of the overview figure's file (``img/overview.png``).
FIGURE_NAME = "overview"


def _status(verdict: str) -> str:
    v = str(verdict)
    if v == "pass":
        return "pass"
    if v.startswith(LIMIT_PREFIX) or v == "known limit":
        return "limit"
    return "FAIL"


def free_row_label(case: str) -> str:
    return f"{case} (free)"


def prescribed_cells(summary: pd.DataFrame) -> list[OverviewCell]:
    """One cell per summary row: its worst error over tolerance (a run that stopped or
    never ran: not run, or inf when it failed)."""
    out = []
    for d in margin_rows(summary).to_dict("records"):
        st = _status(d["verdict"])
        r = float(d["ratio"])
        if not math.isfinite(r) and st == "FAIL" and not str(d.get("worst quantity") or ""):
            st = "not run"
        out.append(OverviewCell(str(d["case"]), str(d["engine"]), r, st))
    return out


def free_ratios(free: dict) -> dict[tuple[str, str], float]:
    """(case, engine) -> the run's worst judged error over that quantity's tolerance."""
    out = {}
    for res in free.get("cases", {}).values():
        for v in res.get("verdicts", []):
            w = v.worst
            out[v.case, v.engine] = (w.normalised / w.tolerance if w.tolerance > 0
                                     else math.inf)
    return out


def free_cells(vt: pd.DataFrame, free: dict) -> list[OverviewCell]:
    ratios = free_ratios(free)
    out = []
    for d in vt.to_dict("records"):
        st = _status(d["verdict"])
        r = ratios.get((d["case"], d["engine"]), math.nan)
        if math.isnan(r):
            st = "not run" if st != "pass" else st
        out.append(OverviewCell(free_row_label(d["case"]), str(d["engine"] or "?"), r, st))
    return out


def prescribed_items(summary: pd.DataFrame) -> list[tuple[str, str, str]]:
    """``(tag, class, text)`` of every prescribed run that did not pass, with why."""
    out = []
    for d in summary.to_dict("records"):
        st = _status(d["verdict"])
        if st == "pass":
            continue
        note = str(d.get("note") or "")
        if note in ("", "nan"):
            note = (f"{d['worst quantity']} {sig2(d['worst error / peak'])} of peak over "
                    f"the tolerance {sig2(d['tolerance'])} at {d.get('at (input)', '')}")
        tag = "FAIL" if st == "FAIL" else str(d["verdict"])
        out.append((tag, "fail" if st == "FAIL" else "limit",
                    f"prescribed {d['case']} / {d['engine']}: {note}"))
    return out


def free_items(vt: pd.DataFrame, free: dict) -> list[tuple[str, str, str]]:
    """``(tag, class, text)`` of every free run that did not pass: its worst quantity
    over its tolerance, how long it is trusted, and its note or why it stopped."""
    ratios = free_ratios(free)
    out = []
    for d in vt.to_dict("records"):
        st = _status(d["verdict"])
        if st == "pass":
            continue
        eng = str(d.get("engine") or "") or "-"
        dur = d.get("duration s")
        head = f"free {d['case']} / {eng}" + (
            f" ({float(dur):g} s)" if dur is not None and not pd.isna(dur) else "")
        why = []
        r = ratios.get((d["case"], d.get("engine")), math.nan)
        if str(d.get("worst quantity") or "") and math.isfinite(r):
            why.append(f"{d['worst quantity']} {sig2(r)} x its tolerance, trusted "
                       f"{d.get('trusted horizon')}")
        run = str(d.get("run") or "")
        if run and run != "ok":
            why.append(run)
        if str(d.get("note") or "") not in ("", "nan"):
            why.append(str(d["note"]))
        out.append((str(d["verdict"]), "fail" if st == "FAIL" else "limit",
                     head + ": " + "; ".join(why or ["no reason recorded"])))
    return out


def _headline(summary: pd.DataFrame, vt: pd.DataFrame | None) -> str:
    n = len(summary) + (len(vt) if vt is not None else 0)
    failed = int((~accepted(summary)).sum()) if len(summary) else 0
    limits = int(summary["verdict"].astype(str).str.startswith(LIMIT_PREFIX).sum()) \
        if len(summary) else 0
    if vt is not None and len(vt):
        failed += int((vt["verdict"].astype(str) == "FAIL").sum())
        limits += int((vt["verdict"].astype(str) == "known limit").sum())
    if failed:
        return f"{failed} of {n} runs FAIL (xval report exits with status 1)"
    text = f"No run fails: {n - limits} of {n} pass"
    return text + (f", {limits} at a known engine or precision limit (not counted as "
                   "failures)" if limits else "")


def lead(doc, summary: pd.DataFrame, vt: pd.DataFrame | None, free: dict | None,
         cases: int, engines) -> None:
    """Write the first screen into ``doc``: the headline, one line per kind of run, the
    runs that did not pass with their reasons, and the overview figure."""
    lines = []
    if len(summary):
        lines.append(f"Prescribed motion ({cases} cases, each engine driven at the analytic "
                     f"input): {counts_line(summary)}.")
    else:
        lines.append("Prescribed motion: no engine ran.")
    if vt is not None:
        nfree = vt["case"].nunique() if len(vt) else 0
        lines.append(f"Free motion ({nfree} cases, each engine released from the exact "
                     f"state): {free_counts_line(vt).removeprefix('free motion: ')}.")
    else:
        lines.append("Free motion: not run in this report (it runs with the built-in "
                     "cases and the studies).")
    items = prescribed_items(summary) + (free_items(vt, free or {}) if vt is not None
                                         else [])
    if not items:
        lines.append("Every run passes: none failed, none at a limit.")
    cells = prescribed_cells(summary) if len(summary) else []
    rows = list(dict.fromkeys(c.row for c in cells))
    split = len(rows)
    if vt is not None and len(vt):
        fc = free_cells(vt, free or {})
        cells += fc
        rows += list(dict.fromkeys(c.row for c in fc))
    cols = list(dict.fromkeys([*engines, *(c.engine for c in cells)]))
    figure = None
    if cells:
        png = overview_figure(rows, cols, cells, split, "worst error / tolerance per case "
                              "and engine" + (" (free motion below the line)"
                                              if len(rows) > split else ""))
        figure = (png, FIGURE_NAME, "every run's worst error over its tolerance: green "
                  "pass, amber at a known or precision limit, red FAIL, grey not run")
    doc.lead(_headline(summary, vt), lines, items, figure)


__all__ = ["FIGURE_NAME", "free_cells", "free_items", "free_ratios", "lead",
           "prescribed_cells", "prescribed_items"]
