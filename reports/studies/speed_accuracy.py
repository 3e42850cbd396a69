"""Speed against error: settings grids, hard cases, a long run and scene economy.

Pure functions returning pandas DataFrames and PNG bytes::

    from reports.studies import speed_accuracy as studies
    grid = studies.speed_error_grid("seed-four-bar", quick=True)   # one row per setting
    table = studies.cheapest_settings(grid)                        # per engine and tolerance
    t_an = studies.analytic_seconds_per_rev("seed-four-bar")
    hard = studies.hard_cases(quick=True)                          # dict of frames and PNGs
    scene = studies.scene_economy(quick=True)
    everything = studies.run_study(quick=True)                     # all of it + figures

``python -m reports.cli.studies [--quick] [--out DIR] [--workers N]`` runs the whole
study and writes CSV tables and PNG figures.

Measurements
------------
Nothing here steps an engine or imports an engine library: every run and timing goes
through :mod:`sim_models` (the verdict runs' sessions), long and change-point runs
through :mod:`reports.studies.runs` and :mod:`reports.studies.change_point`.

* **Errors** come from one engine run per setting (:func:`sim_models.engines.run`,
  ``revolutions`` turns, the last sampled at the analytic sweep's input values) and the
  project's comparison helper :func:`reports.comparison.compare.compare_run`: every quantity's
  largest error divided by its peak over the cycle.  ``accel_error`` is the worst of
  the bodies' angular accelerations and the sliders' accelerations, ``force_error``
  the worst of the drive effort and every joint force (the values this project derives
  from the engine, not the engines' own defective readings); ``error`` is the larger.
* **Speed** is timed separately, on the bare stepping loop of the same engine session
  (:func:`sim_models.engines.time_engine`: the session's own ``advance``, which the run
  loop :func:`sim_models.engine_base.drive` calls between samples, without readout), so
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
import json
import math
import multiprocessing
import os
import time
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np
import pandas as pd

from analytic import Linkage
from analytic.sweep import input_values
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

#: Tolerances of the cheapest-setting table (max normalised error).
TOLERANCES = (1e-2, 1e-3, 1e-4)
#: The mechanism descriptions of the hard cases.
#: Cases of the speed/error grids.
QUICK_CASES = ("seed-four-bar", "seed-slider-crank")
FULL_CASES = ("seed-four-bar", "seed-slider-crank", "near-toggle-four-bar")
#: Long run: revolutions in full and quick mode.
LONG_RUN_REVOLUTIONS = {False: 1000, True: 50}
#: Samples per revolution of the low-level loops (long run, change point).
LONG_RUN_SAMPLES = 36

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
    from sim_models.mjcf import HARD_SOLIMP, direct_solref
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
    return plan


def _pinocchio_plan(T: float, quick: bool) -> list[dict]:
    """Pinocchio's family (RK4 steps per revolution x Baumgarte, its own evidence for
    the recommended 180 / 0.05), when its optional library is installed."""
    from sim_models.registry import available_engines
    if "pinocchio" not in available_engines():
        return []
    spr_all = (90, 180, 360) if quick else (45, 90, 180, 360, 720)
    return [dict(engine="pinocchio", family=f"baumgarte={b:g}", integrator="rk4", spr=spr,
                 label=f"rk4/b{b:g}/{spr}",
                 settings=dict(steps_per_rev=spr, baumgarte=b, timestep=min(T / spr, 0.1)))
            for b in (0.0, 0.05) for spr in spr_all]


# ============================================================================ errors
def _is_accel(quantity: str) -> bool:
    """An acceleration quantity of the studies' ``accel_error``: a body's alpha, a
    slider's acceleration."""
    return quantity.endswith((".alpha", ".a"))


def _is_force(quantity: str) -> bool:
    """A force quantity of the studies' ``force_error``: the drive effort and the joint
    forces (not a prismatic joint's normal and moment)."""
    return quantity == "drive.effort" or quantity.endswith(".force")


def run_errors(run_, reference=None) -> dict:
    """Normalised errors of an engine run through :func:`reports.comparison.compare.compare_run`
    (``reference``: the compiled linkage's Linkage; default the run's own mechanism)."""
    from reports.comparison.compare import compare_run
    from reports.comparison.quantities import judged
    if not run_.ok:
        return dict(accel_error=math.inf, force_error=math.inf, error=math.inf,
                    worst_quantity="", worst_at=math.nan)
    comps = judged(compare_run(run_, reference))
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


def sample_errors(run_, lk: Linkage | None = None) -> dict[str, np.ndarray]:
    """Per-sample normalised errors of a run (for the study plots): ``alpha`` the worst
    acceleration quantity and ``force`` the worst force quantity at each sample
    (:func:`_is_accel`, :func:`_is_force`), each quantity divided by the peak its verdict
    divides by (:func:`reports.comparison.reference.sample_errors`, the one per-sample error), so a
    curve's largest value is the row's ``accel_error`` / ``force_error``; NaN where the
    verdict judges no sample."""
    from reports.comparison.compare import compare_run
    from reports.comparison.reference import reference_of
    from reports.comparison.reference import sample_errors as per_quantity
    errs = per_quantity(run_, reference_of(run_, lk), compare_run(run_, lk))
    out = {}
    for key, family in (("alpha", _is_accel), ("force", _is_force)):
        cols = [e for q, e in errs.items() if family(q)]
        if cols:
            out[key] = np.fmax.reduce(np.vstack(cols), axis=0)  # NaN where all are NaN
    return out


# ============================================================================ timing
def time_engine(tree, engine: str, settings, dt: float, steps: int, repeats: int = 3) -> float:
    """Steps per second of the engine session's own stepping loop (no readout) on the
    compiled linkage: :func:`sim_models.engines.time_engine`, best of ``repeats``."""
    from sim_models.engines import time_engine as session_time
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
    """One engine run at one setting: errors (engine run + :func:`run_errors`) and speed
    (bare stepping loop); ``revolutions``/``samples`` None: the run request's defaults.
    Never raises: failures are rows with ``ok = False``."""
    meta = dict(meta or {})
    meta.update(case=case_name, engine=engine, label=label, settings_dict=settings_dict)
    try:
        from reports.comparison.runs import request_of
        from sim_models import compile_linkage
        from sim_models.engines import run
        tree = compile_linkage(load(case_name))  # one compiled linkage for run and errors
        s = make_settings(engine, settings_dict)
        req = request_of({"revolutions": revolutions, "samples": samples})
        r = run(tree, engine, s, revolutions=req.revolutions, samples=req.samples)
        row = {k: meta.get(k) for k in GRID_COLUMNS}
        row.update(case=case_name, engine=engine, label=label, settings=s.describe(),
                   timestep=float(r.timestep), steps_per_rev=float(r.steps_per_rev),
                   run_seconds_per_rev=float(r.wall_per_rev), ok=bool(r.ok),
                   reason=r.reason or "")
        row.update(run_errors(r, tree.linkage))
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
                                 for k, v in sample_errors(r, tree.linkage).items()}}
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
    revs, samples = 2, (36 if quick else 72)
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
    from reports.figures.study_plots import pareto_frontier_plot
    w = load(case).driver.velocity
    return pareto_frontier_plot(grid, f"{case} (omega2 = {w:g} rad/s): speed against error",
                                analytic_time)


# ============================================================================ long run
def long_run_task(case_name: str, engine: str, settings_dict: dict, revolutions: int,
                  per_rev: int = LONG_RUN_SAMPLES) -> dict:
    """A long run: per-revolution diagnostics (:func:`trace_diagnostics` reduced to the
    worst value in each revolution; ``energy_balance`` and ``phase_drift`` at its end)
    plus a summary.  Never raises."""
    meta = dict(case=case_name, engine=engine, settings_dict=settings_dict)
    try:
        from sim_models import compile_linkage
        tree = compile_linkage(load(case_name))
        tr = trace(tree, engine, make_settings(engine, settings_dict), revolutions, per_rev)
        diag = trace_diagnostics(tree, tr)
        nrev = (len(diag) - 1) // per_rev
        ends = np.arange(1, nrev + 1) * per_rev

        def worst(col, absolute=False):
            if col not in diag:
                return np.full(nrev, np.nan)
            x = diag[col].to_numpy(float)
            x = np.abs(x) if absolute else x
            # samples (r-1) P .. r P of revolution r (both ends)
            body = x[:nrev * per_rev].reshape(nrev, per_rev).max(axis=1) if nrev else x[:0]
            return np.maximum(body, x[ends]) if nrev else body

        per = pd.DataFrame(dict(
            engine=engine, revolution=np.arange(1, nrev + 1), time=diag["t"].to_numpy()[ends],
            loop_violation=worst("loop_violation"),
            speed_deviation=worst("speed_deviation", True),
            phase_drift=diag["phase_drift"].to_numpy()[ends],
            power_residual=worst("power_residual", True),
            energy_balance=diag["energy_balance"].to_numpy()[ends],
            alpha_error=worst("alpha_error"), effort_error=worst("effort_error")))
        summary = dict(case=case_name, engine=engine, settings=tr.settings, ok=tr.ok,
                       reason=tr.reason, revolutions_asked=revolutions,
                       revolutions_done=nrev, timestep=tr.dt, steps=tr.steps,
                       wall_seconds=tr.wall,
                       seconds_per_rev=tr.wall / max(nrev, 1),
                       steps_per_second=tr.steps / tr.wall if tr.wall > 0 else math.nan)
        if len(per):
            first, last = per.iloc[0], per.iloc[-1]
            for col in ("loop_violation", "speed_deviation", "power_residual", "alpha_error",
                        "effort_error"):
                summary[f"{col}_first"] = float(first[col])
                summary[f"{col}_last"] = float(last[col])
                summary[f"{col}_max"] = float(per[col].max())
            summary["energy_balance_final"] = float(last["energy_balance"])
            summary["energy_balance_max"] = float(per["energy_balance"].abs().max())
            summary["phase_drift_final"] = float(last["phase_drift"])
        return {"per_rev": per.to_dict("list"), "summary": summary}
    except Exception as e:  # noqa: BLE001
        return {"per_rev": {}, "summary": dict(meta, ok=False, reason=f"{type(e).__name__}: {e}",
                                               revolutions_asked=revolutions,
                                               revolutions_done=0)}


# ============================================================================ hard cases
def _hard_plan(quick: bool) -> dict:
    """Settings of the hard-case runs."""
    from sim_models.mjcf import MujocoSettings
    mj_default = asdict(MujocoSettings())
    hs = {  # high-speed slider-crank
        "mujoco": [("RK4 default", mj_default),
                   ("implicitfast deadbeat dt=3e-5", mujoco_family("deadbeat", 3e-5,
                                                                   "implicitfast"))],
        "pybullet": [("dt=1e-4", dict(timestep=1e-4)), ("default dt=3e-5", {})],
    }
    nt = {  # near-toggle (and the seed four-bar for contrast)
        "mujoco": [("RK4 default", mj_default),
                   ("implicitfast deadbeat dt=1e-4", mujoco_family("deadbeat", 1e-4,
                                                                   "implicitfast"))],
        "pybullet": [("dt=1e-4", dict(timestep=1e-4)), ("default dt=3e-5", {})],
    }
    cp = {  # the project's settings and each engine's stock solver settings
        "mujoco": [("RK4 default", mj_default),
                   ("stock Euler dt=1e-3", mujoco_family("stock", 1e-3, "Euler"))],
        "pybullet": [("dt=1e-4", dict(timestep=1e-4)),
                     ("stock dt=1/240 erp=0.2 rt=1e-7",
                      dict(timestep=1 / 240, erp=0.2, residual_threshold=1e-7))],
    }
    if not quick:
        hs["mujoco"].append(("Euler deadbeat dt=1e-5", mujoco_family("deadbeat", 1e-5, "Euler")))
        hs["pybullet"].append(("dt=1e-5", dict(timestep=1e-5)))
        nt["mujoco"].append(("RK4 dt=1e-3", dict(mj_default, timestep=1e-3)))
        nt["pybullet"].append(("dt=1e-5", dict(timestep=1e-5)))
        cp["mujoco"].append(("implicitfast deadbeat dt=1e-4",
                             mujoco_family("deadbeat", 1e-4, "implicitfast")))
        cp["mujoco"].append(("stock implicitfast dt=4e-3",
                             mujoco_family("stock", 4e-3, "implicitfast")))
        cp["pybullet"].append(("default dt=3e-5", {}))
        cp["pybullet"].append(("dt=1e-3 erp=0.2 rt=1e-7",
                               dict(timestep=1e-3, erp=0.2, residual_threshold=1e-7)))
    lr = {"mujoco": ("RK4 default", mj_default),
          "pybullet": ("dt=1e-4 (the engine tests' seed-four-bar setting)",
                       dict(timestep=1e-4))}
    return dict(high_speed=hs, near_toggle=nt, change_point=cp, long_run=lr)


def hard_cases(quick: bool, pool=None) -> dict:
    """The hard cases.  Returns a dict:

    * ``high_speed`` (DataFrame), ``high_speed_plot`` (PNG): seed-slider-crank at
      omega2 = 200 rad/s, errors per engine and setting, and the error over the crank
      angle;
    * ``near_toggle`` (DataFrame), ``near_toggle_plot`` (PNG): the near-toggle four-bar
      (``analytic/cases/hard/near-toggle-four-bar.toml``) and the seed four-bar at the
      same settings, with the transmission angle's extreme;
    * ``change_point`` (DataFrame), ``change_point_plot`` (PNG): the parallelogram
      (``parallelogram-four-bar.toml``) through its singular positions; the branch each
      engine follows (``branch_after_singular``: 'parallelogram', 'anti-parallelogram'
      or 'diverged') and the analytic solver's own;
    * ``long_run`` (per-revolution DataFrame), ``long_run_summary`` (DataFrame),
      ``long_run_plot`` and ``long_run_timeseries`` (PNG) and ``long_run_revolutions``:
      seed-four-bar for 1000 revolutions (50 in quick mode);
    * ``notes``: one str (the long run's length among them).
    """
    from reports.figures.plots import timeseries_plot
    from reports.figures.study_plots import branch_plot, long_run_plot
    plan = _hard_plan(quick)
    R_long = LONG_RUN_REVOLUTIONS[bool(quick)]
    cp_revs = 2 if quick else 5
    with executor(pool) as ex:
        # the longest tasks first
        long_f = [(ex.submit(long_run_task, "seed-four-bar", eng, sd, R_long),
                   dict(engine=eng)) for eng, (_, sd) in plan["long_run"].items()]
        hs_f, nt_f, cp_f = [], [], []
        for eng, items in plan["high_speed"].items():
            for lab, sd in items:
                meta = dict(case="seed-slider-crank", engine=eng, label=lab)
                hs_f.append((ex.submit(grid_task, "seed-slider-crank", eng, sd, lab, 2, 72,
                                       3000, 2, meta, True), meta))
        for case in ("near-toggle-four-bar", "seed-four-bar"):
            for eng, items in plan["near_toggle"].items():
                for lab, sd in items:
                    meta = dict(case=case, engine=eng, label=lab)
                    nt_f.append((ex.submit(grid_task, case, eng, sd, lab, 2, 144, 3000, 2,
                                           meta, True), meta))
        for eng, items in plan["change_point"].items():
            for lab, sd in items:
                meta = dict(case="parallelogram-four-bar", engine=eng, label=lab)
                cp_f.append((ex.submit(change_point_task, "parallelogram-four-bar", eng, sd,
                                       cp_revs), meta))
        hs_rows, nt_rows = _gather(hs_f), _gather(nt_f)
        cp_rows = _gather(cp_f, lambda m, why: dict(
            m, ok=False, reason=why, branch_after_singular="diverged", branches="", flips=0,
            series=None, segments=[]))
        long_res = _gather(long_f, lambda m, why: {"per_rev": {}, "summary": dict(
            m, case="seed-four-bar", ok=False, reason=why, revolutions_done=0)})
    notes: list[str] = []
    out: dict = {}

    # --- high speed -------------------------------------------------------------
    hs = _grid_frame(hs_rows)
    hs.insert(1, "omega2", load("seed-slider-crank").driver.velocity)
    out["high_speed"] = hs.drop(columns=[c for c in ("samples",) if c in hs])
    out["high_speed_plot"] = _sample_error_figure(
        hs_rows, "seed-slider-crank at omega2 = 200 rad/s: error over the cycle", None)

    # --- near toggle ----------------------------------------------------------------
    nt = _grid_frame(nt_rows)
    ext = {}
    for case in ("near-toggle-four-bar", "seed-four-bar"):
        kin = Linkage(load(case)).kinematics(input_values(Linkage(load(case)), 3600)[0])
        tr = next(iter(kin.transmission.values()))
        i = int(np.argmax(np.abs(90.0 - tr)))
        ext[case] = (float(tr[i]), float(np.degrees(kin.value[i]) % 360.0))
    nt.insert(1, "transmission_extreme_deg", nt["case"].map(lambda c: ext[c][0]))
    nt.insert(2, "toggle_margin_deg",
              nt["transmission_extreme_deg"].map(lambda v: min(v, 180.0 - v)))
    nt.insert(3, "at_input_deg", nt["case"].map(lambda c: ext[c][1]))
    base = nt[nt["case"] == "seed-four-bar"].set_index(["engine", "label"])["error"]
    nt["error_vs_seed_four_bar"] = [
        r.error / base.get((r.engine, r.label), math.nan)
        if r.case != "seed-four-bar" and base.get((r.engine, r.label), 0) else math.nan
        for r in nt.itertuples()]
    out["near_toggle"] = nt.drop(columns=[c for c in ("samples",) if c in nt])
    lk = Linkage(load("near-toggle-four-bar"))
    vals = input_values(lk, 144)[0]
    tr = next(iter(lk.kinematics(vals).transmission.values()))
    out["near_toggle_plot"] = _sample_error_figure(
        [r for r in nt_rows if r.get("case") == "near-toggle-four-bar"],
        f"near-toggle four-bar (transmission angle up to {ext['near-toggle-four-bar'][0]:.2f}"
        " deg): error over the cycle", ("transmission angle (deg)", np.degrees(vals), tr))

    # --- change point -------------------------------------------------------------
    an = analytic_branch("parallelogram-four-bar", cp_revs)
    cp_all = cp_rows + [an]
    cols = ["case", "engine", "label", "timestep", "branch_after_singular", "final_branch",
            "branches", "flips", "max_deviation_deg", "max_loop_violation", "revolutions",
            "ok", "reason", "settings"]
    cp_df = pd.DataFrame([{k: r.get(k) for k in cols} for r in cp_all], columns=cols)
    cp_df["label"] = [m.get("label", "") for _, m in cp_f] + ["continued branch"]
    out["change_point"] = cp_df
    mech_cp = load("parallelogram-four-bar")
    xs = np.radians(np.array(an["series"]["input_deg"]))
    modes = assembly_modes(mech_cp, xs)
    sing = singular_inputs(Linkage(mech_cp))
    unwr = np.degrees(xs)
    sing_x = [s + 360 * k for s in sing for k in range(0, cp_revs + 2)
              if unwr[0] < s + 360 * k < unwr[-1]]
    eng_series = {}
    for r, (_, m) in zip(cp_rows, cp_f, strict=True):
        if r.get("series"):
            xi = np.array(r["series"]["input_deg"])
            yi = np.array(r["series"]["rocker_deg"])
            yi = np.degrees(_wrap(np.radians(yi - xi)))
            eng_series[f"{r['engine']} {m['label']}"] = np.interp(unwr, xi, yi, left=np.nan,
                                                                  right=np.nan)
    out["change_point_plot"] = branch_plot(
        unwr, {k: np.degrees(_wrap(v - xs)) for k, v in modes.items()}, eng_series, sing_x,
        "parallelogram four-bar through its change points", "rocker angle - crank angle (deg)")

    # --- long run -----------------------------------------------------------------
    per = pd.concat([pd.DataFrame(r.get("per_rev", {})) for r in long_res if r.get("per_rev")],
                    ignore_index=True) if any(r.get("per_rev") for r in long_res) \
        else pd.DataFrame(columns=["engine", "revolution"])
    out["long_run"] = per
    summ = pd.DataFrame([r["summary"] for r in long_res])
    summ.insert(2, "label", [plan["long_run"][r["summary"]["engine"]][0] for r in long_res])
    out["long_run_summary"] = summ
    out["long_run_revolutions"] = R_long
    out["long_run_plot"] = long_run_plot(
        per, f"seed-four-bar, {R_long} revolutions"
        + (" (quick mode; the full study runs 1000)" if quick else ""))
    if len(per):
        series = {}
        for eng, g in per.groupby("engine"):
            series[f"{eng} loop gap / size"] = g["loop_violation"].to_numpy()
            series[f"{eng} |crank rate err|"] = g["speed_deviation"].to_numpy()
            series[f"{eng} |energy balance|"] = g["energy_balance"].to_numpy()
        t = per.groupby("engine")["time"].apply(np.asarray)
        tt = t.iloc[int(np.argmax([len(x) for x in t]))]
        series = {k: np.pad(v, (0, len(tt) - len(v)), constant_values=np.nan)
                  for k, v in series.items()}
        out["long_run_timeseries"] = timeseries_plot(
            tt, series, f"seed-four-bar long run ({R_long} revolutions)", "relative")
    notes.append(f"long run: {R_long} revolutions of seed-four-bar"
                 + (" (quick mode; the full study runs 1000)" if quick else ""))
    notes.append("change point: row 'analytic' is the reference solution of the verdict "
                 f"runs (Linkage.kinematics); it follows {an['branches']}")
    out["notes"] = "; ".join(notes)
    return out


def _sample_error_figure(rows: list[dict], title: str, twin) -> bytes:
    from reports.figures.plots import error_plot
    errors, x = {}, None
    for r in rows:
        smp = r.get("samples")
        if not smp or not r.get("ok"):
            continue
        xi = np.mod(np.array(smp["input_deg"]), 360.0)
        order = np.argsort(xi)
        if x is None:
            x = xi[order]
        for k in ("alpha", "force"):
            if k in smp:
                errors[f"{r['engine']} {r['label']} {k}"] = np.interp(
                    x, xi[order], np.array(smp[k])[order])
    if x is None:
        x, errors = np.array([0.0, 360.0]), {"no successful run": np.array([np.nan, np.nan])}
    tw = None
    if twin is not None:
        label, tx, ty = twin
        tx = np.mod(tx, 360.0)
        o = np.argsort(tx)
        tw = (label, np.interp(x, tx[o], ty[o]))
    return error_plot(x, errors, tw, title)


# ============================================================================ scene economy
SCENE_VARIANTS = {
    "minimal": "the project's scene: contacts off, no gravity, one capsule per link",
    "contacts": "contacts on, link capsules collidable in stacked z layers, pin pairs "
                "excluded",
    "contacts-same-plane": "contacts on, link capsules collidable, all in z = 0, pin pairs "
                           "excluded",
    "contacts-no-excludes": "contacts on, link capsules collidable, all in z = 0, no pin "
                            "excludes",
    "gravity": "gravity (0, -9.81) m/s^2 in the engine and the analytic reference",
    "extra-visual": "24 extra visual geoms per moving link (no collision)",
    "extra-collision": "24 extra collidable geoms per link in stacked layers, contacts on, "
                       "pin pairs excluded",
    "everything": "extra collidable geoms, contacts on, gravity on",
}


#: scene variant -> (MujocoSettings.scene, gravity in the description)
SCENE_PARTS = {
    "minimal": ("minimal", False), "contacts": ("contacts", False),
    "contacts-same-plane": ("contacts-same-plane", False),
    "contacts-no-excludes": ("contacts-no-excludes", False), "gravity": ("minimal", True),
    "extra-visual": ("extra-visual", False), "extra-collision": ("extra-collision", False),
    "everything": ("extra-collision", True),
}


def scene_task(case_name: str, variant: str, settings_dict: dict, timing_steps: int,
               repeats: int) -> dict:
    """One scene variant (:data:`SCENE_VARIANTS`; the MuJoCo scene is a setting,
    :attr:`sim_models.mjcf.MujocoSettings.scene`): errors and speed, through the verdict
    runs' session.  Never raises."""
    from sim_models import compile_linkage
    from sim_models.engines import run
    try:
        scene, gravity = SCENE_PARTS[variant]
        mech0 = load(case_name)
        mech = replace(mech0, gravity=(0.0, -9.81)) if gravity else mech0
        tree = compile_linkage(mech)
        s = make_settings("mujoco", dict(settings_dict, scene=scene))
        r = run(tree, "mujoco", s)  # the run request's defaults
        e = run_errors(r, tree.linkage)
        notes = [SCENE_VARIANTS[variant]]
        if mech is not mech0 and r.ok:
            e0 = run_errors(r, mech0)
            notes.append(f"against the gravity-free description: accel {e0['accel_error']:.2g},"
                         f" force {e0['force_error']:.2g}")
        sps = time_engine(tree, "mujoco", s, r.timestep, timing_steps, repeats)
        return dict(variant=variant, seconds_per_rev=r.steps_per_rev / sps if sps else math.nan,
                    steps_per_second=sps, accel_error=e["accel_error"],
                    force_error=e["force_error"], error=e["error"],
                    ngeom=int(r.extra.get("ngeom", 0)),
                    max_contacts=int(r.extra.get("max_contacts", 0)), ok=r.ok,
                    reason=r.reason or "", notes="; ".join(notes))
    except Exception as ex:  # noqa: BLE001
        return dict(variant=variant, seconds_per_rev=math.nan, steps_per_second=math.nan,
                    accel_error=math.inf, force_error=math.inf, error=math.inf, ngeom=0,
                    max_contacts=0, ok=False, reason=f"{type(ex).__name__}: {ex}",
                    notes=SCENE_VARIANTS.get(variant, ""))


def scene_economy(quick: bool, case: str = "seed-four-bar") -> pd.DataFrame:
    """``case`` in MuJoCo (the project's default settings) with the minimal scene and
    with unneeded parts added (:data:`SCENE_VARIANTS`).  Columns ``variant,
    seconds_per_rev, steps_per_second, accel_error, force_error, error, ngeom,
    max_contacts, ok, reason, notes`` plus ``slowdown`` (time / the minimal scene's).
    Runs serially (timings of the variants side by side on one core)."""
    from sim_models.mjcf import MujocoSettings
    sd = asdict(MujocoSettings())
    steps, reps = (2000, 3) if quick else (6000, 5)
    rows = [scene_task(case, v, sd, steps, reps) for v in SCENE_VARIANTS]
    df = pd.DataFrame(rows)
    base = df.loc[df["variant"] == "minimal", "seconds_per_rev"]
    df["slowdown"] = df["seconds_per_rev"] / float(base.iloc[0]) if len(base) else math.nan
    cols = ["variant", "seconds_per_rev", "slowdown", "steps_per_second", "accel_error",
            "force_error", "error", "ngeom", "max_contacts", "ok", "reason", "notes"]
    return df[cols]


def scene_figure(scene: pd.DataFrame) -> bytes:
    from reports.figures.plots import pareto_plot
    rows = [dict(engine="mujoco", label=r.variant, seconds_per_rev=r.seconds_per_rev,
                 error=r.error) for r in scene.itertuples()
            if np.isfinite(r.seconds_per_rev)]
    return pareto_plot(rows, "seed-four-bar in MuJoCo: what the unneeded scene parts cost")


# ============================================================================ whole study
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
