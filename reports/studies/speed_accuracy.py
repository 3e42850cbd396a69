"""Speed against error: the settings grids, their tasks and executor, timing, errors.

Pure functions returning pandas DataFrames and PNG bytes::

    from reports.studies import speed_accuracy as studies
    grid = studies.speed_error_grid("seed-four-bar", quick=True)   # one row per setting
    table = studies.cheapest_settings(grid)                        # per engine and tolerance
    t_an = studies.analytic_seconds_per_rev("seed-four-bar")

The hard cases, the scene economy and the whole study built on these are
:mod:`reports.studies.hard_cases`, :mod:`reports.studies.scene` and
:mod:`reports.studies.study`.

``python -m reports.cli.studies [--quick] [--out DIR] [--workers N]`` runs the whole
study and writes CSV tables and PNG figures.

Measurements
------------
Nothing here steps an engine or imports an engine library: every run and timing goes
through :mod:`sim_models` (the verdict runs' sessions), long and change-point runs
through :mod:`reports.studies.runs` and :mod:`reports.studies.change_point`.

* **Errors** come from one verdict run per setting
  (:func:`reports.comparison.runs.run_verdict`: ``revolutions`` turns, the last sampled
  at the analytic sweep's input values, compared by
  :func:`reports.comparison.compare.compare_run`): every quantity's largest error
  divided by its peak over the cycle.  ``accel_error`` is the worst of
  the bodies' angular accelerations and the sliders' accelerations, ``force_error``
  the worst of the drive effort and every joint force (the values this project derives
  from the engine, not the engines' own defective readings); ``error`` is the larger.
* **Speed** is timed separately, on the bare stepping loop of the same engine session
  (:func:`sim_models.runs.driven.time_engine`: the session's own ``advance``, which the run
  loop :func:`sim_models.engines.protocol.drive` calls between samples, without readout), so
  that the cost of the 36-72 samples and their Newton-Euler reconstruction does not
  swamp coarse steps:
  ``steps_per_second`` over up to one revolution (best of a few repeats) and
  ``seconds_per_rev = steps_per_rev / steps_per_second``.  ``run_seconds_per_rev`` is
  the engine run's own wall time per revolution including the sampling.  Timings are
  taken with the pool's other workers busy, as the study runs.
* A run that diverges (non-finite state, loop gap above 1e-3 of the mechanism's size,
  crank rate off by 1 %) or raises is a row with ``ok = False``, its ``reason`` and
  infinite errors.  Nothing here raises for a bad simulation.

Settings grids
--------------
MuJoCo: integrators ``Euler``, ``implicitfast``, ``RK4`` x three constraint families x
steps per revolution:

* ``stock``: MuJoCo's own defaults, solref (0.02, 1), solimp (0.9, 0.95, 0.001, 0.5, 2)
  and the stock constraint diagonal (``invweight_scale = 1``);
* ``hard``: the project's default (near-hard solimp cap 0.9999, ``invweight_scale``
  1e-3, critically damped direct solref with a fixed 10 ms time constant);
* ``deadbeat``: the same with solref ``(-1/dt^2, -1/dt)`` scaled with the step
  (ENGINE_NOTES.md's advice for first-order integrators; wrong for RK4).

PyBullet: steps per revolution x ``solverResidualThreshold`` (1e-7 = PyBullet's
default, 1e-30 = never stop early) x global ERP (0.2 default, 1.0); other settings the
project's (damping 0, motors off, ``maxJointVelocity`` 1e4, 20 iterations).

The step is given in steps per revolution (so the slider-crank at 200 rad/s and the
four-bar at 15 rad/s are gridded alike) and shortened by the run so that every sample
falls on a step; ``timestep`` and ``steps_per_rev`` are the values used.

Parallelism
-----------
The tasks (case x engine x setting, and the hard-case runs) are independent,
picklable top-level functions of ``(case_name, engine, settings_dict, ...)``.  Every
heavy function takes ``pool``: ``None`` (default) runs them on a local
``ProcessPoolExecutor`` with one worker per core (serially when called inside a pool
worker, e.g. from :mod:`reports.report.build`'s tasks), any ``concurrent.futures.Executor``
(e.g. a dask client's ``get_executor()``) is used as given, and ``False`` runs them
serially in this process.
"""

from __future__ import annotations

import contextlib
import math
import multiprocessing
import os
import time
from concurrent.futures import Executor, Future, ProcessPoolExecutor

import numpy as np
import pandas as pd

from analytic import Linkage
from analytic.sweep import input_values
from reports.comparison.compare import compare_run
from reports.comparison.quantities import judged
from reports.comparison.reference import reference_of
from reports.comparison.reference import sample_errors as per_quantity
from reports.comparison.runs import request_of, run_verdict
from reports.figures.study_plots import pareto_frontier_plot
from reports.studies.change_point import (  # noqa: F401 - re-exported: the change-point study
    CHANGE_POINT_MAX_VIOLATION,
    _wrap,
    analytic_branch,
    assembly_modes,
    change_point_task,
    classify_branch,
    singular_inputs,
)
from reports.studies.runs import (  # noqa: F401 - re-exported: the studies' engine runs
    HARD_CASES_DIR,
    Trace,
    hard_case_names,
    load,
    make_settings,
    revolution_time,
    trace,
    trace_diagnostics,
)
from sim_models import compile_linkage
from sim_models.builders.mjcf import HARD_SOLIMP, direct_solref
from sim_models.engines.registry import available_engines
from sim_models.runs.driven import time_engine as session_time
from sim_models.runs.engine_run import RunRequest

#: Tolerances of the cheapest-setting table (max normalised error).
TOLERANCES = (1e-2, 1e-3, 1e-4)
#: The mechanism descriptions of the hard cases.
#: Cases of the speed/error grids.
QUICK_CASES = ("seed-four-bar", "seed-slider-crank")
FULL_CASES = ("seed-four-bar", "seed-slider-crank", "near-toggle-four-bar")
#: Long run: revolutions in full and quick mode.
LONG_RUN_REVOLUTIONS = {False: 1000, True: 50}
#: Samples per revolution of the long run's trace (every revolution sampled, for the
#: per-revolution diagnostics): the study's own choice, not the run default
#: (:class:`sim_models.runs.engine_run.RunRequest` samples only a run's last revolution).
LONG_RUN_SAMPLES = 36
#: Samples per revolution of a speed/error grid run: the run default with ``--quick``,
#: else 72 (the full report's verdict runs sample as many: ``reports.report.build.SAMPLES``).
GRID_SAMPLES = {True: RunRequest.samples, False: 72}

#: MuJoCo's own defaults (its XML defaults) for the "stock" family.
STOCK_SOLREF = (0.02, 1.0)
STOCK_SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)

GRID_COLUMNS = ["case", "engine", "label", "family", "integrator", "settings", "timestep",
                "steps_per_rev", "steps_per_second", "seconds_per_rev", "run_seconds_per_rev",
                "accel_error", "force_error", "error", "worst_quantity", "worst_at", "ok",
                "reason"]


# ============================================================================ cases
def mujoco_family(family: str, dt: float, integrator: str) -> dict:
    """MuJoCo settings dict of a constraint family (see the module docstring)."""
    d = {"timestep": dt, "integrator": integrator}
    if family == "stock":
        d.update(solref=STOCK_SOLREF, solimp=STOCK_SOLIMP, invweight_scale=1.0)
    elif family == "hard":
        d.update(solref=direct_solref(1e-2), solimp=HARD_SOLIMP)
    elif family == "deadbeat":
        d.update(solref=(-1.0 / dt ** 2, -1.0 / dt), solimp=HARD_SOLIMP)
    else:
        raise ValueError(f"unknown MuJoCo family {family!r}")
    return d


def grid_plan(case: str, quick: bool) -> list[dict]:
    """The settings of :func:`speed_error_grid`: dicts with engine, label, family,
    integrator, settings (a plain dict) and the nominal steps per revolution."""
    T = revolution_time(load(case))
    if quick:
        mj_spr, pb_spr = (100, 300, 1000, 3000), (300, 1000, 3000)
        ex_spr = (360, 1008, 2016)
    else:
        mj_spr, pb_spr = (30, 100, 300, 1000, 3000, 10000), (100, 300, 1000, 3000, 10000,
                                                               30000)
        ex_spr = (144, 360, 720, 1008, 2016, 3600)
    plan = []
    for integ in ("Euler", "implicitfast", "RK4"):
        for fam in ("stock", "hard", "deadbeat"):
            for spr in mj_spr:
                plan.append(dict(engine="mujoco", family=fam, integrator=integ, spr=spr,
                                 label=f"{integ}/{fam}/{spr}",
                                 settings=mujoco_family(fam, T / spr, integ)))
    for rt in (1e-7, 1e-30):
        for erp in (0.2, 1.0):
            fam = f"rt={rt:g} erp={erp:g}"
            for spr in pb_spr:
                plan.append(dict(engine="pybullet", family=fam, integrator="", spr=spr,
                                 label=f"rt{rt:g}/erp{erp:g}/{spr}",
                                 settings=dict(timestep=T / spr, residual_threshold=rt,
                                               erp=erp)))
    # Exudyn: steps per revolution x the generalized-alpha spectral radius (its own
    # evidence for the recommended 1008 / 0.8; the step cap follows the steps asked for)
    for rho in (0.6, 0.8):
        for spr in ex_spr:
            plan.append(dict(engine="exudyn", family=f"rho={rho:g}", integrator="", spr=spr,
                             label=f"rho{rho:g}/{spr}",
                             settings=dict(steps_per_rev=spr, spectral_radius=rho,
                                           timestep=T / spr)))
    plan += _pinocchio_plan(T, quick)
    plan += _warp_plan(T, quick)
    return plan


def _pinocchio_plan(T: float, quick: bool) -> list[dict]:
    """Pinocchio's family (RK4 steps per revolution x Baumgarte, its own evidence for
    the recommended 180 / 0.05), when its optional library is installed."""
    if "pinocchio" not in available_engines():
        return []
    spr_all = (90, 180, 360) if quick else (45, 90, 180, 360, 720)
    return [dict(engine="pinocchio", family=f"baumgarte={b:g}", integrator="rk4", spr=spr,
                 label=f"rk4/b{b:g}/{spr}",
                 settings=dict(steps_per_rev=spr, baumgarte=b, timestep=min(T / spr, 0.1)))
            for b in (0.0, 0.05) for spr in spr_all]


def _warp_plan(T: float, quick: bool) -> list[dict]:
    """MuJoCo Warp's family (float32 MuJoCo at its recommended solver, steps per
    revolution), when its optional library is installed: its error stops falling with
    the step at its float32 floor (:mod:`sim_models.runs.precision`), which the grid shows."""
    if "mujoco_warp" not in available_engines():
        return []
    spr_all = (300, 1000) if quick else (100, 300, 1000, 3000)
    return [dict(engine="mujoco_warp", family="float32", integrator="", spr=spr,
                 label=f"f32/{spr}", settings=dict(timestep=T / spr)) for spr in spr_all]


# ============================================================================ errors
def _is_accel(quantity: str) -> bool:
    """An acceleration quantity of the studies' ``accel_error``: a body's alpha, a
    slider's acceleration."""
    return quantity.endswith((".alpha", ".a"))


def _is_force(quantity: str) -> bool:
    """A force quantity of the studies' ``force_error``: the drive effort and the joint
    forces (not a prismatic joint's normal and moment)."""
    return quantity == "drive.effort" or quantity.endswith(".force")


def run_errors(run_, linkage: Linkage | None = None) -> dict:
    """Normalised errors of an engine run through :func:`reports.comparison.compare.compare_run`
    (against ``run_.linkage``, the compiled Linkage it was made from; ``linkage``: another
    one to judge it against instead)."""
    return verdict_errors(run_, compare_run(run_, linkage=linkage) if run_.ok else ())


def verdict_errors(run_, comparisons) -> dict:
    """The study row's errors from a run's comparisons (a :class:`Verdict`'s): the worst
    judged acceleration and force quantity, normalised as the verdict normalises them;
    infinite for a run that did not finish."""
    if not run_.ok:
        return dict(accel_error=math.inf, force_error=math.inf, error=math.inf,
                    worst_quantity="", worst_at=math.nan)
    comps = judged(comparisons)
    acc = [c for c in comps if _is_accel(c.quantity)]
    frc = [c for c in comps if _is_force(c.quantity)]
    a = max((c.normalised for c in acc), default=math.nan)
    f = max((c.normalised for c in frc), default=math.nan)
    worst = max(comps, key=lambda c: c.normalised if np.isfinite(c.normalised) else math.inf,
                default=None)
    both = [x for x in (a, f) if not math.isnan(x)]
    err = max(both) if both else math.nan
    return dict(accel_error=float(a), force_error=float(f), error=err,
                worst_quantity=worst.quantity if worst else "",
                worst_at=float(worst.at) if worst else math.nan)


def sample_errors(run_) -> dict[str, np.ndarray]:
    """Per-sample normalised errors of a run (for the study plots): ``alpha`` the worst
    acceleration quantity and ``force`` the worst force quantity at each sample
    (:func:`_is_accel`, :func:`_is_force`), each quantity divided by the peak its verdict
    divides by (:func:`reports.comparison.reference.sample_errors`, the one per-sample error), so a
    curve's largest value is the row's ``accel_error`` / ``force_error``; NaN where the
    verdict judges no sample."""
    errs = per_quantity(run_, reference_of(run_), compare_run(run_))  # run_.linkage's
    out = {}
    for key, family in (("alpha", _is_accel), ("force", _is_force)):
        cols = [e for q, e in errs.items() if family(q)]
        if cols:
            out[key] = np.fmax.reduce(np.vstack(cols), axis=0)  # NaN where all are NaN
    return out


# ============================================================================ timing
def time_engine(tree, engine: str, settings, dt: float, steps: int, repeats: int = 3) -> float:
    """Steps per second of the engine session's own stepping loop (no readout) on the
    compiled linkage: :func:`sim_models.runs.driven.time_engine`, best of ``repeats``."""
    return session_time(tree, engine, settings, dt, steps, repeats)


def analytic_seconds_per_rev(case: str, points: int = 3600, repeats: int = 5) -> float:
    """Wall-clock seconds the analytic solver needs for one revolution of ``points``
    input values: positions, velocities, accelerations and (with masses) the
    kinetostatics of every body and joint (best of ``repeats``)."""
    mech = load(case)
    lk = Linkage(mech)
    vals, _, _ = input_values(lk, points)
    lk.kinematics(vals[:10], on_singular="flag")  # warm caches
    best = math.inf
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        kin = lk.kinematics(vals, on_singular="flag")
        if mech.has_mass:
            lk.forces(kin)
        best = min(best, time.perf_counter() - t0)
    return best


# ============================================================================ tasks
def _failed_row(meta: dict, reason: str) -> dict:
    row = {k: meta.get(k) for k in GRID_COLUMNS}
    row.update(ok=False, reason=reason, accel_error=math.inf, force_error=math.inf,
               error=math.inf)
    for k in ("timestep", "steps_per_rev", "steps_per_second", "seconds_per_rev",
              "run_seconds_per_rev", "worst_at"):
        if row.get(k) is None:
            row[k] = math.nan
    row["settings"] = row.get("settings") or str(meta.get("settings_dict", ""))
    return row


def grid_task(case_name: str, engine: str, settings_dict: dict, label: str = "",
              revolutions: int | None = None, samples: int | None = None,
              timing_steps: int = 5000,
              timing_repeats: int = 3, meta: dict | None = None,
              keep_samples: bool = False) -> dict:
    """One engine run at one setting: errors (:func:`reports.comparison.runs.run_verdict`,
    the one run-and-compare, read by :func:`verdict_errors`) and speed
    (bare stepping loop); ``revolutions``/``samples`` None: the run request's defaults.
    Never raises: failures are rows with ``ok = False``."""
    meta = dict(meta or {})
    meta.update(case=case_name, engine=engine, label=label, settings_dict=settings_dict)
    try:
        tree = compile_linkage(load(case_name))  # one compiled linkage for run and errors
        s = make_settings(engine, settings_dict)
        req = request_of({"revolutions": revolutions, "samples": samples})
        v = run_verdict(tree, engine, s, req)  # the one run-and-compare
        r = v.run
        row = {k: meta.get(k) for k in GRID_COLUMNS}
        row.update(case=case_name, engine=engine, label=label, settings=s.describe(),
                   timestep=float(r.timestep), steps_per_rev=float(r.steps_per_rev),
                   run_seconds_per_rev=float(r.wall_per_rev), ok=bool(r.ok),
                   reason=r.reason or "")
        row.update(verdict_errors(r, v.comparisons))
        n = int(min(max(1, round(r.steps_per_rev)), timing_steps))
        try:
            # the same session class and stepping loop as the run above
            sps = time_engine(tree, engine, s, r.timestep, n, timing_repeats)
        except Exception as e:  # timing is secondary: keep the errors
            sps = math.nan
            row["reason"] = (row["reason"] + "; " if row["reason"] else "") + \
                f"timing failed: {type(e).__name__}: {e}"
        row["steps_per_second"] = float(sps)
        row["seconds_per_rev"] = float(r.steps_per_rev / sps) if sps and sps > 0 else math.nan
        if keep_samples and r.ok:  # the plots draw successful runs only
            row["samples"] = {"input_deg": np.degrees(r.values).tolist(),
                              **{k: v.tolist()
                                 for k, v in sample_errors(r).items()}}
        return row
    except Exception as e:  # noqa: BLE001 - a study row, never an exception
        return _failed_row(meta, f"{type(e).__name__}: {e}")


class _SerialExecutor(Executor):
    """``submit`` runs the call at once (``pool=False``)."""

    def submit(self, fn, /, *args, **kwargs):
        f: Future = Future()
        try:
            f.set_result(fn(*args, **kwargs))
        except BaseException as e:  # noqa: BLE001
            f.set_exception(e)
        return f


@contextlib.contextmanager
def executor(pool=None, workers: int | None = None):
    """The executor to use: a local process pool for ``None`` (shut down on exit; serial
    when this process is itself a pool worker), a serial one for ``False``, else
    ``pool`` itself."""
    if pool is None and multiprocessing.parent_process() is not None:
        # already inside a worker (e.g. a task of reports.report.build's pool, or a daemonic
        # dask worker, which may not have children): run serially, no nested pool
        pool = False
    if pool is None:
        n = workers or os.cpu_count() or 2
        ex = ProcessPoolExecutor(max_workers=n)
        try:
            yield ex
        finally:
            ex.shutdown(wait=True, cancel_futures=True)
    elif pool is False:
        yield _SerialExecutor()
    else:
        yield pool


def _gather(futures: list[tuple[Future, dict]], fallback=None) -> list:
    """Results in submission order; a task that raised (e.g. a worker killed by an
    engine crash) becomes ``fallback(meta, reason)`` (default: a failed grid row)."""
    fallback = fallback or _failed_row
    out = []
    for f, meta in futures:
        try:
            out.append(f.result())
        except Exception as e:  # noqa: BLE001
            out.append(fallback(meta, f"task failed: {type(e).__name__}: {e}"))
    return out


# ============================================================================ grids
def _grid_futures(ex, case: str, quick: bool) -> list[tuple[Future, dict]]:
    revs, samples = RunRequest.revolutions, GRID_SAMPLES[quick]
    cap, reps = (3000, 3) if quick else (20000, 3)
    futs = []
    for item in grid_plan(case, quick):
        meta = dict(case=case, engine=item["engine"], label=item["label"],
                    family=item["family"], integrator=item["integrator"])
        f = ex.submit(grid_task, case, item["engine"], item["settings"], item["label"],
                      revs, samples, cap, reps, meta)
        futs.append((f, meta))
    return futs


def _grid_frame(rows: list[dict]) -> pd.DataFrame:
    df = pd.DataFrame(rows)
    for c in GRID_COLUMNS:
        if c not in df:
            df[c] = np.nan
    df = df[GRID_COLUMNS + [c for c in df.columns if c not in GRID_COLUMNS]]
    df["ok"] = df["ok"].astype(bool)
    df["reason"] = df["reason"].fillna("").astype(str)
    return df


def speed_error_grid(case: str, quick: bool, pool=None) -> pd.DataFrame:
    """Every setting of the grid (:func:`grid_plan`) on ``case``: one row each with
    ``case, engine, label, family, integrator, settings, timestep, steps_per_rev,
    steps_per_second, seconds_per_rev, run_seconds_per_rev, accel_error, force_error,
    error, worst_quantity, worst_at, ok, reason`` (see the module docstring)."""
    with executor(pool) as ex:
        rows = _gather(_grid_futures(ex, case, quick))
    return _grid_frame(rows)


def cheapest_settings(grid: pd.DataFrame, tolerances=TOLERANCES) -> pd.DataFrame:
    """Per (case,) engine and tolerance the row with the least ``seconds_per_rev`` among
    the runs that are ``ok`` with ``error <= tolerance``; ``label = 'none'`` when no
    setting meets it."""
    keys = ["case", "engine"] if "case" in grid and grid["case"].notna().any() else ["engine"]
    out = []
    for key, g in grid.groupby(keys, sort=True):
        key = key if isinstance(key, tuple) else (key,)
        base = dict(zip(keys, key, strict=True))
        for tol in tolerances:
            err = pd.to_numeric(g["error"], errors="coerce")
            cost = pd.to_numeric(g["seconds_per_rev"], errors="coerce")
            ok = g[g["ok"].astype(bool) & (err <= tol) & np.isfinite(cost)]
            row = dict(base, tolerance=tol)
            if len(ok):
                best = ok.loc[pd.to_numeric(ok["seconds_per_rev"]).idxmin()]
                row.update(label=best["label"], settings=best.get("settings", ""),
                           timestep=best.get("timestep", math.nan),
                           steps_per_rev=best.get("steps_per_rev", math.nan),
                           steps_per_second=best.get("steps_per_second", math.nan),
                           seconds_per_rev=best["seconds_per_rev"], error=best["error"],
                           accel_error=best.get("accel_error", math.nan),
                           force_error=best.get("force_error", math.nan))
            else:
                row.update(label="none", settings="", timestep=math.nan,
                           steps_per_rev=math.nan, steps_per_second=math.nan,
                           seconds_per_rev=math.nan, error=math.nan, accel_error=math.nan,
                           force_error=math.nan)
            out.append(row)
    cols = keys + ["tolerance", "label", "seconds_per_rev", "steps_per_second", "timestep",
                   "steps_per_rev", "error", "accel_error", "force_error", "settings"]
    return pd.DataFrame(out, columns=cols)


def pareto_figure(grid: pd.DataFrame, case: str, analytic_time: float | None) -> bytes:
    w = load(case).driver.velocity
    return pareto_frontier_plot(grid, f"{case} (omega2 = {w:g} rad/s): speed against error",
                                analytic_time)
