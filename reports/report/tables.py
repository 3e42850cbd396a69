"""The report's tables, from the task results (pandas DataFrames).

The frames written to CSV keep their machine column names (the maintainer script
``scripts/readme_figures.py`` reads them); :func:`for_reading` makes the versions shown on
the page: units in every header, the input position with its unit, verdicts as
``pass``/``FAIL``.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from analytic import Linkage, load_case
from analytic.input_display import convention_of, display_input, format_input
from analytic.mechanism import Revolute
from analytic.sweep import to_frame
from reports.comparison import quantities
from reports.comparison.compare import FAIL, PASS, comparison_frame, limit_word
from reports.comparison.quantities import base_quantity

# The notes' own figures (REFERENCE.md) for the seed comparison: (label, notes,
# SolidWorks in the notes, why the notes differ from the exact value)
SEED_ROWS = {
    "seed-slider-crank": [
        ("theta3 (deg)", "rod.angle_deg", -14.47, None, "notes round theta3 to 345.5 deg"),
        ("slider position AC (m)", "slide.s", 0.280, None, "notes round to 28.0 cm"),
        ("omega3 (rad/s)", "rod.omega", -89.45, None, "rounded intermediates"),
        ("slider velocity (m/s)", "slide.v", -14.4793, None, "rounded theta3"),
        ("alpha3 (rad/s^2)", "rod.alpha", 8259.0, None,
         "computed with theta3 rounded to 345.5 deg"),
        ("slider acceleration (m/s^2)", "slide.a", -4599.776, None, "rounded theta3"),
        ("drive torque T (N m)", "drive.torque", 476.0, None,
         "graphical: 233 + 243 N m from lever arms measured on a drawing"),
        ("|force at B| (N)", "B.force", 16160.0, None,
         "graphical; a_B written with 0.2 m and I3 alpha3 with 0.2 (typos)"),
        ("|force at C| (N)", "C.force", 3359.0, None, "sub-problem A alone, graphical"),
    ],
    "seed-four-bar": [
        ("theta3 (deg)", "coupler.angle_deg", 29.38, None, "rounded"),
        ("omega3 (rad/s)", "coupler.omega", -3.916, None, "rounded"),
        ("omega4 (rad/s)", "rocker.omega", 3.091, None, "rounded"),
        ("alpha3 (rad/s^2)", "coupler.alpha", 42.27, 42.266,
         "SolidWorks 2421.706 deg/s^2: its own integration error"),
        ("alpha4 (rad/s^2)", "rocker.alpha", 95.5, 95.503,
         "SolidWorks 5471.96 deg/s^2: its own integration error"),
        ("drive torque T2 (N m)", "drive.torque", None, None,
         "the notes give no masses; uniform rods 0.2/0.6/0.5 kg chosen here"),
    ],
}


def _failed_run_row(case, engine, reason, at=np.nan, settings=""):
    return {"case": case, "engine": engine, "quantity": "(run)", "max_abs": np.nan,
            "peak": np.nan, "normalised": np.inf, "at": at, "tolerance": np.nan,
            "passed": False, "engine_reading": False, "run_ok": False,
            "run_reason": reason, "settings": settings, "verdict": FAIL}


def verdict_table(results: list[dict]) -> pd.DataFrame:
    """Case x engine x quantity rows; a failed or missing engine is one failed row."""
    frames = []
    for res in results:
        r = res["run"]
        if r is None:
            frames.append(pd.DataFrame([_failed_run_row(res["case"], res["engine"],
                                                        res["error"])]))
            continue
        df = comparison_frame(r, res["comparisons"]).assign(case=res["case"])
        if not r.ok:
            at = failed_at(r)
            df = pd.concat([pd.DataFrame([_failed_run_row(res["case"], res["engine"],
                                                          r.reason, at, r.settings_text)]),
                            df])
        frames.append(df)
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


def failed_at(run_) -> float:
    """Where a failed run stopped, in the one display convention of an input (deg, a
    full turn wrapped to [0, 360), or m: :mod:`analytic.input_display`); NaN if unknown."""
    if run_.fail_value is None or not math.isfinite(run_.fail_value):
        return np.nan
    return display_input(run_.fail_value, convention_of(run_.linkage))


def input_unit(mech) -> str:
    return "deg" if isinstance(mech.driver_joint, Revolute) else "m"


def summary_table(verdicts: pd.DataFrame, units: dict[str, str] | None = None
                  ) -> pd.DataFrame:
    """One row per case and engine: worst judged quantity and the verdict.  ``units``:
    case -> input unit (deg or m) for the ``at (input)`` text."""
    rows = []
    for (case, engine), g in verdicts.groupby(["case", "engine"], sort=False):
        judged = g[~g["engine_reading"].astype(bool)]
        worst = judged.loc[judged["normalised"].astype(float).idxmax()] if len(judged) else None
        words = _row_verdicts(judged)
        ok = all(w != FAIL for w in words) and bool(g["run_ok"].all())
        limits = [w for w in words if w.startswith(LIMIT_PREFIX)]
        at = float(worst["at"]) if worst is not None else np.nan
        unit = (units or {}).get(case, "")
        rows.append({"case": case, "engine": engine,
                     "verdict": (limits[0] if limits else PASS) if ok else FAIL,
                     "worst quantity": worst["quantity"] if worst is not None else "",
                     "worst error / peak": float(worst["normalised"]) if worst is not None
                     else np.nan,
                     "at (deg or m)": at,
                     "at (input)": format_input(at, unit).strip(),
                     "tolerance": float(worst["tolerance"]) if worst is not None else np.nan,
                     "precision": _precision(g),
                     "note": "" if g["run_ok"].all() else str(g["run_reason"].iloc[0])})
        if ok and limits:
            rows[-1]["note"] = limit_note(judged)
    return pd.DataFrame(rows)


#: How a precision-limit verdict starts (:func:`reports.comparison.compare.limit_word`).
LIMIT_PREFIX = limit_word("")[:-2]


def _row_verdicts(judged: pd.DataFrame) -> list[str]:
    """Each judged row's verdict word ("pass", "precision limit (...)", "FAIL"); a frame
    without the ``verdict`` column (an older CSV) from ``passed``."""
    if "verdict" in judged and judged["verdict"].notna().all():
        return [str(w) for w in judged["verdict"]]
    return [PASS if p else FAIL for p in judged["passed"].astype(bool)]


def limit_note(judged: pd.DataFrame) -> str:
    """A precision-limit verdict's note: the worst such quantity, its error and floor."""
    lim = judged[[str(w).startswith(LIMIT_PREFIX) for w in _row_verdicts(judged)]]
    w = lim.loc[lim["normalised"].astype(float).idxmax()]
    return (f"{w['quantity']} {float(w['normalised']):.2g} of peak is over the tolerance "
            f"but within the engine's {w.get('precision', '')} floor {float(w['floor']):.2g} "
            "(sim_models.runs.precision): a precision limit of the engine, not a harness failure")


def accepted(summary: pd.DataFrame) -> pd.Series:
    """Per summary row: not a failed verdict (a pass or a precision limit), what the exit
    status counts."""
    return summary["verdict"].astype(str) != FAIL


def _precision(g: pd.DataFrame) -> str:
    """The engine's arithmetic (``float32`` / ``float64``) of a case x engine group."""
    if "precision" not in g or not g["precision"].notna().any():
        return "float64"
    return str(g["precision"].dropna().iloc[0])


def quantity_unit(quantity: str, revolute: bool) -> str:
    """SI unit of a verdict quantity's absolute error and peak."""
    q = base_quantity(quantity)
    if q.endswith(".alpha"):
        return "rad/s^2"
    if q.endswith(".a"):
        return "m/s^2"
    if q.startswith("drive.effort"):
        return "N m" if revolute else "N"
    if q.endswith((".force", ".normal")):
        return "N"
    if q.endswith(".moment"):
        return "N m"
    return ""


def instantaneous_floors(results: list[dict], units: dict[str, str] | None = None
                         ) -> pd.DataFrame:
    """MuJoCo mj_forward at the analytic state: the regularisation floor per case and
    variant (stock, stock + DIAGEXACT, this project's scaled inverse weights)."""
    rows = []
    for res in results:
        if res["mode"] != "instantaneous":
            continue
        variant = res["overrides"].get("_label", "")
        judged = quantities.judged(res["comparisons"])
        unit = (units or {}).get(res["case"], "")
        if res["run"] is None or not judged:
            rows.append({"case": res["case"], "variant": variant, "floor (-)": np.inf,
                         "worst quantity": res["error"] or "", "at (input)": ""})
            continue
        w = max(judged, key=lambda c: c.normalised)
        rows.append({"case": res["case"], "variant": variant, "floor (-)": w.normalised,
                     "worst quantity": w.quantity, "at (input)": format_input(w.at, unit)})
    return pd.DataFrame(rows)


def seed_comparison(results: list[dict], engines) -> pd.DataFrame:
    """The notes' numbers, SolidWorks', the exact ones and each engine's, side by side,
    at the seed angle (the first sample of every run is the reference input), for the
    seed cases among the results."""
    present = {r["case"] for r in results}
    rows = []
    for case, spec in SEED_ROWS.items():
        if case not in present:
            continue
        lk = Linkage(load_case(case))
        kin = lk.kinematics()
        exact = to_frame(lk, kin, lk.forces(kin) if lk.mech.has_mass else None).iloc[0]
        eng = {res["engine"]: res["run"].frame().iloc[0] for res in results
               if res["case"] == case and res["mode"] == "run" and res["run"] is not None}
        for label, col, notes, sw, why in spec:
            row = {"case": case, "quantity": label, "notes": notes, "SolidWorks (notes)": sw,
                   "exact (analytic)": _seed_value(exact, col)}
            for e in engines:
                row[e] = _seed_value(eng.get(e), col)
            row["why the notes differ"] = why
            rows.append(row)
    return pd.DataFrame(rows)


def _seed_value(frame, col):
    if frame is None:
        return np.nan
    if col.endswith(".force"):
        j = col[:-6]
        if f"{j}.fx" in frame:
            return float(math.hypot(frame[f"{j}.fx"], frame[f"{j}.fy"]))
        return np.nan
    return float(frame[col]) if col in frame else np.nan


# ----------------------------------------------------------------------------- for reading
def summary_for_reading(summary: pd.DataFrame) -> pd.DataFrame:
    cols = {"case": "case", "engine": "engine", "verdict": "verdict",
            "worst quantity": "worst quantity", "worst error / peak": "worst error / peak (-)",
            "tolerance": "tolerance (-)", "at (input)": "at input", "note": "note"}
    df = summary[[c for c in cols if c in summary]].rename(columns=cols)
    err = pd.to_numeric(summary["worst error / peak"], errors="coerce")
    tol = pd.to_numeric(summary["tolerance"], errors="coerce")
    df.insert(6, "error / tolerance (-)", err / tol)
    return df


def verdicts_for_reading(verdicts: pd.DataFrame, revolute: dict[str, bool]) -> pd.DataFrame:
    v = verdicts
    unit = [quantity_unit(q, revolute.get(c, True)) for q, c in zip(v["quantity"], v["case"],
                                                                   strict=True)]
    at_unit = ["deg" if revolute.get(c, True) else "m" for c in v["case"]]
    return pd.DataFrame({
        "case": v["case"], "engine": v["engine"], "quantity": v["quantity"], "unit": unit,
        "max |error| (unit)": v["max_abs"], "peak (unit)": v["peak"],
        "error / peak (-)": v["normalised"], "tolerance (-)": v["tolerance"],
        "at input": [format_input(a, u) for a, u in
                     zip(v["at"].astype(float), at_unit, strict=True)],
        "verdict": ["not judged" if r else w for w, r in
                    zip(_row_verdicts(v), v["engine_reading"], strict=True)],
        "run finished": v["run_ok"], "why the run stopped": v["run_reason"]})


__all__ = ["LIMIT_PREFIX", "SEED_ROWS", "accepted", "failed_at", "input_unit",
           "instantaneous_floors", "limit_note", "quantity_unit",
           "seed_comparison", "summary_for_reading", "summary_table", "verdict_table",
           "verdicts_for_reading"]
