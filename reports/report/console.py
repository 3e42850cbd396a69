"""The console verdict of ``xval report``: a compact table and one line of counts.

The table fits :data:`WIDTH` columns (long case names are shortened with an ellipsis),
errors are printed to two significant figures, and the last line reads e.g.
``20 of 20 pass (mujoco 10/10, pybullet 10/10); smallest margin: hibbeler-16-121
pybullet crank.alpha 8.5e-4 of 1e-3`` for however many engines ran.
"""

from __future__ import annotations

import math
import textwrap

import pandas as pd

from reports.report.tables import LIMIT_PREFIX, accepted

WIDTH = 100


def sig2(v) -> str:
    """A number to two significant figures (``inf``, blank for NaN)."""
    try:
        v = float(v)
    except (TypeError, ValueError):
        return str(v)
    if math.isnan(v):
        return ""
    if math.isinf(v):
        return "inf"
    if v == 0 or 0.01 <= abs(v) < 1e4:
        return f"{float(f'{v:.2g}'):g}"
    m, e = f"{v:.1e}".split("e")  # 8.5e-04 -> 8.5e-4, 1.0e-03 -> 1e-3
    return f"{m.removesuffix('.0')}e{int(e)}"


def _text(v) -> str:
    return "" if v is None or (isinstance(v, float) and math.isnan(v)) else str(v)


def _short(s: str, n: int) -> str:
    s = str(s)
    return s if len(s) <= n else s[:max(n - 1, 1)] + "…"


def margin_rows(summary: pd.DataFrame) -> pd.DataFrame:
    """Summary rows with ``ratio`` = worst error / tolerance (inf for a failed run)."""
    s = summary.copy()
    err = pd.to_numeric(s["worst error / peak"], errors="coerce")
    tol = pd.to_numeric(s["tolerance"], errors="coerce")
    s["ratio"] = (err / tol).where(err.notna() & tol.notna() & (tol > 0), math.inf)
    return s


def counts_line(summary: pd.DataFrame) -> str:
    """``N of M pass (engine k/n, ...); smallest margin: case engine quantity e of tol``."""
    if not len(summary):
        return "no runs"
    passed = accepted(summary)  # a precision limit is not a failure
    per = ", ".join(f"{e} {int(passed[summary['engine'] == e].sum())}/"
                    f"{int((summary['engine'] == e).sum())}"
                    for e in dict.fromkeys(summary["engine"]))
    s = margin_rows(summary)
    w = s.loc[s["ratio"].idxmax()]
    where = f"{w['case']} {w['engine']} {w['worst quantity'] or '(run)'}"
    err = f"{sig2(w['worst error / peak'])} of {sig2(w['tolerance'])}"
    if math.isinf(w["ratio"]):
        margin, label = f"{where} (run failed)", "worst"
    elif w["ratio"] > 1:
        margin, label = f"{where} {err}", "worst"
    else:
        margin, label = f"{where} {err}", "smallest margin"
    lim = int(summary["verdict"].astype(str).str.startswith(LIMIT_PREFIX).sum())
    lim_text = f", {lim} of them at a precision limit" if lim else ""
    return (f"{int(passed.sum())} of {len(summary)} pass{lim_text} ({per}); "
            f"{label}: {margin}")


def verdict_table(summary: pd.DataFrame, width: int = WIDTH) -> list[str]:
    """The verdict rows as fixed-width lines no wider than ``width``."""
    if not len(summary):
        return []
    rows = []
    for d in summary.to_dict("records"):
        prec = d.get("precision")
        engine = str(d.get("engine", "")) + (f" ({prec})" if prec == "float32" else "")
        rows.append([str(d.get("case", "")), engine,
                     str(d.get("verdict", "")), str(d.get("worst quantity", "") or ""),
                     sig2(d.get("worst error / peak")), sig2(d.get("tolerance")),
                     _text(d.get("at (input)")), _text(d.get("note"))])
    head = ["case", "engine", "verdict", "worst quantity", "error/peak", "tol", "at", "note"]
    # engine: "mujoco_warp (float32)" fits; verdict: "precision limit (float32)" too
    fixed = [None, 21, 25, 16, 10, 5, 12, None]
    for i, f in enumerate(fixed):
        if f is not None:
            fixed[i] = max(len(head[i]), min(f, max(len(r[i]) for r in rows)))
    case_w = max(len(head[0]), min(max(len(r[0]) for r in rows), 24))
    used = case_w + sum(fixed[1:7]) + 7 * 2
    note_w = max(0, width - used - 2)
    has_note = any(r[7] for r in rows)
    widths = [case_w, *fixed[1:7], note_w]
    ncol = 8 if has_note and note_w >= 8 else 7

    def line(cells):
        out = []
        for i in range(ncol):
            c = _short(cells[i], widths[i])
            out.append(c.rjust(widths[i]) if i in (4, 5) else c.ljust(widths[i]))
        return "  ".join(out).rstrip()[:width]

    return [line(head)] + [line(r) for r in rows]


def failure_notes(summary: pd.DataFrame, width: int = WIDTH) -> list[str]:
    """Each failed row's note in full, wrapped to ``width``."""
    out = []
    for d in summary.to_dict("records"):
        if d.get("verdict") != "pass" and _text(d.get("note")):
            out += textwrap.wrap(f"{d['case']} / {d['engine']}: {_text(d['note'])}", width,
                                 subsequent_indent="    ")
    return out


def print_verdict(summary: pd.DataFrame, echo=print) -> None:
    for ln in verdict_table(summary) + failure_notes(summary):
        echo(ln)
    echo(counts_line(summary))


def free_counts_line(free: pd.DataFrame) -> str:
    """The free-motion verdicts (``free_verdicts.csv``) in one line: ``free motion: N of
    M pass (engine k/n, ...), F failed, K known engine limits (engine case, ...)``."""
    if not len(free):
        return "free motion: no verdicts"
    v = free["verdict"].astype(str)
    eng = free["engine"].fillna("").astype(str)
    per = ", ".join(f"{e} {int(((v == 'pass') & (eng == e)).sum())}/{int((eng == e).sum())}"
                    for e in dict.fromkeys(eng) if e)
    known = free[v == "known limit"]
    line = (f"free motion: {int((v == 'pass').sum())} of {len(free)} pass"
            + (f" ({per})" if per else "") + f", {int((v == 'FAIL').sum())} failed")
    if len(known):
        line += (f", {len(known)} known engine limit{'s' if len(known) > 1 else ''} ("
                 + ", ".join(f"{r.engine} {r.case}" for r in known.itertuples()) + ")")
    return line


def free_failure_lines(free: pd.DataFrame, width: int = WIDTH) -> list[str]:
    """Each failed or known-limit free verdict in full: case / engine, verdict, worst
    quantity and error, trusted horizon, and its note or why the run stopped."""
    out = []
    for d in free.to_dict("records"):
        if d.get("verdict") == "pass":
            continue
        what = (f"{d['case']} / {_text(d.get('engine')) or '-'}: {d['verdict']}")
        if _text(d.get("worst quantity")):
            what += (f", {d['worst quantity']} {sig2(d.get('worst error / scale'))} of "
                     f"its scale, trusted {_text(d.get('trusted horizon'))}")
        run = _text(d.get("run"))
        if run and run != "ok":
            what += f"; {run}"
        if _text(d.get("note")):
            what += f"; {d['note']}"
        out += textwrap.wrap(what, width, subsequent_indent="    ")
    return out


__all__ = ["WIDTH", "counts_line", "failure_notes", "free_counts_line", "free_failure_lines",
           "margin_rows", "print_verdict", "sig2", "verdict_table"]
