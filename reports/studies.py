"""Speed against error: settings grids, hard cases, a long run and scene economy.

Pure functions returning pandas DataFrames and PNG bytes::

    from reports import studies
    grid = studies.speed_error_grid("seed-four-bar", quick=True)   # one row per setting
    table = studies.cheapest_settings(grid)                        # per engine and tolerance
    t_an = studies.analytic_seconds_per_rev("seed-four-bar")
    hard = studies.hard_cases(quick=True)                          # dict of frames and PNGs
    scene = studies.scene_economy(quick=True)
    everything = studies.run_study(quick=True)                     # all of it + figures

``python -m reports.studies [--quick] [--out DIR] [--workers N]`` runs the whole study
and writes CSV tables and PNG figures.

Measurements
------------
* **Errors** come from one engine run per setting (:func:`sim_models.engines.run`,
  ``revolutions`` turns, the last sampled at the analytic sweep's input values) and the
  project's comparison helper :func:`reports.compare.compare_run`: every quantity's
  largest error divided by its peak over the cycle.  ``accel_error`` is the worst of
  the bodies' angular accelerations and the sliders' accelerations, ``force_error``
  the worst of the drive effort and every joint force (the values this project derives
  from the engine, not the engines' own defective readings); ``error`` is the larger.
* **Speed** is timed separately, on a bare stepping loop of the same compiled model
  from Python (``mj_step`` / ``stepSimulation``, no readout), so that the cost of the
  36-72 samples and their Newton-Euler reconstruction does not swamp coarse steps:
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
worker, e.g. from :mod:`reports.report`'s tasks), any ``concurrent.futures.Executor``
(e.g. a dask client's ``get_executor()``) is used as given, and ``False`` runs them
serially in this process.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import multiprocessing
import os
import sys
import time
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd

from analytic import Linkage, Mechanism, load_case
from analytic.cases import case_names
from analytic.sweep import input_values

#: Tolerances of the cheapest-setting table (max normalised error).
TOLERANCES = (1e-2, 1e-3, 1e-4)
#: The mechanism descriptions of the hard cases.
HARD_CASES_DIR = Path(__file__).parent / "hard_cases"
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
def case_source(case: str) -> str:
    """What :func:`analytic.load_case` needs for ``case``: a built-in name, the name of a
    hard case in :data:`HARD_CASES_DIR` (``near-toggle-four-bar``,
    ``parallelogram-four-bar``) or a path to a mechanism TOML file."""
    s = str(case)
    if s in case_names():
        return s
    p = HARD_CASES_DIR / f"{s}.toml"
    if p.is_file():
        return str(p)
    return s


def hard_case_names() -> list[str]:
    return sorted(p.stem for p in HARD_CASES_DIR.glob("*.toml"))


def load(case: str) -> Mechanism:
    return load_case(case_source(case))


def revolution_time(mech: Mechanism) -> float:
    """Duration of the first revolution of a revolute driver (s)."""
    d = mech.driver
    if d.acceleration == 0.0:
        return 2 * math.pi / abs(d.velocity)
    sgn = math.copysign(1.0, d.velocity if d.velocity else d.acceleration)
    # value(t) - value0 = sgn 2 pi, smallest positive root
    a, b, c = 0.5 * d.acceleration, d.velocity, -sgn * 2 * math.pi
    disc = b * b - 4 * a * c
    roots = [(-b + s * math.sqrt(max(disc, 0.0))) / (2 * a) for s in (-1, 1)]
    return min(r for r in roots if r > 0)


# ============================================================================ settings
def _mujoco_settings(d: dict):
    from sim_models.mjcf import MujocoSettings
    d = dict(d)
    for k in ("solref", "solimp"):
        if k in d:
            d[k] = tuple(d[k])
    return MujocoSettings(**d)


def _pybullet_settings(d: dict):
    from sim_models.pybullet_sim import PybulletSettings
    return PybulletSettings(**d)


def make_settings(engine: str, settings: dict):
    """``MujocoSettings`` / ``PybulletSettings`` from a plain dict of their fields."""
    return _mujoco_settings(settings) if engine == "mujoco" else _pybullet_settings(settings)


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
    else:
        mj_spr, pb_spr = (30, 100, 300, 1000, 3000, 10000), (100, 300, 1000, 3000, 10000,
                                                               30000)
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
    return plan


# ============================================================================ errors
def run_errors(run_, mech: Mechanism) -> dict:
    """Normalised errors of an engine run through :func:`reports.compare.compare_run`."""
    from reports.compare import compare_run
    if not run_.ok:
        return dict(accel_error=math.inf, force_error=math.inf, error=math.inf,
                    worst_quantity="", worst_at=math.nan)
    comps = [c for c in compare_run(run_, mech) if not c.quantity.endswith("[engine]")]
    acc = [c for c in comps if c.quantity.endswith(".alpha") or c.quantity.endswith(".a")]
    frc = [c for c in comps if c.quantity == "drive.effort" or c.quantity.endswith(".force")]
    a = max((c.normalised for c in acc), default=math.nan)
    f = max((c.normalised for c in frc), default=math.nan)
    worst = max(comps, key=lambda c: c.normalised if np.isfinite(c.normalised) else math.inf,
                default=None)
    both = [x for x in (a, f) if not math.isnan(x)]
    err = max(both) if both else math.nan
    return dict(accel_error=float(a), force_error=float(f), error=err,
                worst_quantity=worst.quantity if worst else "",
                worst_at=float(worst.at) if worst else math.nan)


def sample_errors(run_, mech: Mechanism) -> dict[str, np.ndarray]:
    """Per-sample normalised errors of a run (for plots): ``alpha`` (worst body, by the
    largest body peak) and ``force`` (worst of the drive effort and each joint force,
    each by its own peak), NaN where the run has no value."""
    lk = Linkage(mech)
    vel = np.where(np.isfinite(run_.driver_velocity), run_.driver_velocity,
                   mech.driver.velocity)
    kin = lk.kinematics(run_.values, vel, run_.driver_acceleration, on_singular="flag")
    moving = [b for b, n in enumerate(run_.body_names) if n != mech.ground]
    pk = np.nanmax(np.abs(kin.alpha[:, moving]))
    out = {"alpha": np.max(np.abs(run_.alpha[:, moving] - kin.alpha[:, moving]), axis=1) / pk}
    if run_.has_forces and mech.has_mass:
        frc = lk.forces(kin)
        e = np.abs(run_.drive_effort - frc.effort) / np.nanmax(np.abs(frc.effort))
        for j, name in enumerate(run_.joint_names):
            ref = frc.joint_force[name]
            e = np.fmax(e, np.linalg.norm(run_.joint_force[:, j] - ref, axis=1)
                        / np.nanmax(np.linalg.norm(ref, axis=1)))
        out["force"] = e
    return out


# ============================================================================ timing
@contextlib.contextmanager
def _quiet_mujoco():
    """Collect MuJoCo warnings instead of writing MUJOCO_LOG.TXT."""
    from sim_models.mjcf import require_mujoco
    mujoco = require_mujoco()
    msgs: list[str] = []
    old = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(msgs.append)
    try:
        yield msgs
    finally:
        mujoco.set_mju_user_warning(old)


def _mujoco_model(mech: Mechanism, settings, st=None, spec_hook=None):
    from sim_models.mjcf import build_mjcf, compile_spec
    from sim_models.tree import SimTree
    st = st or SimTree(mech)
    spec = build_mjcf(mech, settings, tree=st)
    if spec_hook is not None:
        spec_hook(spec, st)
    model, _ = compile_spec(spec, settings)
    return st, model


def time_mujoco(mech: Mechanism, settings, dt: float, steps: int, repeats: int = 3,
                spec_hook=None) -> float:
    """Steps per second of a bare ``mj_step`` loop from the reference state (best of
    ``repeats``; a loop that goes non-finite is timed up to that point)."""
    from sim_models.mjcf import require_mujoco
    mujoco = require_mujoco()
    with _quiet_mujoco():
        st, m = _mujoco_model(mech, settings, spec_hook=spec_hook)
        m.opt.timestep = dt
        d = mujoco.MjData(m)
        qadr = np.array([m.joint(tj.name).qposadr[0] for tj in st.joints])
        dadr = np.array([m.joint(tj.name).dofadr[0] for tj in st.joints])
        _, qd0, _ = st.coords(st.kin_ref)
        best = 0.0
        step = mujoco.mj_step
        chunk = max(1, min(steps, 200))
        for _ in range(max(1, repeats)):
            mujoco.mj_resetData(m, d)
            d.qpos[qadr] = 0.0
            d.qvel[dadr] = qd0[0]
            done = 0
            t0 = time.perf_counter()
            while done < steps:
                for _ in range(min(chunk, steps - done)):
                    step(m, d)
                done += min(chunk, steps - done)
                if not np.isfinite(d.qvel).all():
                    break
            el = time.perf_counter() - t0
            if el > 0:
                best = max(best, done / el)
    return best


def time_pybullet(mech: Mechanism, settings, dt: float, steps: int, repeats: int = 3) -> float:
    """Steps per second of a bare ``stepSimulation`` loop from the reference state."""
    from sim_models.pybullet_sim import PybulletSim
    from sim_models.tree import SimTree
    st = SimTree(mech)
    best = 0.0
    for _ in range(max(1, repeats)):
        sim = PybulletSim(st, settings)
        try:
            p, cid = sim.p, sim.cid
            q0, qd0, _ = st.coords(st.kin_ref)
            sim.set_state(np.zeros_like(q0[0]), qd0[0])
            sim.set_drive(mech.driver.velocity)
            p.setPhysicsEngineParameter(fixedTimeStep=dt, physicsClientId=cid)
            step = p.stepSimulation
            t0 = time.perf_counter()
            for _ in range(steps):
                step(physicsClientId=cid)
            el = time.perf_counter() - t0
        finally:
            sim.close()
        if el > 0:
            best = max(best, steps / el)
    return best


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
              revolutions: int = 2, samples: int = 36, timing_steps: int = 5000,
              timing_repeats: int = 3, meta: dict | None = None,
              keep_samples: bool = False) -> dict:
    """One engine run at one setting: errors (engine run + :func:`run_errors`) and speed
    (bare stepping loop).  Never raises: failures are rows with ``ok = False``."""
    meta = dict(meta or {})
    meta.update(case=case_name, engine=engine, label=label, settings_dict=settings_dict)
    try:
        from sim_models.engines import run
        mech = load(case_name)
        s = make_settings(engine, settings_dict)
        r = run(mech, engine, s, revolutions=revolutions, samples=samples)
        row = {k: meta.get(k) for k in GRID_COLUMNS}
        row.update(case=case_name, engine=engine, label=label, settings=s.describe(),
                   timestep=float(r.timestep), steps_per_rev=float(r.steps_per_rev),
                   run_seconds_per_rev=float(r.wall_per_rev), ok=bool(r.ok),
                   reason=r.reason or "")
        row.update(run_errors(r, mech))
        n = int(min(max(1, round(r.steps_per_rev)), timing_steps))
        try:
            if engine == "mujoco":
                sps = time_mujoco(mech, s, r.timestep, n, timing_repeats)
            else:
                sps = time_pybullet(mech, s, r.timestep, n, timing_repeats)
        except Exception as e:  # timing is secondary: keep the errors
            sps = math.nan
            row["reason"] = (row["reason"] + "; " if row["reason"] else "") + \
                f"timing failed: {type(e).__name__}: {e}"
        row["steps_per_second"] = float(sps)
        row["seconds_per_rev"] = float(r.steps_per_rev / sps) if sps and sps > 0 else math.nan
        if keep_samples:
            row["samples"] = {"input_deg": np.degrees(r.values).tolist(),
                              **{k: v.tolist() for k, v in sample_errors(r, mech).items()}}
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
        # already inside a worker (e.g. a task of reports.report's pool, or a daemonic
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
    from .study_plots import pareto_frontier_plot
    w = load(case).driver.velocity
    return pareto_frontier_plot(grid, f"{case} (omega2 = {w:g} rad/s): speed against error",
                                analytic_time)


# ============================================================================ low-level loop
@dataclass
class Trace:
    """Raw samples of a low-level engine loop (tree coordinates, SI)."""

    engine: str
    settings: str
    t: np.ndarray          # (N,) s
    q: np.ndarray          # (N, nt)
    qd: np.ndarray         # (N, nt)
    qdd: np.ndarray        # (N, nt)
    effort: np.ndarray     # (N,) drive effort on body_b, N m
    ok: bool
    reason: str
    wall: float            # s of the whole loop (stepping and sampling)
    steps: int
    dt: float
    per_rev: int


def _check_state(st, q, qd, vmax: float, w: float, wmax: float) -> str | None:
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
        return "non-finite state (simulation diverged)"
    th, _, _, org, _, _ = st.propagate(q[None], qd[None], np.zeros_like(q)[None])
    for ch in st.chords:
        gap = float(np.linalg.norm(st.point_world(th, org, ch.body_a, ch.point_a)[0]
                                   - st.point_world(th, org, ch.body_b, ch.point_b)[0]))
        if gap > vmax:
            return f"loop violation {gap:.3g} m > {vmax:.3g} m"
    rate = st.driver_sigma * qd[st.driver_tree]
    if abs(rate - w) > wmax * abs(w):
        return f"driver rate off by {abs(rate - w):.3g} rad/s (> {wmax:g} relative)"
    return None


def _loop_args(mech: Mechanism, dt_max: float, per_rev: int):
    if mech.loads or mech.driver.acceleration != 0.0:
        raise ValueError("the low-level loop supports constant-speed drivers without loads")
    T = revolution_time(mech)
    interval = T / per_rev
    n = max(1, math.ceil(interval / dt_max - 1e-9))
    return T, n, interval / n


def _long_run_buffers(revolutions: int, per_rev: int, T: float, nt: int):
    """Sample count, sample times and NaN-filled q, q', q'' (per tree joint) and drive
    effort buffers of a long run sampled ``per_rev`` times a revolution of period T."""
    N = revolutions * per_rev + 1
    nan = np.nan
    return (N, np.arange(N) * T / per_rev, np.full((N, nt), nan), np.full((N, nt), nan),
            np.full((N, nt), nan), np.full(N, nan))


def trace_mujoco(mech: Mechanism, settings_dict: dict, revolutions: int,
                 per_rev: int = LONG_RUN_SAMPLES, max_violation: float = 1e-3,
                 max_speed_error: float = 1e-2) -> Trace:
    """Step MuJoCo ``revolutions`` turns from the reference state and sample the tree
    coordinates, their rates and accelerations (``mj_forward`` at the sample) and the
    armature drive's effort ``per_rev`` times per turn.  Stops at a divergence."""
    from sim_models.mjcf import require_mujoco
    mujoco = require_mujoco()
    s = _mujoco_settings(settings_dict)
    T, n, h = _loop_args(mech, s.timestep, per_rev)
    with _quiet_mujoco():
        st, m = _mujoco_model(mech, s)
        m.opt.timestep = h
        d = mujoco.MjData(m)
        qadr = np.array([m.joint(tj.name).qposadr[0] for tj in st.joints])
        dadr = np.array([m.joint(tj.name).dofadr[0] for tj in st.joints])
        ddof = int(dadr[st.driver_tree])
        _, qd0, _ = st.coords(st.kin_ref)
        d.qpos[qadr] = 0.0
        d.qvel[dadr] = qd0[0]
        A, sig = float(s.armature), st.driver_sigma
        N, t, q, qd, qdd, eff = _long_run_buffers(revolutions, per_rev, T, len(st.joints))
        w = mech.driver.velocity
        vmax = max_violation * st.size
        reason, steps = None, 0
        step, fwd = mujoco.mj_step, mujoco.mj_forward
        t0 = time.perf_counter()
        for k in range(N):
            fwd(m, d)
            q[k], qd[k], qdd[k] = d.qpos[qadr], d.qvel[dadr], d.qacc[dadr]
            eff[k] = sig * A * (0.0 - d.qacc[ddof])
            reason = _check_state(st, q[k], qd[k], vmax, w, max_speed_error)
            if reason is None and d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number:
                reason = "MuJoCo reported bad qacc (simulation diverged)"
            if reason is not None:
                reason = f"{reason} at t = {t[k]:.4g} s (revolution {k / per_rev:.2f})"
                break
            if k == N - 1:
                break
            for _ in range(n):
                step(m, d)
            steps += n
        wall = time.perf_counter() - t0
    K = k + 1 if reason is None else k
    return Trace("mujoco", s.describe(), t[:K], q[:K], qd[:K], qdd[:K], eff[:K],
                 reason is None, reason or "", wall, steps, h, per_rev)


def trace_pybullet(mech: Mechanism, settings_dict: dict, revolutions: int,
                   per_rev: int = LONG_RUN_SAMPLES, max_violation: float = 1e-3,
                   max_speed_error: float = 1e-2) -> Trace:
    """Step PyBullet ``revolutions`` turns (after the usual pre-roll from the analytic
    state) and sample like :func:`sim_models.engines.run`: positions at the sample,
    accelerations ``(v_{n+1} - v_n) / dt``, midpoint velocity, the drive effort from the
    velocity motor's torque (impulse / dt of the step after the sample)."""
    from sim_models.pybullet_sim import PybulletSim
    from sim_models.tree import SimTree
    s = _pybullet_settings(settings_dict)
    T, n, h = _loop_args(mech, s.timestep, per_rev)
    st = SimTree(mech)
    sim = PybulletSim(st, s)
    p, cid, body, jidx = sim.p, sim.cid, sim.body, sim.jidx
    drv = mech.driver
    try:
        # pre-roll (PybulletSettings.preroll_steps) from the analytic state of that earlier
        # time, unless the analytic solution there is not the continuation of the
        # reference pose (it holds its dyad signs, so it changes assembly mode at a
        # change point): then start at the reference without pre-roll
        n_pre = max(int(s.preroll_steps), 0)
        t_pre = -n_pre * h
        q0, qd0, _ = st.coords(st.kin_ref)
        q0 = np.zeros_like(q0)
        if n_pre:
            try:
                kin = st.linkage.kinematics(drv.value + drv.velocity * t_pre, drv.velocity, 0.0)
                guess = st.theta_ref + st.kin_ref.omega[0] * t_pre
                if np.max(np.abs(_wrap(kin.theta[0] - guess))) < math.radians(5.0):
                    q0, qd0, _ = st.coords(kin)
                else:
                    n_pre = 0
            except Exception:  # noqa: BLE001 - e.g. an infeasible earlier input
                n_pre = 0
        sim.set_state(q0[0], qd0[0])
        sim.set_drive(drv.velocity)
        p.setPhysicsEngineParameter(fixedTimeStep=h, physicsClientId=cid)
        step = p.stepSimulation
        for _ in range(n_pre):
            step(physicsClientId=cid)
        N, t, q, qd, qdd, eff = _long_run_buffers(revolutions, per_rev, T, len(st.joints))
        sig = st.driver_sigma
        vmax = max_violation * st.size
        reason, steps = None, n_pre

        def states():
            ss = p.getJointStates(body, jidx, physicsClientId=cid)
            return (np.array([x[0] for x in ss]), np.array([x[1] for x in ss]),
                    ss[st.driver_tree][3])

        t0 = time.perf_counter()
        for k in range(N):
            qk, vk, _ = states()
            step(physicsClientId=cid)
            _, v1, tau = states()
            q[k], qd[k], qdd[k] = qk, 0.5 * (vk + v1), (v1 - vk) / h
            eff[k] = sig * tau
            reason = _check_state(st, q[k], qd[k], vmax, drv.velocity, max_speed_error)
            if reason is not None:
                reason = f"{reason} at t = {t[k]:.4g} s (revolution {k / per_rev:.2f})"
                break
            steps += n
            if k == N - 1:
                break
            for _ in range(n - 1):
                step(physicsClientId=cid)
        wall = time.perf_counter() - t0
    finally:
        sim.close()
    K = k + 1 if reason is None else k
    return Trace("pybullet", s.describe(), t[:K], q[:K], qd[:K], qdd[:K], eff[:K],
                 reason is None, reason or "", wall, steps, h, per_rev)


def trace_diagnostics(mech: Mechanism, tr: Trace, analytic: bool = True) -> pd.DataFrame:
    """Per-sample diagnostics of a :class:`Trace` (one row per sample):

    ``t``, ``input_deg`` (the engine's own driver angle), ``phase_drift`` (engine driver
    angle minus the prescribed one, rad), ``loop_violation`` (largest loop gap / the
    mechanism's size), ``speed_deviation`` ((rate - omega) / omega), ``ke`` (J, the
    engine's body velocities and the engine's mass properties), ``drive_power`` (W),
    ``power_residual`` (drive + gravity power - dKE/dt, relative to the analytic peak
    drive power), ``energy_balance`` (drive + gravity work, trapezoid rule over the
    samples, minus the change of KE, relative to the analytic drive throughput
    ``integral |P| dt`` of one revolution), ``theta.<body>`` (deg, unwrapped) and, with
    ``analytic``, ``alpha_error`` and ``effort_error`` against the analytic solution at
    the engine's driver angle (normalised by the analytic peaks over a revolution).
    """
    from sim_models.tree import SimTree
    st = SimTree(mech)
    lk = st.linkage
    th, om, al, org, v, a = st.propagate(tr.q, tr.qd, tr.qdd)
    w = mech.driver.velocity
    x = st.driver_value(tr.q[:, st.driver_tree])
    presc = mech.driver.value + w * tr.t
    rate = st.driver_sigma * tr.qd[:, st.driver_tree]
    gap = np.zeros(len(tr.t))
    for ch in st.chords:
        gap = np.maximum(gap, np.linalg.norm(st.point_world(th, org, ch.body_a, ch.point_a)
                                             - st.point_world(th, org, ch.body_b, ch.point_b),
                                             axis=1))
    g = np.asarray(mech.gravity, float)
    ke = np.zeros(len(tr.t))
    dke = np.zeros(len(tr.t))
    pg = np.zeros(len(tr.t))
    for b in range(len(st.body_names)):
        if b == st.ground:
            continue
        c = st.com[b]
        cs, sn = np.cos(th[:, b]), np.sin(th[:, b])
        r = np.stack([cs * c[0] - sn * c[1], sn * c[0] + cs * c[1]], axis=1)
        rp = np.stack([-r[:, 1], r[:, 0]], axis=1)
        vc = v[:, b] + om[:, b, None] * rp
        ac = a[:, b] + al[:, b, None] * rp - (om[:, b] ** 2)[:, None] * r
        m_, I_ = st.mass[b], st.inertia[b]
        ke += 0.5 * m_ * np.sum(vc * vc, axis=1) + 0.5 * I_ * om[:, b] ** 2
        dke += m_ * np.sum(vc * ac, axis=1) + I_ * om[:, b] * al[:, b]
        pg += m_ * vc @ g
    power = tr.effort * rate
    # analytic scales over one revolution
    kin1 = frc1 = None
    p_peak = throughput = math.nan
    if analytic:
        vals, _, _ = input_values(lk, max(tr.per_rev, 36))
        kin1 = lk.kinematics(vals, on_singular="flag")
        frc1 = lk.forces(kin1) if mech.has_mass else None
        if frc1 is not None:
            p_peak = float(np.nanmax(np.abs(frc1.power)))
            throughput = float(np.nanmean(np.abs(frc1.power)) * revolution_time(mech))
    P = power + pg
    work = np.concatenate([[0.0], np.cumsum(0.5 * (P[1:] + P[:-1]) * np.diff(tr.t))])
    cols = {"t": tr.t, "input_deg": np.degrees(x), "phase_drift": x - presc,
            "loop_violation": gap / st.size, "speed_deviation": (rate - w) / abs(w), "ke": ke,
            "drive_power": power, "power_residual": (P - dke) / p_peak,
            "energy_balance": (work - (ke - ke[0])) / throughput}
    for b, name in enumerate(st.body_names):
        if b != st.ground:
            cols[f"theta.{name}"] = np.degrees(th[:, b])
    if analytic:
        kin = lk.kinematics(x, np.full(len(x), w), np.zeros(len(x)), on_singular="flag")
        moving = [b for b in range(len(st.body_names)) if b != st.ground]
        pk = float(np.nanmax(np.abs(kin1.alpha[:, moving])))
        cols["alpha_error"] = np.max(np.abs(al[:, moving] - kin.alpha[:, moving]), axis=1) / pk
        if frc1 is not None:
            frc = lk.forces(kin)
            cols["effort_error"] = np.abs(tr.effort - frc.effort) / \
                float(np.nanmax(np.abs(frc1.effort)))
    return pd.DataFrame(cols)


def _trace(case_name: str, engine: str, settings_dict: dict, revolutions: int,
           per_rev: int, max_violation: float = 1e-3) -> Trace:
    mech = load(case_name)
    fn = trace_mujoco if engine == "mujoco" else trace_pybullet
    return fn(mech, settings_dict, revolutions, per_rev, max_violation=max_violation)


# ============================================================================ long run
def long_run_task(case_name: str, engine: str, settings_dict: dict, revolutions: int,
                  per_rev: int = LONG_RUN_SAMPLES) -> dict:
    """A long run: per-revolution diagnostics (:func:`trace_diagnostics` reduced to the
    worst value in each revolution; ``energy_balance`` and ``phase_drift`` at its end)
    plus a summary.  Never raises."""
    meta = dict(case=case_name, engine=engine, settings_dict=settings_dict)
    try:
        mech = load(case_name)
        tr = _trace(case_name, engine, settings_dict, revolutions, per_rev)
        diag = trace_diagnostics(mech, tr)
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


# ============================================================================ change point
def four_bar_modes(mech: Mechanism, theta2) -> dict[str, np.ndarray]:
    """Both assembly modes of a four-revolute four-bar driven at the ground: the output
    (rocker) body's angle for each driver angle (rad).  ``"parallelogram"`` is the
    circle intersection whose rocker angle is nearer the crank's (rocker parallel to
    the crank), ``"anti-parallelogram"`` the other; for other four-bars they are simply
    the two assembly modes in that order."""
    from sim_models.tree import SimTree
    st = SimTree(mech)
    topo = st.linkage.topo
    dj = mech.driver_joint
    g = mech.ground
    crank = dj.body_b if dj.body_a == g else dj.body_a
    ground_j = [j for j in mech.joints if g in j.bodies and j.name != dj.name]
    rocker_j = ground_j[0]
    rocker = rocker_j.body_b if rocker_j.body_a == g else rocker_j.body_a
    cj = next(j for j in mech.joints if crank in j.bodies and j.name != dj.name)
    coupler = cj.body_b if cj.body_a == crank else cj.body_a
    rj = next(j for j in mech.joints if rocker in j.bodies and coupler in j.bodies)
    names = st.body_names
    ig, ic, ir, iu = (names.index(x) for x in (g, crank, rocker, coupler))
    k = {j.name: i for i, j in enumerate(mech.joints)}
    O2g = np.asarray(topo.attach(k[dj.name], ig), float)
    O4g = np.asarray(topo.attach(k[rocker_j.name], ig), float)
    O2c = np.asarray(topo.attach(k[dj.name], ic), float)
    Ac = np.asarray(topo.attach(k[cj.name], ic), float)
    Au = np.asarray(topo.attach(k[cj.name], iu), float)
    Bu = np.asarray(topo.attach(k[rj.name], iu), float)
    O4r = np.asarray(topo.attach(k[rocker_j.name], ir), float)
    Br = np.asarray(topo.attach(k[rj.name], ir), float)
    b = np.linalg.norm(Bu - Au)
    c = np.linalg.norm(Br - O4r)
    beta_c = math.atan2(*(Ac - O2c)[::-1])      # crank body angle -> direction O2A
    beta_r = math.atan2(*(Br - O4r)[::-1])      # rocker body angle -> direction O4B
    th = np.atleast_1d(np.asarray(theta2, float))  # crank body angle
    gth = st.theta_ref[ig]
    O2 = st.origin_ref[ig] + np.array([[math.cos(gth), -math.sin(gth)],
                                       [math.sin(gth), math.cos(gth)]]) @ O2g
    O4 = st.origin_ref[ig] + np.array([[math.cos(gth), -math.sin(gth)],
                                       [math.sin(gth), math.cos(gth)]]) @ O4g
    ra = np.linalg.norm(Ac - O2c)
    A = O2 + ra * np.stack([np.cos(th + beta_c), np.sin(th + beta_c)], axis=1)
    dvec = O4 - A
    dist = np.linalg.norm(dvec, axis=1)
    # B = A + along * u + / - across * n  (circle |B - A| = b, |B - O4| = c)
    along = (dist ** 2 + b ** 2 - c ** 2) / (2 * dist)
    across = np.sqrt(np.maximum(b ** 2 - along ** 2, 0.0))
    u = dvec / dist[:, None]
    nvec = np.stack([-u[:, 1], u[:, 0]], axis=1)
    sols = []
    for sgn in (1.0, -1.0):
        B = A + along[:, None] * u + sgn * across[:, None] * nvec
        ang = np.arctan2(B[:, 1] - O4[1], B[:, 0] - O4[0]) - beta_r
        sols.append(ang)
    # the crank's direction O2A, compared with the rocker's direction O4B
    crank_dir = th + beta_c
    d0 = np.abs(_wrap(sols[0] + beta_r - crank_dir))
    d1 = np.abs(_wrap(sols[1] + beta_r - crank_dir))
    para = np.where(d0 <= d1, sols[0], sols[1])
    anti = np.where(d0 <= d1, sols[1], sols[0])
    return {"parallelogram": para, "anti-parallelogram": anti}


def _wrap(a):
    return np.pi - np.mod(np.pi - np.asarray(a, float), 2 * np.pi)


def classify_branch(theta2, rocker, modes: dict[str, np.ndarray], singular_deg,
                    exclude_deg: float = 15.0, tol_deg: float = 5.0) -> list[dict]:
    """Label each stretch between singular positions: ``parallelogram``,
    ``anti-parallelogram`` or ``diverged``.

    ``theta2`` is the unwrapped input (rad), ``rocker`` the rocker angle (rad, NaN where
    the run had failed), ``modes`` from :func:`four_bar_modes`, ``singular_deg`` the
    singular input angles (deg, mod 360).  Samples within ``exclude_deg`` of a singular
    position are left out (the modes meet there); a stretch is a branch when every
    remaining sample is within ``min(tol_deg, half the modes' separation)`` of it.
    """
    x = np.degrees(np.asarray(theta2, float))
    lo, hi = float(np.nanmin(x)), float(np.nanmax(x))
    sing = sorted({s + 360 * k for s in singular_deg for k in range(-2, 100)
                   if lo < s + 360 * k < hi})
    edges = [lo - 1e-9] + sing + [hi + 1e-9]
    out = []
    names = list(modes)
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        sel = (x >= a) & (x <= b)
        near = np.zeros_like(sel)
        for s in sing:
            near |= np.abs(x - s) < exclude_deg
        use = sel & ~near
        label, worst = "diverged", math.nan
        if use.any():
            y = np.asarray(rocker)[use]
            dists = {n: np.degrees(np.abs(_wrap(y - modes[n][use]))) for n in names}
            sep = np.degrees(np.abs(_wrap(modes[names[0]][use] - modes[names[1]][use])))
            lim = np.minimum(tol_deg, 0.5 * sep)
            for n in names:
                if np.all(np.isfinite(dists[n])) and np.all(dists[n] <= lim):
                    label, worst = n, float(np.max(dists[n]))
                    break
            else:
                worst = float(np.nanmax(np.fmin(*dists.values()))) if np.isfinite(
                    np.fmin(*dists.values())).any() else math.inf
        out.append(dict(start_deg=a if a > lo else lo, end_deg=b if b < hi else hi,
                        branch=label, max_deviation_deg=worst, samples=int(use.sum())))
    return out


#: Loop gap (relative to the mechanism's size) that ends a change-point run: looser than
#: the engine runs' 1e-3 so that soft (stock) constraints still show a branch.
CHANGE_POINT_MAX_VIOLATION = 1e-2


def change_point_task(case_name: str, engine: str, settings_dict: dict, revolutions: int,
                      per_rev: int = 72) -> dict:
    """Run a change-point four-bar through its singular positions and label the branch
    the engine follows after each (see :func:`classify_branch`).  Never raises."""
    label = "diverged"
    try:
        mech = load(case_name)
        tr = _trace(case_name, engine, settings_dict, revolutions, per_rev,
                    CHANGE_POINT_MAX_VIOLATION)
        diag = trace_diagnostics(mech, tr, analytic=False)
        lk = Linkage(mech)
        sing = singular_inputs(lk)
        x = np.radians(diag["input_deg"].to_numpy())
        rocker_name = _rocker_name(mech)
        y = np.radians(diag[f"theta.{rocker_name}"].to_numpy())
        modes = four_bar_modes(mech, x)
        segs = classify_branch(x, y, modes, sing) if len(x) > 1 else []
        after = [s["branch"] for s in segs[1:]]
        if not tr.ok:
            # a stretch the run did not finish is a divergence
            full_x = np.degrees(mech.driver.value) + 360.0 * revolutions
            if segs and segs[-1]["end_deg"] < full_x - 1:
                segs[-1]["branch"] = "diverged"
                after = [s["branch"] for s in segs[1:]]
            if not after:
                after = ["diverged"]
        label = after[0] if after else "diverged"
        return dict(case=case_name, engine=engine, settings=tr.settings, ok=tr.ok,
                    reason=tr.reason, timestep=tr.dt, branch_after_singular=label,
                    final_branch=segs[-1]["branch"] if segs else "diverged",
                    branches=" > ".join(s["branch"] for s in segs),
                    flips=sum(1 for a, b in zip(segs[:-1], segs[1:], strict=False)
                              if a["branch"] != b["branch"]),
                    max_deviation_deg=max((s["max_deviation_deg"] for s in segs
                                           if np.isfinite(s["max_deviation_deg"])),
                                          default=math.nan),
                    max_loop_violation=float(diag["loop_violation"].max())
                    if len(diag) else math.nan,
                    revolutions=revolutions,
                    series={"input_deg": diag["input_deg"].tolist(),
                            "rocker_deg": np.degrees(y).tolist()},
                    segments=segs)
    except Exception as e:  # noqa: BLE001
        return dict(case=case_name, engine=engine, settings=str(settings_dict), ok=False,
                    reason=f"{type(e).__name__}: {e}", branch_after_singular=label,
                    branches="", flips=0, max_deviation_deg=math.nan,
                    max_loop_violation=math.nan, revolutions=revolutions, series=None,
                    segments=[])


def _rocker_name(mech: Mechanism) -> str:
    dj = mech.driver_joint
    g = mech.ground
    j = next(j for j in mech.joints if g in j.bodies and j.name != dj.name)
    return j.body_b if j.body_a == g else j.body_a


def singular_inputs(lk: Linkage, points: int = 3600) -> list[float]:
    """Input angles (deg, mod 360) of the singular positions of a sweep."""
    ev = lk.sweep(points, forces=False).events
    s = ev[ev["kind"] == "singular"]["input"].to_numpy(float)
    out: list[float] = []
    for v in np.mod(s, 360.0):
        if all(abs(_wrap(math.radians(v - o))) > 1e-3 for o in out):
            out.append(float(v))
    return sorted(out)


def analytic_branch(case_name: str, revolutions: int = 1, per_rev: int = 72) -> dict:
    """The branch the analytic solver's sweep follows after the singular position (its
    dyad sign is held, so it may cross over)."""
    mech = load(case_name)
    lk = Linkage(mech)
    x = mech.driver.value + 2 * np.pi * np.arange(revolutions * per_rev + 1) / per_rev
    kin = lk.kinematics(x, on_singular="flag")
    rb = mech.bodies.index(mech.body(_rocker_name(mech)))
    y = kin.theta[:, rb]
    modes = four_bar_modes(mech, x)
    segs = classify_branch(x, y, modes, singular_inputs(lk))
    return dict(case=case_name, engine="analytic (held dyad sign)", settings="Linkage.kinematics",
                ok=True, reason="", timestep=math.nan,
                branch_after_singular=segs[1]["branch"] if len(segs) > 1 else segs[0]["branch"],
                final_branch=segs[-1]["branch"], branches=" > ".join(s["branch"] for s in segs),
                flips=sum(1 for a, b in zip(segs[:-1], segs[1:], strict=False)
                          if a["branch"] != b["branch"]),
                max_deviation_deg=max(s["max_deviation_deg"] for s in segs),
                max_loop_violation=0.0, revolutions=revolutions,
                series={"input_deg": np.degrees(x).tolist(), "rocker_deg": np.degrees(y).tolist()},
                segments=segs)


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
      (``reports/hard_cases/near-toggle-four-bar.toml``) and the seed four-bar at the
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
    from .plots import timeseries_plot
    from .study_plots import branch_plot, long_run_plot
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
    cp_df["label"] = [m.get("label", "") for _, m in cp_f] + ["held dyad sign"]
    out["change_point"] = cp_df
    mech_cp = load("parallelogram-four-bar")
    xs = np.radians(np.array(an["series"]["input_deg"]))
    modes = four_bar_modes(mech_cp, xs)
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
    notes.append("change point: the analytic solver holds its dyad sign, so past the "
                 "singular position it follows the other assembly mode of the "
                 "parallelogram (row 'analytic (held dyad sign)')")
    out["notes"] = "; ".join(notes)
    return out


def _sample_error_figure(rows: list[dict], title: str, twin) -> bytes:
    from .plots import error_plot
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
def _jointed_pairs(mech: Mechanism, st) -> list[tuple[str, str]]:
    """Body pairs sharing a joint, with the ground called ``world`` (the MJCF name)."""
    pairs = set()
    for j in mech.joints:
        a, b = (j.guide, j.slider) if hasattr(j, "guide") else (j.body_a, j.body_b)
        a = "world" if a == mech.ground else a
        b = "world" if b == mech.ground else b
        pairs.add(tuple(sorted((a, b))))
    return sorted(pairs)


def scene_hook(variant: str, mech: Mechanism):
    """An ``MjSpec`` post-processor for a scene variant (``None`` when the description
    alone makes it: ``minimal``, ``gravity``).

    * ``contacts``: contact flag on, every geom collidable (contype = conaffinity = 1),
      each link's geoms in its own z layer (4 capsule radii apart, as the links of a
      real planar linkage are stacked) and ``exclude`` pairs for the bodies sharing a
      joint: contacts are detected but none occur;
    * ``contacts-same-plane``: the same with every link in the plane z = 0 (the
      coupler's capsule sweeps over the ground pivot O4);
    * ``contacts-no-excludes``: same plane and no excludes (capsules overlap at the pins);
    * ``extra-visual``: 24 extra non-colliding geoms per moving link (boxes, cylinders,
      ellipsoids along it), contacts off;
    * ``extra-collision``: those geoms collidable, in layers, contacts on, pin excludes;
    * ``everything``: ``extra-collision`` (gravity comes from the description).
    """
    import mujoco
    layer = {b.name: (0 if b.name == mech.ground else i + 1)
             for i, b in enumerate(x for x in mech.bodies if x.name != mech.ground)}
    layer["world"] = 0
    layer[mech.ground] = 0

    def contacts(spec, st, layered=True, excludes=True):
        spec.option.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
        dz = 4 * 0.01 * st.size
        for g in spec.geoms:
            g.contype, g.conaffinity = 1, 1
            z = dz * layer.get(g.parent.name, 0) if layered else 0.0
            if z:
                ft = list(g.fromto)
                if np.isnan(ft[0]):
                    g.pos = [g.pos[0], g.pos[1], g.pos[2] + z]
                else:
                    g.fromto = [ft[0], ft[1], ft[2] + z, ft[3], ft[4], ft[5] + z]
        if excludes:
            for a, b in _jointed_pairs(mech, st):
                spec.add_exclude(bodyname1=a, bodyname2=b)

    def extra(spec, st, collide: bool):
        radius = 0.01 * st.size
        types = [mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_CYLINDER,
                 mujoco.mjtGeom.mjGEOM_ELLIPSOID]
        for body in mech.bodies:
            if body.name == mech.ground:
                continue
            bs = spec.body(body.name)
            pts = np.array(list(body.points.values()), float)
            if len(pts) < 2:
                pts = np.vstack([pts, pts + [radius, 0.0]])
            for k in range(24):
                p, q = pts[k % (len(pts) - 1)], pts[k % (len(pts) - 1) + 1]
                c = p + (k + 0.5) / 24 * (q - p)
                ang = math.atan2(q[1] - p[1], q[0] - p[0])
                bs.add_geom(type=types[k % 3], size=[0.8 * radius, 0.5 * radius, 0.4 * radius],
                            pos=[c[0], c[1], 0.0],
                            quat=[math.cos(ang / 2), 0, 0, math.sin(ang / 2)],
                            contype=int(collide), conaffinity=int(collide),
                            rgba=[0.7, 0.7, 0.2, 0.5])

    if variant in ("minimal", "gravity"):
        return None
    if variant == "contacts":
        return lambda spec, st: contacts(spec, st)
    if variant == "contacts-same-plane":
        return lambda spec, st: contacts(spec, st, layered=False)
    if variant == "contacts-no-excludes":
        return lambda spec, st: contacts(spec, st, layered=False, excludes=False)
    if variant == "extra-visual":
        return lambda spec, st: extra(spec, st, False)
    if variant in ("extra-collision", "everything"):
        def hook(spec, st):
            extra(spec, st, True)
            contacts(spec, st)
        return hook
    raise ValueError(f"unknown scene variant {variant!r}")


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


def scene_task(case_name: str, variant: str, settings_dict: dict, timing_steps: int,
               repeats: int) -> dict:
    """One scene variant (see :func:`scene_hook`): errors and speed.  Never raises."""
    from sim_models.engines import run
    try:
        mech0 = load(case_name)
        mech = mech0
        if variant in ("gravity", "everything"):
            mech = replace(mech0, gravity=(0.0, -9.81))
        s = _mujoco_settings(settings_dict)
        hook = scene_hook(variant, mech)
        r = run(mech, "mujoco", s, revolutions=2, samples=36, spec_hook=hook)
        e = run_errors(r, mech)
        notes = [SCENE_VARIANTS[variant]]
        if mech is not mech0 and r.ok:
            e0 = run_errors(r, mech0)
            notes.append(f"against the gravity-free description: accel {e0['accel_error']:.2g},"
                         f" force {e0['force_error']:.2g}")
        # geoms and contacts of the model actually run
        import mujoco
        with _quiet_mujoco():
            st, m = _mujoco_model(mech, s, spec_hook=hook)
            d = mujoco.MjData(m)
            qadr = np.array([m.joint(tj.name).qposadr[0] for tj in st.joints])
            vals = input_values(st.linkage, 36)[0]
            q, _, _ = st.coords(st.linkage.kinematics(vals, on_singular="flag"))
            ncon = 0
            for i in range(len(vals)):
                d.qpos[qadr] = q[i]
                mujoco.mj_forward(m, d)
                ncon = max(ncon, int(d.ncon))
            ngeom = int(m.ngeom)
        sps = time_mujoco(mech, s, r.timestep, timing_steps, repeats, spec_hook=hook)
        return dict(variant=variant, seconds_per_rev=r.steps_per_rev / sps if sps else math.nan,
                    steps_per_second=sps, accel_error=e["accel_error"],
                    force_error=e["force_error"], error=e["error"], ngeom=ngeom,
                    max_contacts=ncon, ok=r.ok, reason=r.reason or "",
                    notes="; ".join(notes))
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
    from .plots import pareto_plot
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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m reports.studies",
                                 description="Speed against error of the engines.")
    ap.add_argument("--quick", action="store_true", help="the reduced study (~40 s)")
    ap.add_argument("--out", type=Path, default=None, help="write CSV and PNG files here")
    ap.add_argument("--workers", type=int, default=None, help="process-pool size")
    ap.add_argument("--serial", action="store_true", help="no process pool")
    a = ap.parse_args(argv)
    res = run_study(a.quick, pool=False if a.serial else None, workers=a.workers)
    pd.set_option("display.width", 200)
    pd.set_option("display.max_colwidth", 60)
    print(res["cheapest"].drop(columns=["settings"]).to_string(index=False))
    h = res["hard"]
    print(h["high_speed"][["engine", "label", "seconds_per_rev", "accel_error",
                           "force_error", "ok"]].to_string(index=False))
    print(h["near_toggle"][["case", "engine", "label", "transmission_extreme_deg",
                            "accel_error", "force_error", "error_vs_seed_four_bar",
                            "ok"]].to_string(index=False))
    print(h["change_point"][["engine", "label", "branch_after_singular", "final_branch",
                             "flips", "ok"]].to_string(index=False))
    print(h["long_run_summary"].drop(columns=["settings"]).T.to_string(
        float_format=lambda v: f"{v:.3g}"))
    print(res["scene_economy"].drop(columns=["notes"]).to_string(index=False))
    print("analytic seconds per revolution:", res["analytic_seconds_per_rev"])
    print("timings (s):", {k: round(v, 2) for k, v in res["timings"].items()})
    if a.out:
        for p in write_study(res, a.out):
            print("wrote", p)
    return 0


if __name__ == "__main__":
    sys.exit(main())
