"""The hard cases of the speed/accuracy study: the slider-crank at high speed, the
near-toggle four-bar, the parallelogram through its change points, and the long run.

:func:`hard_cases` runs them on the study's executor
(:func:`reports.studies.speed_accuracy.executor`) and returns their tables and figures;
each part is a phase of its own (``_submit``, ``_high_speed``, ``_near_toggle``,
``_change_point``, ``_long_run``).
"""

from __future__ import annotations

import math
from dataclasses import asdict

import numpy as np
import pandas as pd

from analytic import Linkage
from analytic.sweep import input_values
from reports.figures.plots import error_plot, timeseries_plot
from reports.figures.study_plots import branch_plot, long_run_plot
from reports.studies.change_point import (
    _wrap,
    analytic_branch,
    assembly_modes,
    change_point_task,
    singular_inputs,
)
from reports.studies.runs import load, make_settings, trace, trace_diagnostics
from reports.studies.speed_accuracy import (
    LONG_RUN_REVOLUTIONS,
    LONG_RUN_SAMPLES,
    _gather,
    _grid_frame,
    executor,
    grid_task,
    mujoco_family,
)
from sim_models import compile_linkage
from sim_models.builders.mjcf import MujocoSettings


def long_run_task(case_name: str, engine: str, settings_dict: dict, revolutions: int,
                  per_rev: int = LONG_RUN_SAMPLES) -> dict:
    """A long run: per-revolution diagnostics (:func:`trace_diagnostics` reduced to the
    worst value in each revolution; ``energy_balance`` and ``phase_drift`` at its end)
    plus a summary.  Never raises."""
    meta = dict(case=case_name, engine=engine, settings_dict=settings_dict)
    try:
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


def _hard_plan(quick: bool) -> dict:
    """Settings of the hard-case runs."""
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
    plan = _hard_plan(quick)
    R_long = LONG_RUN_REVOLUTIONS[bool(quick)]
    cp_revs = 2 if quick else 5
    with executor(pool) as ex:
        futures = _submit(ex, plan, R_long, cp_revs)
        hs_rows, nt_rows = _gather(futures["high_speed"]), _gather(futures["near_toggle"])
        cp_rows = _gather(futures["change_point"], lambda m, why: dict(
            m, ok=False, reason=why, branch_after_singular="diverged", branches="", flips=0,
            series=None, segments=[]))
        long_res = _gather(futures["long_run"], lambda m, why: {"per_rev": {}, "summary": dict(
            m, case="seed-four-bar", ok=False, reason=why, revolutions_done=0)})
    out: dict = {}
    out.update(_high_speed(hs_rows))
    out.update(_near_toggle(nt_rows))
    cp_labels = [m.get("label", "") for _, m in futures["change_point"]]
    an = analytic_branch("parallelogram-four-bar", cp_revs)
    out.update(_change_point(cp_rows, cp_labels, an, cp_revs))
    out.update(_long_run(long_res, plan, R_long, quick))
    notes = [f"long run: {R_long} revolutions of seed-four-bar"
             + (" (quick mode; the full study runs 1000)" if quick else ""),
             "change point: row 'analytic' is the reference solution of the verdict "
             f"runs (Linkage.kinematics); it follows {an['branches']}"]
    out["notes"] = "; ".join(notes)
    return out


def _submit(ex, plan: dict, R_long: int, cp_revs: int) -> dict[str, list]:
    """The hard-case runs handed to ``ex``, the longest first: part -> [(future, meta)]."""
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
    return {"long_run": long_f, "high_speed": hs_f, "near_toggle": nt_f, "change_point": cp_f}


def _high_speed(hs_rows: list[dict]) -> dict:
    """``high_speed`` and its figure: seed-slider-crank at omega2 = 200 rad/s."""
    hs = _grid_frame(hs_rows)
    hs.insert(1, "omega2", load("seed-slider-crank").driver.velocity)
    return {"high_speed": hs.drop(columns=[c for c in ("samples",) if c in hs]),
            "high_speed_plot": _sample_error_figure(
                hs_rows, "seed-slider-crank at omega2 = 200 rad/s: error over the cycle",
                None)}


def _near_toggle(nt_rows: list[dict]) -> dict:
    """``near_toggle`` (with each case's transmission-angle extreme) and its figure."""
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
    lk = Linkage(load("near-toggle-four-bar"))
    vals = input_values(lk, 144)[0]
    tr = next(iter(lk.kinematics(vals).transmission.values()))
    return {"near_toggle": nt.drop(columns=[c for c in ("samples",) if c in nt]),
            "near_toggle_plot": _sample_error_figure(
                [r for r in nt_rows if r.get("case") == "near-toggle-four-bar"],
                "near-toggle four-bar (transmission angle up to "
                f"{ext['near-toggle-four-bar'][0]:.2f} deg): error over the cycle",
                ("transmission angle (deg)", np.degrees(vals), tr))}


def _change_point(cp_rows: list[dict], labels: list[str], an: dict, cp_revs: int) -> dict:
    """``change_point`` (the engines' rows and the analytic solver's ``an``) and the
    figure of the branches against the assembly modes."""
    cols = ["case", "engine", "label", "timestep", "branch_after_singular", "final_branch",
            "branches", "flips", "max_deviation_deg", "max_loop_violation", "revolutions",
            "ok", "reason", "settings"]
    cp_df = pd.DataFrame([{k: r.get(k) for k in cols} for r in cp_rows + [an]], columns=cols)
    cp_df["label"] = labels + ["continued branch"]
    mech_cp = load("parallelogram-four-bar")
    xs = np.radians(np.array(an["series"]["input_deg"]))
    modes = assembly_modes(mech_cp, xs)
    sing = singular_inputs(Linkage(mech_cp))
    unwr = np.degrees(xs)
    sing_x = [s + 360 * k for s in sing for k in range(0, cp_revs + 2)
              if unwr[0] < s + 360 * k < unwr[-1]]
    eng_series = {}
    for r, label in zip(cp_rows, labels, strict=True):
        if r.get("series"):
            xi = np.array(r["series"]["input_deg"])
            yi = np.array(r["series"]["rocker_deg"])
            yi = np.degrees(_wrap(np.radians(yi - xi)))
            eng_series[f"{r['engine']} {label}"] = np.interp(unwr, xi, yi, left=np.nan,
                                                             right=np.nan)
    return {"change_point": cp_df, "change_point_plot": branch_plot(
        unwr, {k: np.degrees(_wrap(v - xs)) for k, v in modes.items()}, eng_series, sing_x,
        "parallelogram four-bar through its change points", "rocker angle - crank angle (deg)")}


def _long_run(long_res: list[dict], plan: dict, R_long: int, quick: bool) -> dict:
    """``long_run`` (per revolution), its summary, and their figures."""
    out: dict = {}
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
    return out


def _sample_error_figure(rows: list[dict], title: str, twin) -> bytes:
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


