"""Figures of free motion (PNG bytes): the released joint's trajectory with engine
markers on the exact curve, the error against time with the tolerance and each engine's
trusted horizon, the energy and loop-closure drift, and the work-precision plot."""

from __future__ import annotations

import math

import numpy as np

from analytic.mechanism import Revolute
from reports.comparison.free_compare import ENERGY_DRIFT, FREE_KINEMATIC, LOOP_DRIFT
from reports.figures.plots import (
    ENGINE_STYLE,
    LABEL_PT,
    LEGEND_PT,
    TITLE_PT,
    _png,
    engine_marker,
    floor_note,
    plt,
)

#: Magnitudes drawn on log axes are floored here (and counted on the figure).
LOG_FLOOR = 1e-14
#: Engine markers on a trajectory: about this many per curve (the line is the exact one).
MARKERS = 40


def _colour(engine: str) -> str:
    return ENGINE_STYLE.get(engine, {}).get("color", "tab:purple")


def trajectory_figure(ref, runs: dict, joint: str, title: str) -> bytes:
    """``joint``'s coordinate against time: the exact line, each engine's samples as
    markers (every k-th, about :data:`MARKERS` per engine)."""
    fig, ax = plt.subplots(figsize=(7.4, 3.6))
    i = list(ref.joints).index(joint)
    mech = next(iter(runs.values())).mechanism
    rev = isinstance(next(j for j in mech.joints if j.name == joint), Revolute)
    k = 180 / math.pi if rev else 1.0
    ax.plot(ref.t, ref.x[:, i] * k, color="black", lw=1.4, label="exact")
    for n, (eng, run) in enumerate(runs.items()):
        step = max(1, len(run.times) // MARKERS)
        sl = slice(n % step, None, step)  # engines staggered: markers do not hide each other
        j = list(run.joint_names).index(joint)
        ax.plot(run.times[sl], run.x[sl, j] * k, ls="none", color=_colour(eng),
                label=eng, **engine_marker(eng, n))
    ax.set_xlabel("time (s)", fontsize=LABEL_PT)
    ax.set_ylabel(f"{joint} ({'deg' if rev else 'm'})", fontsize=LABEL_PT)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=LEGEND_PT, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              borderaxespad=0)
    ax.set_title(title, fontsize=TITLE_PT)
    return _png(fig)


def error_figure(verdicts, title: str) -> bytes:
    """Per engine, the largest error over the joint coordinates and body angles at each
    time, of their ranges (log), the tolerance line and the trusted horizon (vertical)."""
    fig, ax = plt.subplots(figsize=(7.4, 3.6))
    arrays = []
    for v in verdicts:
        kin = [c.error for c in v.comparisons if c.family in ("joint angle", "slider", "angle")]
        if not kin:
            continue
        # fmax skips NaN without a warning; NaN where no quantity was measured (a run that
        # stopped: nanmax printed "All-NaN slice" into the report's console)
        env = np.fmax.reduce(np.vstack(kin), axis=0)
        arrays.append(env)
        ax.semilogy(v.times, np.maximum(env, LOG_FLOOR), color=_colour(v.engine), lw=1.0,
                    label=v.engine)
        if math.isfinite(v.horizon):
            by = f" ({v.lost_by.quantity})" if v.lost_by else " (run stopped)"
            ax.axvline(v.horizon, color=_colour(v.engine), ls="--", lw=0.9,
                       label=f"{v.engine} trusted to {v.horizon:.3g} s{by}")
    ax.axhline(FREE_KINEMATIC, color="0.3", ls=":", lw=1.0,
               label=f"tolerance {FREE_KINEMATIC:g}")
    floor_note(ax, arrays, LOG_FLOOR)
    ax.set_xlabel("time (s)", fontsize=LABEL_PT)
    ax.set_ylabel("error / range (coordinates, angles)", fontsize=LABEL_PT)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=LEGEND_PT, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              borderaxespad=0)
    ax.set_title(title, fontsize=TITLE_PT)
    return _png(fig)


def drift_figure(ref, runs: dict, verdicts, title: str) -> bytes:
    """Energy drift (engine total minus exact, of the energy scale; signed) and the
    loop-closure gap (of the size, log), against time."""
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7.4, 5.0), sharex=True)
    e_ref = ref.kinetic + ref.potential
    gaps = []
    for v in verdicts:
        run = runs[v.engine]
        d = (run.kinetic + run.potential - e_ref) / v.energy.scale
        a1.plot(run.times, d, color=_colour(v.engine), lw=1.0, label=v.engine)
        g = run.loop_gap / v.loop.scale
        gaps.append(g)
        a2.semilogy(run.times, np.maximum(np.abs(g), LOG_FLOOR), color=_colour(v.engine),
                    lw=1.0, label=v.engine)
    for a, tol in ((a1, ENERGY_DRIFT), (a2, LOOP_DRIFT)):
        a.axhline(tol, color="0.3", ls=":", lw=1.0, label=f"tolerance {tol:g}")
        a.grid(alpha=0.3, which="both")
    a1.axhline(-ENERGY_DRIFT, color="0.3", ls=":", lw=1.0)
    floor_note(a2, gaps, LOG_FLOOR)
    a1.set_ylabel("energy drift / scale", fontsize=LABEL_PT)
    a2.set_ylabel("loop gap / size", fontsize=LABEL_PT)
    a2.set_xlabel("time (s)", fontsize=LABEL_PT)
    a1.legend(fontsize=LEGEND_PT, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              borderaxespad=0)
    a1.set_title(title, fontsize=TITLE_PT)
    return _png(fig)


def case_figures(traj, ref, runs: dict, verdicts) -> dict[str, bytes]:
    """The three figures of one case, by name."""
    name = traj.mech.name
    joint = traj.mech.motion.joint
    return {"trajectory": trajectory_figure(ref, runs, joint,
                                            f"{name}: {joint} released (exact line, engine "
                                            "markers)"),
            "error": error_figure(verdicts, f"{name}: error against time"),
            "drift": drift_figure(ref, runs, verdicts, f"{name}: energy and loop drift")}


def work_precision_figure(grid, front, tolerances, title: str) -> bytes:
    """Error at the end of the run (of the range) against CPU seconds per simulated
    second, one colour per engine, each engine's Pareto front ``front`` (rows of
    ``grid``: :func:`reports.studies.free_studies.pareto`) as a step line, the cheapest-setting
    ``tolerances`` dotted; runs that did not reach the end as crosses on the top edge."""
    fig, ax = plt.subplots(figsize=(7.4, 4.4))
    g = grid.assign(ok=grid["ok"].astype(bool))
    good = g[g["ok"] & np.isfinite(g["err_end"].astype(float))]
    for eng, gg in good.groupby("engine", sort=False):
        ax.loglog(gg["cpu_per_s"], np.maximum(gg["err_end"].astype(float), LOG_FLOOR),
                  ls="none", color=_colour(eng), label=eng, **engine_marker(eng))
        f = front[front["engine"] == eng].sort_values("cpu_per_s")
        ax.step(f["cpu_per_s"], np.maximum(f["err_end"].astype(float), LOG_FLOOR),
                where="post", color=_colour(eng), lw=0.9, alpha=0.7)
        for _, r in f.iterrows():
            ax.annotate(r["settings"], (r["cpu_per_s"], max(r["err_end"], LOG_FLOOR)),
                        fontsize=7, color=_colour(eng), xytext=(3, 3),
                        textcoords="offset points")
    bad = g[~(g["ok"] & np.isfinite(g["err_end"].astype(float)))]
    if len(bad):
        top = ax.get_ylim()[1]
        ax.plot(bad["cpu_per_s"].fillna(ax.get_xlim()[0]), [top] * len(bad), "kx",
                label=f"did not reach the end ({len(bad)})")
    for tol in tolerances:
        ax.axhline(tol, color="0.5", ls=":", lw=0.8)
    floor_note(ax, [good["err_end"].to_numpy(float)], LOG_FLOOR)
    ax.set_xlabel("CPU seconds per simulated second (stepping loop)", fontsize=LABEL_PT)
    ax.set_ylabel("joint-coordinate error at the end / range", fontsize=LABEL_PT)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=LEGEND_PT, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              borderaxespad=0)
    ax.set_title(title, fontsize=TITLE_PT)
    return _png(fig)
