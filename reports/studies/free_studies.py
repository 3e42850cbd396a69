"""Free motion in the report: the verdicts at each engine's recommended free-motion
settings, and speed against error (a grid of integrators, steps and loop-constraint
settings per engine), with IFToMM-style rows.

Every run is :func:`sim_models.runs.free.run_free` (the one stepping loop; its
``wall`` times :meth:`FreeSession.advance` only, the same loop as the verdicts), judged
by :func:`reports.comparison.free_compare.compare_free` against the exact trajectory, computed once
per case.  Cost is CPU seconds of stepping per simulated second; error at the end is the
largest joint-coordinate error at the last sample over that coordinate's range in the
run; the trusted horizon is :attr:`FreeVerdict.horizon`.
"""

from __future__ import annotations

import math
import os
import platform
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from analytic.free_motion import simulate
from reports.comparison.free_cases import free_case, release_and_judge
from reports.comparison.free_compare import FreeVerdict, compare_free, reference_samples
from reports.figures.free_report_plots import case_figures
from reports.figures.study_plots import _frontier
from reports.regression.baseline import versions
from sim_models.engines.free_protocol import free_start
from sim_models.runs.free import free_engine_names, free_settings, open_free_session, run_free
from sim_models.runs.free_run import FreeRequest
from sim_models.runs.timing import time_free_steps

#: The report's free-motion verdict cases, (case, duration s): quick keeps the report's
#: 30 s budget (A01 and the seed four-bar, short); full runs the IFToMM problems whose
#: exact reference this machine computes in seconds (A01 over 20 s, A03 over its
#: published 0.03 s) and every built-in case with masses released under gravity for 2 s.
#: A02 (N = 40) is not run: its exact reference takes minutes per simulated second here.
VERDICT_CASES = {
    True: (("iftomm-a01-pendulum", 2.0), ("seed-four-bar", 1.0)),
    False: (("iftomm-a01-pendulum", 20.0), ("iftomm-a03-andrews", 0.03),
            ("seed-four-bar", 2.0), ("seed-slider-crank", 2.0), ("offset-slider-crank", 2.0),
            ("inverted-slider-crank", 2.0), ("quick-return", 2.0), ("six-bar", 2.0)),
}
#: Samples of a verdict run (the judged times), per mode.
SAMPLES = {True: 100, False: 400}
#: Cases of the work-precision grid (full report only): A01 (a conservative
#: single-degree-of-freedom reference) and the seed four-bar released under gravity
#: (a closed loop through limit positions of its joints).
GRID_CASES = (("iftomm-a01-pendulum", 5.0), ("seed-four-bar", 2.0))
#: Per engine: the integrator and step grid, plus the loop-constraint settings that
#: matter (MuJoCo's solref and inverse-weight scaling, PyBullet's ERP and iterations,
#: Exudyn's spectral radius).  Each entry overrides the recommended free settings.
GRID = {
    "mujoco": ([{"integrator": i, "timestep": h} for i in ("RK4", "implicitfast", "Euler")
                for h in (4e-3, 2e-3, 1e-3, 5e-4)]
               + [{"solref": (-1 / t ** 2, -2 / t)} for t in (3e-3, 1e-1)]
               + [{"invweight_scale": 1.0}]),
    "pybullet": ([{"timestep": h} for h in (1e-3, 4e-4, 1e-4, 2.5e-5)]
                 + [{"erp": 0.2}, {"solver_iterations": 100}]),
    "exudyn": [{"timestep": h, "spectral_radius": r} for h in (4e-3, 1e-3, 2.5e-4)
               for r in (0.6, 0.95)],
    # Pinocchio: its two integrators over the step, and the loop's Baumgarte gain
    # (a fraction of 1/h: 0 leaves the drift uncorrected)
    "pinocchio": ([{"integrator": i, "timestep": h} for i in ("rk4", "euler")
                   for h in (4e-3, 1e-3, 2.5e-4)]
                  + [{"baumgarte": b} for b in (0.0, 0.2)]),
    # MuJoCo Warp (float32): the step, and the two choices its settings' docstring
    # measured against (Newton at the prescribed runs' inverse weights; CG at 1e-2 and
    # at stock weights)
    "mujoco_warp": ([{"timestep": h} for h in (2e-3, 5e-4)]
                    + [{"solver": "Newton", "invweight_scale": 1e-2},
                       {"invweight_scale": 1e-2}, {"invweight_scale": 1.0}]),
}
#: Tolerances of the cheapest-setting table (error at the end, of the range).
TOLERANCES = (1e-2, 1e-3, 1e-4)
#: The published A03 angles at t = 0.03 s, rad (Test Set for IVP Solvers, problem
#: 'andrews', PSIDE at rtol = atol = 1e-14), by joint: beta, Theta, gamma, Phi, delta,
#: Omega, epsilon.
ANDREWS_PUBLISHED = {"O": 0.1581077119629904e2, "F": -0.1575637105984298e2,
                     "B": 0.4082224013073101e-1, "H": -0.5347301163226948,
                     "A5": 0.5244099658805304, "G": 0.5347301163226948,
                     "A7": 0.1048080741042263e1}


@dataclass(frozen=True)
class FreeRow:
    """One engine run's summary: the verdict table's row and the grid's point.
    ``err_end``: the largest joint-coordinate error at the last sample over its range;
    ``worst``: the judged quantity with the largest error over its tolerance and its
    error (of its scale); ``horizon`` s (inf: the whole run) and ``lost_by``, the
    quantity that exceeds its tolerance first; ``energy_drift`` and
    ``loop_drift``: maxima over the run, of the energy scale and of the size;
    ``cpu_per_s``: stepping CPU seconds per simulated second; ``position_error`` m: the
    IFToMM reference point's (A01, A02) or, for A03, the largest angle error at 0.03 s
    against the published values (rad), NaN elsewhere."""

    case: str
    engine: str
    duration: float
    settings: str
    integrator: str
    timestep: float
    passed: bool
    ok: bool
    reason: str
    worst: str
    worst_error: float
    err_end: float
    horizon: float
    lost_by: str
    energy_drift: float
    loop_drift: float
    cpu_per_s: float
    steps: int
    wall: float
    iftomm_level: str
    position_error: float
    timing: str = "the run's stepping loop"
    not_read: str = ""


def end_error(v: FreeVerdict) -> float:
    """The largest joint-coordinate error at the last sample, of its range (inf when
    the run did not reach the end)."""
    vals = [float(c.error[-1]) for c in v.comparisons if c.quantity.endswith(".x")]
    vals = [e if math.isfinite(e) else math.inf for e in vals]
    return max(vals, default=math.nan)


def _a03_error(run) -> float:
    names = list(run.joint_names)
    d = [abs(float(run.x[-1, names.index(j)]) - ref) for j, ref in ANDREWS_PUBLISHED.items()
         if j in names]
    return max(d) if d and all(math.isfinite(x) for x in d) else math.inf


def _loop_drift(run, v: FreeVerdict) -> float:
    """The loop gap's maximum over the size, NaN for a mechanism without a loop (a
    pendulum: no gap to measure, not a gap of 0)."""
    return v.loop.normalised if v.has_loop else math.nan


def free_row(run, v: FreeVerdict) -> FreeRow:
    pos = v.iftomm.max_error if v.iftomm else (
        _a03_error(run) if v.case == "iftomm-a03-andrews" else math.nan)
    return FreeRow(v.case, v.engine, v.duration, v.settings, v.integrator, v.timestep,
                   v.passed, v.run_ok, v.reason or "", v.worst.quantity, v.worst.normalised,
                   end_error(v), v.horizon, v.lost_by.quantity if v.lost_by else "",
                   v.energy.normalised, _loop_drift(run, v),
                   v.cpu_per_simulated_second, int(run.steps), float(run.wall),
                   v.iftomm.level if v.iftomm else "", pos, not_read=" ".join(v.not_read))


def _reference(case: str, duration: float, samples: int):
    mech = free_case(case, duration)
    traj = simulate(mech)
    req = FreeRequest(duration=duration, samples=samples)
    return mech, traj, req, reference_samples(traj, req.times())


def case_task(case: str, duration: float, samples: int, engines=None,
              figures: bool = True) -> dict:
    """Every engine's free run of one case at its recommended settings, judged, with the
    case's figures: ``{"rows": [FreeRow], "verdicts": [FreeVerdict], "png": {name:
    bytes}, "errors": [str]}``; never raises (a failed engine is a line in ``errors``)."""
    out: dict = {"rows": [], "verdicts": [], "png": {}, "errors": [], "case": case}
    try:
        mech, traj, req, ref = _reference(case, duration, samples)
    except Exception as e:  # noqa: BLE001 - a study failure is a line of the report
        out["errors"].append(f"{case}: the exact reference failed: {type(e).__name__}: {e}")
        return out
    runs = {}
    for eng in engines or free_engine_names():
        try:
            run = run_free(mech, eng, None, req, traj)
        except Exception as e:  # noqa: BLE001 - an engine that refuses is a result
            out["errors"].append(f"{case} / {eng}: {type(e).__name__}: {e}")
            continue
        v = compare_free(run, traj, ref)
        runs[eng] = run
        out["verdicts"].append(v)
        out["rows"].append(free_row(run, v))
    if figures and runs:
        try:
            out["png"] = case_figures(traj, ref, runs, out["verdicts"])
        except Exception as e:  # noqa: BLE001 - a figure must not take the report down
            out["errors"].append(f"{case}: figures failed: {type(e).__name__}: {e}")
    return out


def grid_task(case: str, duration: float, engine: str, samples: int = 200,
              grid=None) -> list[FreeRow]:
    """One engine's work-precision grid on one case (:data:`GRID`; the recommended
    setting first): a :class:`FreeRow` per setting (a refused setting is a row with
    ``ok = False`` and the reason)."""
    mech, traj, req, ref = _reference(case, duration, samples)
    rows = []
    for over in [{}, *(GRID[engine] if grid is None else grid)]:
        label = " ".join(f"{k}={_fmt(v)}" for k, v in over.items()) or "recommended"
        try:
            run = run_free(mech, engine, free_settings(engine, over), req, traj,
                           step_from_motion="timestep" not in over)
        except Exception as e:  # noqa: BLE001 - a setting the engine refuses is a row
            rows.append(FreeRow(case, engine, duration, label, "", math.nan, False, False,
                                f"{type(e).__name__}: {e}", "", math.inf, math.inf, 0.0, "",
                                math.nan, math.nan, math.nan, 0, 0.0, "", math.nan))
            continue
        v = compare_free(run, traj, ref)
        r = asdict(free_row(run, v))
        cpu = _best_cpu(mech, engine, run, traj)
        if math.isfinite(cpu):
            r.update(cpu_per_s=cpu, timing=f"best of {TIMING_REPEATS} bare stepping loops")
        rows.append(FreeRow(**{**r, "settings": label}))
    return rows


#: The grid's cost: the same stepping loop (FreeSession.advance) from the released
#: state, at most this many steps, best of TIMING_REPEATS; a shared machine's other
#: load only ever adds time, so the best of several is the loop's own cost.
TIMING_STEPS = 2000
TIMING_REPEATS = 3


def _best_cpu(mech, engine: str, run, traj) -> float:
    """Stepping CPU seconds per simulated second, best of :data:`TIMING_REPEATS` bare
    loops of up to :data:`TIMING_STEPS` steps (NaN when it cannot be timed)."""
    if not run.ok or run.steps <= 0:
        return math.nan
    session = open_free_session(mech, engine, run.settings)
    try:
        start = free_start(session.tree, traj.at(np.array([0.0]), forces=False))
        sps = time_free_steps(session, start, float(run.timestep),
                              min(run.steps, TIMING_STEPS), TIMING_REPEATS)
    finally:
        session.close()
    return (run.steps / run.request.duration) / sps if sps > 0 else math.nan


def _fmt(v) -> str:
    if isinstance(v, tuple):
        return ",".join(f"{x:.3g}" for x in v)
    return f"{v:.3g}" if isinstance(v, float) else str(v)


def frame(rows) -> pd.DataFrame:
    """The rows as a table (one column per :class:`FreeRow` field)."""
    return pd.DataFrame([asdict(r) for r in rows],
                        columns=list(FreeRow.__dataclass_fields__))


def pareto(grid: pd.DataFrame) -> pd.DataFrame:
    """The settings no other setting of the same engine and case beats on both CPU per
    simulated second and error at the end (runs that reached the end only)."""
    keep = []
    ok = grid[grid["ok"].astype(bool) & np.isfinite(grid["err_end"].astype(float))]
    for _, g in ok.groupby(["case", "engine"], sort=True):
        idx = _frontier(g["cpu_per_s"].to_numpy(float), g["err_end"].to_numpy(float))
        keep += list(g.index[idx])
    return grid.loc[keep]


def cheapest(grid: pd.DataFrame, tolerances=TOLERANCES) -> pd.DataFrame:
    """Per case, engine and tolerance: the setting with the least CPU per simulated
    second whose error at the end is within the tolerance (``none`` when no setting of
    the grid reaches it)."""
    out = []
    for (case, eng), g in grid.groupby(["case", "engine"], sort=True):
        ok = g[g["ok"].astype(bool) & (g["err_end"].astype(float) <= 1.0)]
        for tol in tolerances:
            hit = ok[ok["err_end"].astype(float) <= tol]
            if len(hit):
                b = hit.loc[hit["cpu_per_s"].astype(float).idxmin()]
                out.append({"case": case, "engine": eng, "tolerance": tol,
                            "settings": b["settings"], "cpu_per_s": b["cpu_per_s"],
                            "err_end": b["err_end"], "horizon": b["horizon"]})
            else:
                out.append({"case": case, "engine": eng, "tolerance": tol,
                            "settings": "none", "cpu_per_s": math.nan,
                            "err_end": math.nan, "horizon": math.nan})
    return pd.DataFrame(out, columns=["case", "engine", "tolerance", "settings",
                                      "cpu_per_s", "err_end", "horizon"])


def machine() -> str:
    """The machine, as the IFToMM rows name it."""
    cpu = platform.processor() or platform.machine()
    return f"{platform.node() or 'host'}: {cpu}, {os.cpu_count()} cores, {platform.system()}"


def iftomm_rows(rows: pd.DataFrame) -> pd.DataFrame:
    """IFToMM-style rows of the benchmark problems among ``rows``: problem, code and
    version, integrator, step, error (A01, A02: the reference point's largest position
    error over the run, m; A03: the largest angle error at 0.03 s against the
    published values, rad), CPU time of the stepping loop, s, and machine."""
    sel = rows[rows["case"].str.startswith("iftomm-")]
    out = []
    for _, r in sel.iterrows():
        out.append({"problem": r["case"], "code": versions(r["engine"])["engine"],
                    "integrator": r["integrator"], "step_s": r["timestep"],
                    "settings": r["settings"], "duration_s": r["duration"],
                    "error": r["position_error"],
                    "error_unit": "rad" if r["case"] == "iftomm-a03-andrews" else "m",
                    "class": r["iftomm_level"], "cpu_s": r["wall"], "machine": machine()})
    return pd.DataFrame(out, columns=["problem", "code", "integrator", "step_s", "settings",
                                      "duration_s", "error", "error_unit", "class", "cpu_s",
                                      "machine"])


def free_verdict(mech, engine: str, duration: float | None = None, samples: int = 200,
                 settings=None):
    """One engine's free run of ``mech`` (a Mechanism with ``[motion]``, or a driven
    one, released by :func:`reports.comparison.free_cases.free_case`'s rule) judged against the
    exact trajectory: ``(run, FreeVerdict)``.  ``settings``: overrides of the engine's
    recommended free settings (typed values or ``key=value`` strings)."""
    return release_and_judge(mech, engine, duration, samples, settings)
