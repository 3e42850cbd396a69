"""The validation report: ``xval report [--out DIR] [--quick] [--cases ...]``.

Runs every built-in case through the analytic solver and both engines (at the
recommended settings), compares them with the one comparison helper
(:func:`reports.compare.compare_run`), adds the studies of
:mod:`reports.studies` (speed against error, hard cases, scene economy), and writes
``index.html`` (plots embedded), ``report.md`` (with the plots as PNG files beside
it) and one CSV per table into the output directory.  Every number in the report
comes from the run that wrote it.

The (case x engine x setting) tasks are independent: they run on a local process
pool, or on an existing Dask distributed scheduler with ``--dask ADDRESS``.  A task
that fails (an engine that diverges, is missing, or raises) becomes a failed row of
the verdict table; the report is still written.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import math
import os
import platform
import re
import time
import traceback
from concurrent.futures import Executor, ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

ENGINES = ("mujoco", "pybullet")
DEFAULT_OUT = Path(__file__).parent / "out"

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


@dataclass(frozen=True)
class ReportConfig:
    """What a report run does (``quick`` shrinks sample counts and study grids)."""

    out: Path
    quick: bool = False
    cases: tuple[str, ...] = ()
    engines: tuple[str, ...] = ENGINES
    revolutions: int = 2
    samples: int = 72
    studies: bool = True
    workers: int | None = None
    dask: str | None = None
    settings: dict = field(default_factory=dict)  # engine -> dict of setting overrides


# ----------------------------------------------------------------------------- tasks
def engine_task(case: str, engine: str, overrides: dict, revolutions: int, samples: int,
                mode: str = "run") -> dict:
    """One (case, engine) run and its comparisons; never raises (picklable result)."""
    t0 = time.perf_counter()
    try:
        from analytic import load_case
        from reports.verdict_runs import run_comparison
        from sim_models import compile_linkage, make_settings
        # the description is compiled once (Linkage + reference solution) and passed down
        tree = compile_linkage(load_case(case))
        settings = make_settings(engine, overrides)
        r, comps = run_comparison(tree, engine, settings, mode, revolutions, samples)
        return {"case": case, "engine": engine, "mode": mode, "overrides": overrides,
                "run": r, "comparisons": comps, "error": None,
                "seconds": time.perf_counter() - t0}
    except Exception as e:  # a report must survive any engine failure
        return {"case": case, "engine": engine, "mode": mode, "overrides": overrides,
                "run": None, "comparisons": [], "seconds": time.perf_counter() - t0,
                "error": f"{type(e).__name__}: {e}",
                "traceback": traceback.format_exc(limit=4)}


def make_executor(cfg: ReportConfig) -> Executor:
    """A process pool, or the executor of a Dask distributed client."""
    if cfg.dask:
        try:
            from distributed import Client
        except ImportError:
            from analytic import LinkageError
            raise LinkageError("--dask needs the 'distributed' package "
                               "(pip install 'dask[distributed]')") from None
        try:
            client = Client(cfg.dask)
        except OSError as e:  # no scheduler there: a user error, one line
            from analytic import LinkageError
            raise LinkageError(f"--dask: cannot reach a scheduler at {cfg.dask!r}: {e}") from None
        ex = client.get_executor()
        ex.client_to_close = client
        return ex
    return ProcessPoolExecutor(max_workers=cfg.workers or os.cpu_count() or 2)


# ----------------------------------------------------------------------------- metadata
def metadata(cfg: ReportConfig) -> dict:
    from importlib.metadata import PackageNotFoundError, version
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    vers = {}
    for pkg in ("numpy", "pandas", "mujoco", "pybullet", "matplotlib", "linkage-xval"):
        try:
            vers[pkg] = version(pkg)
        except PackageNotFoundError:
            vers[pkg] = "not installed"
    return {"date": _dt.datetime.now().isoformat(timespec="seconds"), "cpu": cpu,
            "cores": os.cpu_count(), "python": platform.python_version(),
            "platform": platform.platform(), **vers,
            "mode": "quick" if cfg.quick else "full", "samples": cfg.samples,
            "revolutions": cfg.revolutions, "executor": f"dask {cfg.dask}" if cfg.dask
            else f"process pool ({cfg.workers or os.cpu_count()} workers)"}


# ----------------------------------------------------------------------------- sections
def verdict_table(results: list[dict]) -> pd.DataFrame:
    """Case x engine x quantity rows; a failed or missing engine is one failed row."""
    from reports.compare import comparison_frame
    frames = []
    for res in results:
        r = res["run"]
        if r is None:
            frames.append(pd.DataFrame([{
                "case": res["case"], "engine": res["engine"], "quantity": "(run)",
                "max_abs": np.nan, "peak": np.nan, "normalised": np.inf, "at": np.nan,
                "tolerance": np.nan, "passed": False, "engine_reading": False,
                "run_ok": False, "run_reason": res["error"], "settings": ""}]))
            continue
        df = comparison_frame(r, res["comparisons"])
        if not r.ok:
            df = pd.concat([pd.DataFrame([{
                "case": res["case"], "engine": res["engine"], "quantity": "(run)",
                "max_abs": np.nan, "peak": np.nan, "normalised": np.inf,
                "at": math.degrees(r.fail_value) if r.fail_value is not None else np.nan,
                "tolerance": np.nan, "passed": False, "engine_reading": False,
                "run_ok": False, "run_reason": r.reason, "settings": r.settings_text}]), df])
        frames.append(df)
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


def summary_table(verdicts: pd.DataFrame) -> pd.DataFrame:
    """One row per case and engine: worst judged quantity and the verdict."""
    rows = []
    for (case, engine), g in verdicts.groupby(["case", "engine"], sort=False):
        judged = g[~g["engine_reading"]]
        worst = judged.loc[judged["normalised"].astype(float).idxmax()] if len(judged) else None
        ok = bool(judged["passed"].all()) and bool(g["run_ok"].all())
        rows.append({"case": case, "engine": engine,
                     "verdict": "pass" if ok else "FAIL",
                     "worst quantity": worst["quantity"] if worst is not None else "",
                     "worst error / peak": float(worst["normalised"]) if worst is not None
                     else np.nan,
                     "at (deg or m)": float(worst["at"]) if worst is not None else np.nan,
                     "tolerance": float(worst["tolerance"]) if worst is not None else np.nan,
                     "note": "" if g["run_ok"].all() else str(g["run_reason"].iloc[0])})
    return pd.DataFrame(rows)


def instantaneous_floors(results: list[dict]) -> pd.DataFrame:
    """MuJoCo mj_forward at the analytic state: the regularisation floor per case and
    variant (stock, stock + DIAGEXACT, this project's scaled inverse weights)."""
    rows = []
    for res in results:
        if res["mode"] != "instantaneous":
            continue
        variant = res["overrides"].get("_label", "")
        judged = [c for c in res["comparisons"] if not c.quantity.endswith("[engine]")]
        if res["run"] is None or not judged:
            rows.append({"case": res["case"], "variant": variant, "floor": np.inf,
                         "worst quantity": res["error"] or "", "at (deg)": np.nan})
            continue
        w = max(judged, key=lambda c: c.normalised)
        rows.append({"case": res["case"], "variant": variant, "floor": w.normalised,
                     "worst quantity": w.quantity, "at (deg)": w.at})
    return pd.DataFrame(rows)


def seed_comparison(results: list[dict]) -> pd.DataFrame:
    """The notes' numbers, SolidWorks', the exact ones and each engine's, side by side,
    at the seed angle (the first sample of every run is the reference input)."""
    from analytic import Linkage, load_case
    from analytic.sweep import to_frame
    rows = []
    for case, spec in SEED_ROWS.items():
        lk = Linkage(load_case(case))
        kin = lk.kinematics()
        exact = to_frame(lk, kin, lk.forces(kin) if lk.mech.has_mass else None).iloc[0]
        eng = {}
        for res in results:
            if res["case"] == case and res["mode"] == "run" and res["run"] is not None:
                eng[res["engine"]] = res["run"].frame().iloc[0]
        for label, col, notes, sw, why in spec:
            def get(frame, col=col):
                if frame is None:
                    return np.nan
                if col.endswith(".force"):
                    j = col[:-6]
                    if f"{j}.fx" in frame:
                        return float(math.hypot(frame[f"{j}.fx"], frame[f"{j}.fy"]))
                    return np.nan
                return float(frame[col]) if col in frame else np.nan
            row = {"case": case, "quantity": label, "notes": notes, "SolidWorks (notes)": sw,
                   "exact (analytic)": get(exact)}
            for e in ENGINES:
                row[e] = get(eng.get(e))
            row["why the notes differ"] = why
            rows.append(row)
    return pd.DataFrame(rows)


# ----------------------------------------------------------------------------- figures
def case_figures(case: str, results: list[dict]) -> dict[str, bytes]:
    """Drawing, full-cycle curves (analytic line, engines' samples) and error plots."""
    from analytic import Linkage, load_case
    from reports import plots
    from reports.compare import analytic_at
    mech = load_case(case)
    lk = Linkage(mech)
    res = lk.sweep(360)
    kin, frc = res.kinematics, res.forces
    rev = lk.driver_is_revolute
    x = np.degrees(kin.value) if rev else kin.value
    xl = "input (deg)" if rev else "input (m)"
    figs = {}
    v0 = mech.driver.value
    span = (np.linspace(0, 2 * math.pi, 4, endpoint=False) if res.full_cycle else
            np.linspace(0, 1, 4) * (kin.value[-1] - kin.value[0]) + kin.value[0] - v0)
    figs["linkage"] = plots.draw_linkage(lk, v0 + span, f"{case} at four inputs")
    runs = {r["engine"]: r["run"] for r in results
            if r["case"] == case and r["mode"] == "run" and r["run"] is not None}
    moving = [b for b in range(len(mech.bodies)) if b != lk.topo.ground]

    def engine_x(r):
        return np.degrees(r.values) if rev else r.values

    for what, arr, unit in (("angle", np.degrees(kin.theta), "deg"),
                            ("omega", kin.omega, "rad/s"), ("alpha", kin.alpha, "rad/s^2")):
        series = {}
        for b in moving:
            name = mech.bodies[b].name
            s = {"analytic": arr[:, b]}
            for e, r in runs.items():
                val = {"angle": np.degrees(r.theta[:, b]) if r.theta is not None else None,
                       "omega": r.omega[:, b], "alpha": r.alpha[:, b]}[what]
                if val is not None:
                    s[e] = _align(x, engine_x(r), val)
            series[name] = s
        figs[f"{what}"] = plots.cycle_plot(x, series, f"{what} ({unit})",
                                           f"{case}: body {what}", xl)
    if lk.topo.prismatic:
        series = {}
        for j in lk.topo.prismatic:
            jn = lk.topo.joint_names[j]
            s = {"analytic": kin.slider(jn)[2]}
            for e, r in runs.items():
                s[e] = _align(x, engine_x(r), r.slider_acc[:, r.prismatic_names.index(jn)])
            series[jn] = s
        figs["slider"] = plots.cycle_plot(x, series, "s'' (m/s^2)",
                                          f"{case}: slider accelerations", xl)
    if frc is not None:
        series = {"drive": {"analytic": frc.effort,
                            **{e: _align(x, engine_x(r), r.drive_effort)
                               for e, r in runs.items()}}}
        figs["drive"] = plots.cycle_plot(x, series, "N m" if rev else "N",
                                         f"{case}: drive effort", xl)
        series = {}
        for jt in mech.joints:
            s = {"analytic": np.linalg.norm(frc.joint_force[jt.name], axis=1)}
            for e, r in runs.items():
                k = r.joint_names.index(jt.name)
                s[e] = _align(x, engine_x(r), np.linalg.norm(r.joint_force[:, k], axis=1))
            series[jt.name] = s
        figs["forces"] = plots.cycle_plot(x, series, "|F| (N)",
                                          f"{case}: joint force magnitudes", xl)
    # error against input, with the transmission angle (or Jacobian condition); samples a
    # limited-range run did not reach are NaN and stay gaps in the plot
    for e, r in runs.items():
        if not np.isfinite(r.alpha).any():
            continue
        _, kin_e, frc_e = analytic_at(r, mech)
        xe = engine_x(r)
        errs = {}
        pk = np.nanmax(np.abs(kin_e.alpha[:, moving])) or 1.0
        errs["alpha (max body)"] = np.max(np.abs(r.alpha[:, moving] - kin_e.alpha[:, moving]),
                                          axis=1) / pk
        if frc_e is not None and r.has_forces:
            pk = np.nanmax(np.abs(frc_e.effort)) or 1.0
            errs["drive effort"] = np.abs(r.drive_effort - frc_e.effort) / pk
            worst = np.zeros(len(xe))
            for jt in mech.joints:
                k = r.joint_names.index(jt.name)
                ref = frc_e.joint_force[jt.name]
                pkj = np.nanmax(np.linalg.norm(ref, axis=1)) or 1.0
                worst = np.fmax(worst, np.linalg.norm(r.joint_force[:, k] - ref, axis=1) / pkj)
            errs["joint forces (max)"] = worst
        if kin_e.transmission:
            name, tr = next(iter(kin_e.transmission.items()))
            twin = (f"transmission angle at {name} (deg)", tr)
        else:
            twin = ("loop Jacobian condition", kin_e.condition)
        order = np.argsort(xe)
        figs[f"error-{e}"] = plots.error_plot(
            xe[order], {k: v[order] for k, v in errs.items()},
            (twin[0], twin[1][order]), f"{case}: {e} error against input", xl)
    return figs


def _align(x, xe, ye):
    """Engine samples on the analytic axis: NaN except at the nearest analytic point."""
    out = np.full(len(x), np.nan)
    ok = np.isfinite(ye)
    if not ok.any():
        return out
    period = 360.0 if len(x) > 1 and np.isclose(x[-1] - x[0] + (x[1] - x[0]), 360.0) else None
    for xv, yv in zip(xe[ok], ye[ok], strict=True):
        d = np.abs(x - xv)
        if period:
            d = np.minimum(d, period - np.mod(d, period))
        k = int(np.argmin(d))
        out[k] = yv
    return out


# ----------------------------------------------------------------------------- rendering
_MD_SPECIAL = re.compile(r"([\\`*_\[\]<>|#~!&])")
_MD_LINE_START = re.compile(r"^(\s*|\s*\d+)([-+=]|(?<=\d)[.)])")


def md_escape(text, block: bool = False) -> str:
    """Text as literal Markdown, as ``html.escape`` makes it literal HTML: the
    characters that start emphasis, code, links, tags, entities or table cells are
    backslash-escaped, and newlines (which would end a table row) become spaces.
    For a paragraph (``block``), a line-start list marker is escaped too."""
    s = _MD_SPECIAL.sub(r"\\\1", str(text).replace("\r", " ").replace("\n", " "))
    return _MD_LINE_START.sub(lambda m: m.group(1) + "\\" + m.group(2), s) if block else s


def file_stem(name: str) -> str:
    """A file-name-safe stem for ``name`` (a case may be a path such as sub/f.toml)."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("._") or "x"


class Document:
    """Collects sections; renders self-contained HTML and Markdown with PNG files."""

    def __init__(self, out: Path):
        self.out = out
        self.parts: list[tuple[str, object]] = []
        self.nimg = 0

    def h(self, level: int, text: str):
        self.parts.append(("h", (level, text)))

    def p(self, text: str):
        self.parts.append(("p", text))

    def table(self, df: pd.DataFrame, name: str, caption: str = "", max_rows: int = 80,
              columns: list[str] | None = None, digits: int = 4):
        """Write the whole table as CSV; show it inline (only ``columns``, numbers to
        ``digits`` significant figures) unless it is longer than ``max_rows`` (a
        per-revolution log), in which case the document links the CSV only."""
        df.to_csv(self.out / f"{name}.csv", index=False)
        if len(df) > max_rows:
            self.parts.append(("p", f"{caption or name}: {len(df)} rows, in {name}.csv"))
            return
        shown = df[[c for c in columns if c in df.columns]] if columns else df
        self.parts.append(("table", (shown, name, caption, digits)))

    def image(self, png: bytes, name: str, caption: str = ""):
        (self.out / "img").mkdir(exist_ok=True)
        (self.out / "img" / f"{file_stem(name)}.png").write_bytes(png)
        self.parts.append(("img", (png, name, caption)))

    @staticmethod
    def _fmt(v, digits: int = 4):
        if isinstance(v, float | np.floating):
            if not np.isfinite(v):
                return "inf" if v == np.inf else ("" if np.isnan(v) else str(v))
            return f"{v:.{digits}g}"
        return str(v)

    def html(self, title: str) -> str:
        out = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}"
               "</title><style>body{font-family:sans-serif;max-width:1100px;margin:auto}"
               "table{border-collapse:collapse;font-size:12px;margin:8px 0}"
               "td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}"
               "td:first-child,th:first-child{text-align:left}.FAIL,.False{color:#b00;"
               "font-weight:bold}img{max-width:100%}figure{display:inline-block;margin:4px}"
               "</style></head><body>"]
        for kind, data in self.parts:
            if kind == "h":
                lv, text = data
                out.append(f"<h{lv}>{html.escape(text)}</h{lv}>")
            elif kind == "p":
                out.append(f"<p>{html.escape(data)}</p>")
            elif kind == "table":
                df, name, cap, digits = data
                head = "".join(f"<th>{html.escape(str(c))}</th>" for c in df.columns)
                body = []
                for _, row in df.iterrows():
                    cells = []
                    for v in row:
                        s = self._fmt(v, digits)
                        cells.append(f"<td class='{html.escape(s)}'>{html.escape(s)}</td>")
                    body.append("<tr>" + "".join(cells) + "</tr>")
                cap_html = f"<caption>{html.escape(cap)}</caption>" if cap else ""
                out.append(f"<table id='{name}'>{cap_html}<tr>{head}</tr>{''.join(body)}"
                           f"</table><p><a href='{name}.csv'>{name}.csv</a></p>")
            elif kind == "img":
                png, name, cap = data
                b64 = base64.b64encode(png).decode()
                out.append(f"<figure><img alt='{html.escape(name)}' "
                           f"src='data:image/png;base64,{b64}'><figcaption>"
                           f"{html.escape(cap)}</figcaption></figure>")
        out.append("</body></html>")
        return "\n".join(out)

    def markdown(self, title: str) -> str:
        out = [f"# {title}", ""]
        for kind, data in self.parts:
            if kind == "h":
                lv, text = data
                out += ["#" * (lv + 1) + " " + md_escape(text), ""]
            elif kind == "p":
                out += [md_escape(data, block=True), ""]
            elif kind == "table":
                df, name, cap, digits = data
                if cap:
                    out += [f"*{md_escape(cap)}*", ""]
                out.append("| " + " | ".join(md_escape(c) for c in df.columns) + " |")
                out.append("|" + "---|" * len(df.columns))
                for _, row in df.iterrows():
                    out.append("| " + " | ".join(md_escape(self._fmt(v, digits))
                                                 for v in row) + " |")
                out += ["", f"([{md_escape(name)}.csv]({name}.csv))", ""]
            elif kind == "img":
                _, name, cap = data
                out += [f"![{md_escape(cap)}](img/{file_stem(name)}.png)", ""]
        return "\n".join(out)


# ----------------------------------------------------------------------------- main job
INSTANT_VARIANTS = {
    "stock MuJoCo": {"invweight_scale": 1.0, "diagexact": False},
    "stock + DIAGEXACT": {"invweight_scale": 1.0, "diagexact": True},
    "this project (invweight x 1e-3)": {},
}


def build_report(cfg: ReportConfig, progress=None) -> Path:
    """Run everything and write the report; returns the output directory."""
    from analytic import case_names
    t_start = time.perf_counter()
    out = Path(cfg.out)
    out.mkdir(parents=True, exist_ok=True)
    cases = list(cfg.cases or case_names())
    meta = metadata(cfg)

    tasks = []
    for case in cases:
        for eng in cfg.engines:
            tasks.append((case, eng, dict(cfg.settings.get(eng, {})), cfg.revolutions,
                          cfg.samples, "run"))
        if "mujoco" in cfg.engines:
            for label, ov in INSTANT_VARIANTS.items():
                over = {**ov, **cfg.settings.get("mujoco", {})}
                tasks.append((case, "mujoco", over | {"_label": label}, 1,
                              max(cfg.samples // 2, 12), "instantaneous"))
    results = []
    ex = make_executor(cfg)
    try:
        futs = [ex.submit(_task_entry, *t) for t in tasks]
        study_futs = {}
        if cfg.studies:
            study_futs = _submit_studies(cfg, ex, cases)
        for f in futs:
            results.append(f.result())
            if progress:
                progress("engine runs", len(results), len(futs))
        studies = {k: _result_or_error(f) for k, f in study_futs.items()}
    finally:
        ex.shutdown()
        if hasattr(ex, "client_to_close"):
            ex.client_to_close.close()
    if progress:
        progress("figures", 0, 1)

    doc = Document(out)
    verdicts = verdict_table([r for r in results if r["mode"] == "run"])
    summary = summary_table(verdicts) if len(verdicts) else pd.DataFrame()
    doc.h(1, "Verdict")
    n_fail = int((summary["verdict"] != "pass").sum()) if len(summary) else 0
    doc.p(f"{len(summary)} case x engine runs, {n_fail} failing. Engines run at the "
          f"recommended settings for {cfg.revolutions} revolutions, the last sampled at "
          f"{cfg.samples} inputs; errors are the largest |engine - analytic| normalised by "
          "the quantity's peak over the cycle. Rows marked [engine] in the full table are "
          "the engines' own readings (PyBullet's jointReactionForces and motor torque), "
          "reported but not judged: the judged forces are reconstructed by Newton-Euler "
          "from the engine's motion.")
    doc.table(summary, "verdict_summary", "case x engine: worst judged quantity")
    doc.table(verdicts, "verdicts", "case x engine x quantity")
    settings_rows = [{"engine": r["engine"], "settings": r["run"].settings_text}
                     for r in results if r["mode"] == "run" and r["run"] is not None]
    doc.table(pd.DataFrame(settings_rows).drop_duplicates("engine"), "engine_settings",
              "engine settings used for the verdict runs")

    floors = instantaneous_floors(results)
    if len(floors):
        doc.h(1, "MuJoCo instantaneous mode: the regularisation floor")
        doc.p("mj_forward at the exact analytic state (positions and velocities) at every "
              "sampled input: only MuJoCo's constraint regularisation separates its "
              "accelerations and forces from the exact ones. Stock MuJoCo, stock with the "
              "mjENBL_DIAGEXACT flag, and this project's model (inverse weights scaled by "
              "1e-3 after compiling, see sim_models/mjcf.py).")
        doc.table(floors, "instantaneous_floors",
                  "largest error / peak over all judged quantities, and where it peaks")

    seeds = seed_comparison(results)
    doc.h(1, "Seed comparison (course notes)")
    doc.p("The notes' numbers, SolidWorks Motion's (where the notes give them), the exact "
          "analytic value and each engine's, at the notes' crank angle.")
    doc.table(seeds, "seed_comparison", digits=7)

    if cfg.studies:
        _render_studies(doc, studies, cases)

    doc.h(1, "Cases")
    for i, case in enumerate(cases):
        if progress:
            progress("figures", i, len(cases))
        doc.h(2, case)
        try:
            figs = case_figures(case, results)
        except Exception as e:  # a figure must not take the report down
            doc.p(f"figures failed: {type(e).__name__}: {e}")
            continue
        for name, png in figs.items():
            doc.image(png, f"{case}-{name}", f"{case}: {name}")

    if progress:
        progress("figures", len(cases), len(cases))
    meta["wall_seconds"] = round(time.perf_counter() - t_start, 1)
    doc.h(1, "Run")
    doc.table(pd.DataFrame([{"key": k, "value": str(v)} for k, v in meta.items()]),
              "run_metadata", "machine, versions, settings")
    title = f"linkage-xval validation report ({meta['mode']}, {meta['date']})"
    (out / "index.html").write_text(doc.html(title))
    (out / "report.md").write_text(doc.markdown(title))
    return out


def _task_entry(case, engine, overrides, revolutions, samples, mode):
    over = {k: v for k, v in overrides.items() if not k.startswith("_")}
    res = engine_task(case, engine, over, revolutions, samples, mode)
    res["overrides"] = overrides
    return res


def _result_or_error(fut):
    try:
        return fut.result()
    except Exception as e:
        return {"error": f"{type(e).__name__}: {e}"}


def _submit_studies(cfg: ReportConfig, ex: Executor, cases: list[str]) -> dict:
    try:
        from reports import studies  # noqa: F401
    except ImportError:
        return {}
    subs = {}
    for case in [c for c in ("seed-four-bar", "seed-slider-crank") if c in cases]:
        subs[f"grid:{case}"] = ex.submit(_study_grid, case, cfg.quick)
    subs["hard"] = ex.submit(_study_hard, cfg.quick)
    subs["scene"] = ex.submit(_study_scene, cfg.quick)
    return subs


def _study_grid(case, quick):
    from reports import studies
    grid = studies.speed_error_grid(case, quick)
    return {"grid": grid, "cheapest": studies.cheapest_settings(grid),
            "analytic_s_per_rev": studies.analytic_seconds_per_rev(case)}


def _study_hard(quick):
    from reports import studies
    return studies.hard_cases(quick)


def _study_scene(quick):
    from reports import studies
    return {"table": studies.scene_economy(quick)}


def _render_studies(doc: Document, studies: dict, cases) -> None:
    from reports import plots
    doc.h(1, "Speed against error")
    grids = {k.split(":", 1)[1]: v for k, v in studies.items() if k.startswith("grid:")}
    if not grids:
        doc.p("no speed-error study in this run")
    for case, res in grids.items():
        doc.h(2, case)
        if "error" in res and "grid" not in res:
            doc.p(f"study failed: {res['error']}")
            continue
        g = res["grid"]
        doc.table(g, f"speed_error_{case}", "each engine setting: wall-clock time per "
                  "simulated revolution against the largest normalised error (all columns, "
                  "with the full settings, in the CSV)",
                  columns=["engine", "label", "timestep", "steps_per_rev", "steps_per_second",
                           "seconds_per_rev", "accel_error", "force_error", "error",
                           "worst_quantity", "ok", "reason"])
        doc.table(res["cheapest"], f"cheapest_{case}",
                  "cheapest setting meeting each tolerance",
                  columns=["engine", "tolerance", "label", "steps_per_rev", "seconds_per_rev",
                           "error", "accel_error", "force_error"])
        rows = g.to_dict("records")
        doc.image(plots.pareto_plot(rows, f"{case}: speed against error",
                                    res["analytic_s_per_rev"]), f"pareto-{case}",
                  f"{case}: Pareto plot (vertical line: the analytic solver's time per "
                  "revolution of 3600 points)")
    doc.h(1, "Hard cases")
    hard = studies.get("hard", {})
    if "error" in hard and len(hard) == 1:
        doc.p(f"study failed: {hard['error']}")
    for key, val in hard.items():
        if isinstance(val, pd.DataFrame):
            doc.table(val, f"hard_{key}", key)
        elif isinstance(val, bytes | bytearray):
            doc.image(bytes(val), f"hard-{key}", key)
        elif isinstance(val, str):
            doc.p(f"{key}: {val}")
    doc.h(1, "Scene economy")
    scene = studies.get("scene", {})
    if "table" in scene:
        doc.table(scene["table"], "scene_economy",
                  "seed-four-bar in MuJoCo with and without unneeded scene parts")
    elif scene:
        doc.p(f"study failed: {scene.get('error')}")


def main(args) -> int:
    """``xval report`` entry point."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
    stamp = _dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    out = Path(args.out) if args.out else DEFAULT_OUT / stamp
    cfg = ReportConfig(out=out, quick=args.quick, cases=tuple(args.cases or ()),
                       samples=36 if args.quick else 72, workers=args.workers,
                       dask=args.dask)
    with Progress(TextColumn("{task.description}"), BarColumn(), TextColumn(
            "{task.completed}/{task.total}"), TimeElapsedColumn(), transient=False) as pg:
        ids = {}

        def progress(stage, done, total):
            if stage not in ids:
                ids[stage] = pg.add_task(stage, total=total)
            pg.update(ids[stage], completed=done, total=total)

        path = build_report(cfg, progress)
    summary = pd.read_csv(path / "verdict_summary.csv")
    print(summary.to_string(index=False))
    print(f"report: {path / 'index.html'}  ({path / 'report.md'})")
    return 0


__all__ = ["ReportConfig", "build_report", "engine_task", "main"]
