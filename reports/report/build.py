"""The validation report: ``xval report [--out DIR] [--quick] [--cases ...]``.

Runs every built-in case (or the ``--cases`` given: built-in names or the user's TOML
files, each named by its description's ``name``) through the analytic solver and every
registered engine at its recommended settings, compares them with the one comparison
helper (:func:`reports.comparison.compare.compare_run`, whose reference is
:func:`reports.comparison.reference.analytic_reference`; the case figures read the same
reference), adds the studies of :mod:`reports.studies.speed_accuracy` (speed against error on the
requested cases; hard cases and scene economy with the built-in set), and writes
``index.html`` (its first screen: what passed, what failed and why, one overview
figure), one page per case in ``cases/``, ``report.md``, the figures as PNG files in
``img/`` (which both the pages and the Markdown refer to) and one CSV per table, all
under the output directory and nowhere else (:mod:`reports.report.layout`).

Every task (engine runs, study runs, the figures of each case, the Pareto plots) runs on
one process pool, or on an existing Dask distributed scheduler with ``--dask ADDRESS``,
and the figures of a case are drawn as soon as its runs are in.  A task that fails (an
engine that diverges, is missing, or raises) becomes a failed row of the verdict table;
the report is still written.  The run times each phase and prints its wall time; it
exits with status 1 when any verdict fails (DEVELOPERS.md), 0 when all pass.
"""

from __future__ import annotations

import datetime as _dt
import os
import platform
import threading
import time
import traceback
from concurrent.futures import FIRST_COMPLETED, Executor, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import pandas as pd

from analytic import case_names, load_case
from analytic.tolerances import ENGINE_RELATIVE
from reports.comparison import runs as verdict_runs
from reports.figures.case_figures import render_case
from reports.figures.study_plots import pareto_frontier_plot
from reports.report import free_section as report_free
from reports.report import tune_section as report_tune
from reports.report.document import Document, file_stem, md_escape  # noqa: F401 - re-exported
from reports.report.layout import write_page
from reports.report.tables import (  # noqa: F401 - re-exported
    SEED_ROWS,
    input_unit,
    instantaneous_floors,
    seed_comparison,
    summary_table,
    verdict_table,
)
from reports.studies import speed_accuracy as S
from reports.studies import speed_accuracy as studies
from reports.studies.hard_cases import hard_cases
from reports.studies.scene import scene_economy, scene_figure
from reports.studies.scheduler import PriorityExecutor, dask_executor
from sim_models import compile_linkage, make_settings
from sim_models.engines.registry import available_engines
from sim_models.runs.engine_run import RunRequest

#: Where a report goes without --out: under the current folder (in the checkout, the
#: git-ignored reports/out/; never inside an installed package's folder).
DEFAULT_OUT = Path("reports") / "out"
#: Cases of the speed-against-error grid when no --cases are given.
GRID_CASES = {True: ("seed-slider-crank",),
              False: ("seed-four-bar", "seed-slider-crank", "near-toggle-four-bar")}
#: Samples per revolution of the verdict runs: the full report's own choice, and with
#: ``--quick`` the run default (:class:`sim_models.runs.engine_run.RunRequest`).
SAMPLES = {False: 72, True: RunRequest.samples}


@dataclass(frozen=True)
class ReportConfig:
    """What a report run does (``quick`` shrinks sample counts and study grids).
    ``engines`` empty: every registered engine whose library is installed."""

    out: Path
    quick: bool = False
    cases: tuple[str, ...] = ()
    engines: tuple[str, ...] = ()
    revolutions: int = RunRequest.revolutions
    samples: int = SAMPLES[False]
    studies: bool = True
    workers: int | None = None
    dask: str | None = None
    settings: dict = field(default_factory=dict)  # engine -> dict of setting overrides


def engines_of(cfg: ReportConfig) -> tuple[str, ...]:
    if cfg.engines:
        return tuple(cfg.engines)
    return tuple(available_engines())


# ----------------------------------------------------------------------------- tasks
def engine_task(case: str, engine: str, overrides: dict, revolutions: int, samples: int,
                mode: str = "run") -> dict:
    """One (case, engine) run and its comparisons; never raises (picklable result).
    ``case``: a built-in name or a TOML file."""
    t0 = time.perf_counter()
    try:
        # the description is compiled once (Linkage + reference solution) and passed down
        tree = compile_linkage(load_case(case))
        settings = make_settings(engine, overrides)
        r, comps = verdict_runs.run_comparison(tree, engine, settings, mode, revolutions, samples)
        return {"case": case, "engine": engine, "mode": mode, "overrides": overrides,
                "run": r, "comparisons": comps, "error": None,
                "seconds": time.perf_counter() - t0}
    except Exception as e:  # a report must survive any engine failure
        return {"case": case, "engine": engine, "mode": mode, "overrides": overrides,
                "run": None, "comparisons": [], "seconds": time.perf_counter() - t0,
                "error": f"{type(e).__name__}: {e}",
                "traceback": traceback.format_exc(limit=4)}


def _quiet_worker():
    """Pool-worker start: engine libraries' banners (``pybullet build time: ...``,
    printed from C to file descriptor 1) must not cut into the progress display."""
    try:
        fd = os.open(os.devnull, os.O_WRONLY)
        os.dup2(fd, 1)
        os.close(fd)
    except OSError:
        pass


def make_executor(cfg: ReportConfig) -> Executor:
    """A process pool (workers silenced on standard output), or the executor of a Dask
    distributed client."""
    if cfg.dask:
        return dask_executor(cfg.dask)
    return ProcessPoolExecutor(max_workers=cfg.workers or os.cpu_count() or 2,
                               initializer=_quiet_worker)


def _start_workers(pool, cfg: ReportConfig) -> None:
    """Start the pool's worker processes now, while this process has one thread: a
    process forked while another thread holds a lock (the import lock of the hard-case
    thread, say) inherits it locked and hangs."""
    if isinstance(pool, ProcessPoolExecutor):
        n = cfg.workers or os.cpu_count() or 2
        wait([pool.submit(os.getpid) for _ in range(n)])


def _task_entry(case, engine, overrides, revolutions, samples, mode):
    over = {k: v for k, v in overrides.items() if not k.startswith("_")}
    res = engine_task(case, engine, over, revolutions, samples, mode)
    res["overrides"] = overrides
    return res


def _figure_task(label: str, source: str, runs: dict, comparisons: dict,
                 tolerance: float) -> dict:
    """Every figure of one case (PNG bytes by name), drawn in a pool worker; never
    raises (a failure is ``{"error": ...}``)."""
    try:
        return render_case(label, runs, comparisons, load_case(source), tolerance)
    except Exception as e:  # noqa: BLE001 - a figure must not take the report down
        return {"error": f"{type(e).__name__}: {e}"}


def _pareto_task(grid: pd.DataFrame, label: str, source: str, samples: int) -> dict:
    """The speed-against-error plot of a grid and the analytic solver's time per
    revolution at the engines' sample count."""
    t_an = studies.analytic_seconds_per_rev(source, points=samples)
    mech = studies.load(source)
    unit = "rad/s" if input_unit(mech) == "deg" else "m/s"
    png = pareto_frontier_plot(grid, f"{label} (input {mech.driver.velocity:g} {unit}): "
                               "speed against error", t_an, analytic_points=samples)
    return {"png": png, "analytic_s_per_rev": t_an}


def _scene_task(quick: bool) -> dict:
    table = scene_economy(quick)
    return {"table": table, "png": scene_figure(table)}


# ----------------------------------------------------------------------------- metadata
#: Engines whose library's distribution has another name (PyPI ``pin`` installs the
#: ``pinocchio`` module; its cmeel layout hides the module from
#: ``importlib.metadata.packages_distributions``).
DISTRIBUTIONS = {"pinocchio": "pin"}


def metadata(cfg: ReportConfig, engines) -> dict:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    vers = {}
    for pkg in ("numpy", "pandas", "matplotlib", *engines, "linkage-xval"):
        try:
            vers[pkg] = version(DISTRIBUTIONS.get(pkg, pkg))
        except PackageNotFoundError:
            vers[pkg] = "not installed"
    try:
        load = "{:.2f} {:.2f} {:.2f}".format(*os.getloadavg())
    except OSError:
        load = ""
    return {"date": _dt.datetime.now().isoformat(timespec="seconds"), "cpu": cpu,
            "cores": os.cpu_count(), "load average at start (1, 5, 15 min)": load,
            "python": platform.python_version(), "platform": platform.platform(), **vers,
            "mode": "quick" if cfg.quick else "full", "samples": cfg.samples,
            "revolutions": cfg.revolutions, "executor": f"dask {cfg.dask}" if cfg.dask
            else f"process pool ({cfg.workers or os.cpu_count()} workers)"}


# ----------------------------------------------------------------------------- phases
class Phases:
    """Named phases of the run: start and end wall times, shown on the progress display
    as they advance (``progress(name, done, total)``)."""

    def __init__(self, progress=None):
        self.progress = progress
        self.t0 = time.perf_counter()
        self.start: dict[str, float] = {}
        self.end: dict[str, float] = {}
        self.count: dict[str, list[int]] = {}

    def add(self, name: str, total: int):
        self.start.setdefault(name, time.perf_counter())
        c = self.count.setdefault(name, [0, 0])
        c[1] += total
        self._show(name)

    def step(self, name: str, n: int = 1):
        c = self.count[name]
        c[0] += n
        if c[0] >= c[1]:
            self.end[name] = time.perf_counter()
        self._show(name)

    def _show(self, name):
        if self.progress:
            done, total = self.count[name]
            self.progress(name, done, total)

    def seconds(self) -> dict[str, float]:
        """Each phase's wall time, s (from its first task to its last result)."""
        now = time.perf_counter()
        return {k: round(self.end.get(k, now) - s, 1) for k, s in self.start.items()}


# ----------------------------------------------------------------------------- main job
INSTANT_VARIANTS = {
    "stock MuJoCo": {"invweight_scale": 1.0, "diagexact": False},
    "stock + DIAGEXACT": {"invweight_scale": 1.0, "diagexact": True},
    "this project (invweight x 1e-3)": {},
}


def resolve_cases(cfg: ReportConfig) -> list[tuple[str, str]]:
    """``(label, source)`` of each requested case: the label is the description's
    ``name`` (made unique), the source what :func:`analytic.load_case` reads."""
    out, seen = [], set()
    for src in (cfg.cases or case_names()):
        name = load_case(src).name
        label, k = name, 2
        while label in seen:
            label, k = f"{name} ({k})", k + 1
        seen.add(label)
        out.append((label, str(src)))
    return out


def _tasks(cfg: ReportConfig, cases, engines) -> list[tuple]:
    tasks = []
    for label, src in cases:
        for eng in engines:
            tasks.append((label, src, eng, dict(cfg.settings.get(eng, {})), cfg.revolutions,
                          cfg.samples, "run"))
        if "mujoco" in engines:
            for vl, ov in INSTANT_VARIANTS.items():
                over = {**ov, **cfg.settings.get("mujoco", {})}
                tasks.append((label, src, "mujoco", over | {"_label": vl}, 1,
                              max(cfg.samples // 2, 12), "instantaneous"))
    return tasks


def build_report(cfg: ReportConfig, progress=None) -> Path:
    """Run everything and write the report; returns the output directory."""
    ph = Phases(progress)
    out = Path(cfg.out)
    out.mkdir(parents=True, exist_ok=True)
    cases = resolve_cases(cfg)
    engines = engines_of(cfg)
    meta = metadata(cfg, engines)
    results: list[dict] = []
    figures: dict[str, dict] = {}
    studies: dict = {}
    pool = make_executor(cfg)
    _start_workers(pool, cfg)
    # one queue for every task, most urgent first (reports.studies.scheduler.PRIORITY)
    ex = PriorityExecutor(pool, cfg.workers or os.cpu_count() or 2)
    try:
        hard = _start_hard_cases(cfg, ex, ph) if cfg.studies and not cfg.cases else None
        pending = {}
        tasks = _tasks(cfg, cases, engines)
        ph.add("engine runs", len(tasks))
        per_case = {label: 0 for label, _ in cases}
        for t in tasks:
            f = ex.submit(_task_entry, t[1], *t[2:])
            pending[f] = ("run", t[0], t[1])
            per_case[t[0]] += 1
        if cfg.studies and not cfg.cases:  # free motion: its own cases (report_free)
            pending.update(report_free.submit(ex, cfg.quick, ph))
            pending.update(report_tune.submit(ex, cfg.quick, ph))  # xval tune's table
        if cfg.studies:
            grid_futs, studies["grid_sizes"] = _submit_grids(cfg, ex, cases, ph)
            pending.update(grid_futs)
            if not cfg.cases:
                pending[ex.submit(_scene_task, cfg.quick)] = ("scene", "", "")
                ph.add("scene economy", 1)
        grid_rows: dict[str, list] = {}
        while pending:
            done, _ = wait(list(pending), return_when=FIRST_COMPLETED)
            for f in done:
                kind, label, src = pending.pop(f)
                _collect(f, kind, label, src, cfg, ex, ph, results, figures, studies,
                         grid_rows, per_case, pending, ENGINE_RELATIVE)
        if hard is not None:
            hard[0].join()
            studies["hard"] = hard[1].get("hard", {"error": hard[1].get("error", "")})
            ph.step("hard cases")
    finally:
        ex.shutdown()
        pool.shutdown()
        if hasattr(pool, "client_to_close"):
            pool.client_to_close.close()
    ph.add("page", 1)
    write_page(out, cfg, cases, engines, results, figures, studies, meta, ph)
    ph.step("page")
    pd.DataFrame([{"phase": k, "seconds": v} for k, v in ph.seconds().items()]).to_csv(
        out / "phases.csv", index=False)
    return out


def _collect(f, kind, label, src, cfg, ex, ph, results, figures, studies, grid_rows,
             per_case, pending, tol):
    """One finished task: store it and submit what it unblocks (a case's figures once
    its runs are in; a grid's Pareto plot once its rows are in)."""
    if kind in ("free", "freegrid"):
        report_free.collect(kind, f, label, studies, ph)
        return
    if kind == "tune":
        report_tune.collect(f, label, studies, ph)
        return
    if kind == "run":
        res = _result_or_error(f)
        if "case" not in res:  # the task itself died
            res = {"case": label, "engine": "?", "mode": "run", "overrides": {},
                   "run": None, "comparisons": [], "error": res.get("error")}
        res["case"], res["source"] = label, src
        results.append(res)
        ph.step("engine runs")
        per_case[label] -= 1
        if per_case[label] == 0:
            done_runs = sorted((r for r in results if r["case"] == label
                                and r["mode"] == "run" and r["run"] is not None),
                               key=lambda r: _engine_rank(cfg, r["engine"]))
            runs = {r["engine"]: r["run"] for r in done_runs}
            comps = {r["engine"]: r["comparisons"] for r in done_runs}
            ph.add("figures", 1)
            pending[ex.submit(_figure_task, label, src, runs, comps, tol)] = \
                ("figures", label, src)
    elif kind == "figures":
        figures[label] = _result_or_error(f)
        ph.step("figures")
    elif kind.startswith("grid:"):
        rows = grid_rows.setdefault(label, [])
        meta = kind.split(":", 1)[1]
        try:
            rows.append(f.result())
        except Exception as e:  # noqa: BLE001 - a study row, never an exception
            rows.append(S._failed_row({"label": meta}, f"task failed: {e}"))
        ph.step("speed-error grid")
        if len(rows) == studies["grid_sizes"][label]:
            g = S._grid_frame(rows).assign(case=label)
            studies.setdefault("grids", {})[label] = {"grid": g,
                                                      "cheapest": S.cheapest_settings(g)}
            ph.add("figures", 1)
            pending[ex.submit(_pareto_task, g, label, src, cfg.samples)] = \
                ("pareto", label, src)
    elif kind == "pareto":
        studies["grids"][label].update(_result_or_error(f))
        ph.step("figures")
    elif kind == "scene":
        studies["scene"] = _result_or_error(f)
        ph.step("scene economy")


def _engine_rank(cfg: ReportConfig, engine: str) -> int:
    """Registry order: every figure lists the engines in one order."""
    order = engines_of(cfg)
    return order.index(engine) if engine in order else len(order)


def _submit_grids(cfg: ReportConfig, ex, cases, ph) -> tuple[dict, dict]:
    """The speed-against-error grid of the requested cases (of :data:`GRID_CASES` when
    none were given), each setting a pool task: ``(pending futures, rows per case)``."""
    if cfg.cases:
        chosen = cases[:3]
    else:
        want = GRID_CASES[bool(cfg.quick)]
        chosen = [(w, w) for w in want]
    pending = {}
    for label, src in chosen:
        futs = S._grid_futures(ex, src, cfg.quick)
        for f, m in futs:
            pending[f] = (f"grid:{m.get('label', '')}", label, src)
        ph.add("speed-error grid", len(futs))
    sizes: dict[str, int] = {}
    for _, label, _ in pending.values():
        sizes[label] = sizes.get(label, 0) + 1
    return pending, sizes


class _HardLane(Executor):
    """The hard-case study's tasks: long runs first, the rest before the grids."""

    def __init__(self, ex: PriorityExecutor):
        self.ex = ex

    def submit(self, fn, /, *args, **kwargs):
        if getattr(fn, "__name__", "") == "long_run_task":
            return self.ex.submit(fn, *args, **kwargs)
        return self.ex.submit_at(1.5, fn, *args, **kwargs)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False):
        pass


def _start_hard_cases(cfg: ReportConfig, ex, ph):
    """The hard-case study in a thread of this process, its runs on the pool (long
    runs first: in the full report they are the critical path)."""
    box: dict = {}
    ph.add("hard cases", 1)

    def go():
        try:
            # its own runs ahead of the speed grid's runs of the same function; its
            # long runs (function long_run_task) keep their own first place
            box["hard"] = hard_cases(cfg.quick, _HardLane(ex))
        except Exception as e:  # noqa: BLE001 - a study failure is a line of the report
            box["error"] = f"{type(e).__name__}: {e}"
    t = threading.Thread(target=go, name="hard-cases", daemon=True)
    t.start()
    return t, box


def _result_or_error(fut):
    try:
        return fut.result()
    except Exception as e:
        return {"error": f"{type(e).__name__}: {e}"}


# ----------------------------------------------------------------------------- command
__all__ = ["ReportConfig", "build_report", "engine_task"]
