"""Figures of the speed/accuracy studies (:mod:`reports.studies.speed_accuracy`); PNG bytes out.

Same conventions as :mod:`reports.figures.plots` (Agg backend, one function per figure,
arrays or DataFrames in, PNG bytes out), whose ``ENGINE_STYLE`` colours are reused.
"""

from __future__ import annotations

import math

import numpy as np

from reports.figures.plots import (
    ENGINE_STYLE,
    LABEL_PT,
    LEGEND_PT,
    LOG_FLOOR,
    NOTE_PT,
    TITLE_PT,
    _png,
    declutter,
    floor_note,
    linear_if_narrow,
    plt,
)

_MARKERS = {"Euler": "s", "implicitfast": "^", "implicit": "v", "RK4": "o"}
#: Colours of the settings families: blues for MuJoCo, oranges/reds for PyBullet.
_FAMILY_COLOURS = {("mujoco", "stock"): "#9ecae1", ("mujoco", "hard"): "#08519c",
                   ("mujoco", "deadbeat"): "#6a51a3"}
_PYBULLET_COLOURS = ["#fdae6b", "#e6550d", "#a63603", "#d62728", "#7f2704"]
_TOLERANCES = (1e-2, 1e-3, 1e-4)


def _frontier(t: np.ndarray, e: np.ndarray) -> np.ndarray:
    """Indices of the Pareto-optimal points (no other point both faster and more
    accurate), ordered by time."""
    order = np.argsort(t, kind="stable")
    keep, best = [], math.inf
    for i in order:
        if e[i] < best:
            keep.append(i)
            best = e[i]
    return np.array(keep, int)


def pareto_frontier_plot(grid, title: str, analytic_time: float | None = None,
                         floor: float = 1e-9, analytic_points: int | None = None) -> bytes:
    """Speed against error of a settings grid
    (:func:`reports.studies.speed_accuracy.speed_error_grid`).

    One colour per engine and settings family, MuJoCo integrators by marker; each
    engine's Pareto frontier as a step line with its points labelled; failed runs
    as crosses on the top edge; tolerance lines; the analytic solver's time per
    revolution (at ``analytic_points`` samples, the engines' count) as a vertical line.
    Only the Pareto-optimal points are labelled, alternately above and below.
    """
    fig, ax = plt.subplots(figsize=(8.4, 5.2))
    labels = []
    grid = grid.assign(integrator=grid["integrator"].fillna("").astype(str),
                       family=grid["family"].fillna("").astype(str),
                       ok=grid["ok"].astype(bool))
    ok = grid[grid["ok"] & np.isfinite(grid["error"].astype(float))]
    bad = grid[~(grid["ok"] & np.isfinite(grid["error"].astype(float)))]
    groups = ok.groupby(["engine", "family"], sort=True)
    pb = sorted({f for e, f in zip(grid["engine"], grid["family"], strict=True)
                 if e != "mujoco"})
    cmap = plt.get_cmap("tab10")
    for gi, ((engine, family), g) in enumerate(groups):
        colour = _FAMILY_COLOURS.get((engine, family))
        if colour is None and family in pb:
            colour = _PYBULLET_COLOURS[pb.index(family) % len(_PYBULLET_COLOURS)]
        for integ, gg in g.groupby("integrator", sort=True):
            ax.loglog(gg["seconds_per_rev"], np.maximum(gg["error"].astype(float), floor),
                      _MARKERS.get(integ, "D" if engine == "pybullet" else "o"),
                      color=colour or cmap(gi % 10), ms=4.5, alpha=0.9,
                      label=f"{engine} {integ} {family}".replace("  ", " ").strip())
    for engine, g in ok.groupby("engine"):
        t = g["seconds_per_rev"].to_numpy(float)
        e = np.maximum(g["error"].to_numpy(float), floor)
        idx = _frontier(t, e)
        if len(idx):
            st = ENGINE_STYLE.get(engine, {})
            ax.step(t[idx], e[idx], where="post", color=st.get("color", "k"), lw=0.9,
                    alpha=0.7)
            for n, i in enumerate(idx):
                labels.append(ax.annotate(
                    g["label"].iloc[i], (t[i], e[i]), fontsize=LABEL_PT - 1, alpha=0.9,
                    xytext=(4, 5 if n % 2 == 0 else -11), textcoords="offset points",
                    color=st.get("color", "k")))
    ymax = max(1.0, float(np.nanmax(ok["error"])) if len(ok) else 1.0)
    if len(bad):
        tb = bad["seconds_per_rev"].to_numpy(float)
        tb = np.where(np.isfinite(tb) & (tb > 0), tb, np.nan)
        if np.isfinite(tb).any():
            ax.loglog(tb, np.full(len(tb), 2 * ymax), "x", color="red", ms=5,
                      label=f"failed / diverged ({len(bad)})")
    tol_text = []
    for tol in _TOLERANCES:
        ax.axhline(tol, color="grey", lw=0.6, ls=":")
        tol_text.append(ax.annotate(
            f"tolerance {tol:g}", (1.0, tol), xycoords=("axes fraction", "data"),
            xytext=(-2, 2), textcoords="offset points", ha="right", va="bottom",
            fontsize=LABEL_PT - 1, color="0.35"))
    if analytic_time:
        ax.axvline(analytic_time, color="black", lw=0.9)
        what = f"{analytic_points} samples" if analytic_points else "one revolution"
        ax.annotate(f"analytic solver\n({what})", (analytic_time, 1.0),
                    xycoords=("data", "axes fraction"), xytext=(3, -3),
                    textcoords="offset points", fontsize=LABEL_PT - 1, va="top", ha="left")
    ax.set_xlabel("wall-clock time per simulated revolution (s, log)")
    ax.set_ylabel("largest error / peak, accelerations and forces (-, log)")
    ax.set_title(title, fontsize=TITLE_PT)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=LEGEND_PT, ncol=1, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              borderaxespad=0)
    fig.tight_layout()
    hidden = declutter(ax, labels, avoid=tol_text)
    if hidden:
        ax.text(0.01, 0.01, f"{hidden} frontier labels left out where they would overlap "
                "(the table lists every setting)", transform=ax.transAxes,
                fontsize=NOTE_PT, color="0.35")
    return _png(fig)


def branch_plot(x_deg, analytic: dict[str, np.ndarray], engines: dict[str, np.ndarray],
                singular: list[float], title: str, ylabel: str = "rocker angle (deg)") -> bytes:
    """Output angle against the (unwrapped) input angle: the analytic assembly modes as
    lines, each engine as markers, singular positions as vertical lines."""
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    for (name, y), ls in zip(analytic.items(), ("-", "--", "-.", ":"), strict=False):
        ax.plot(x_deg, y, ls, color="black", lw=1.0, label=f"analytic: {name}")
    markers = ("o", "s", "^", "v", "D")
    for k, (name, y) in enumerate(engines.items()):
        eng = name.split()[0]
        st = ENGINE_STYLE.get(eng, {})
        ax.plot(x_deg, y, markers[k % len(markers)], ms=3, mfc="none",
                color=st.get("color"), label=name)
    for k, s in enumerate(singular):
        ax.axvline(s, color="red", lw=0.7, alpha=0.6,
                   label="change point (singular position)" if k == 0 else None)
    ax.set_xlabel("input angle, unwrapped (deg)")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=TITLE_PT)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=LEGEND_PT, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    return _png(fig)


def long_run_plot(frame, title: str) -> bytes:
    """Long-run diagnostics per revolution (:func:`reports.studies.speed_accuracy.hard_cases`): four
    panels (loop violation, crank-speed deviation and phase drift, energy and power
    balance, acceleration and drive-effort error), one colour per engine."""
    fig, axes = plt.subplots(2, 2, figsize=(10.0, 6.4), sharex=True)
    panels = [
        (axes[0, 0], [("loop_violation", "-")], "max loop gap / size"),
        (axes[0, 1], [("speed_deviation", "-"), ("phase_drift", "--")],
         "|crank rate error| / omega (-)\n|phase drift| rad (--)"),
        (axes[1, 0], [("energy_balance", "-"), ("power_residual", "--")],
         "|work - dKE| / work per rev (-)\n|power residual| / peak (--)"),
        (axes[1, 1], [("alpha_error", "-"), ("effort_error", "--")],
         "alpha error (-), effort error (--)\n/ peak"),
    ]
    drawn: dict = {}
    for engine, g in frame.groupby("engine"):
        st = ENGINE_STYLE.get(engine, {})
        for ax, cols, ylabel in panels:
            for col, ls in cols:
                if col in g:
                    raw = g[col].to_numpy(float)
                    drawn.setdefault(id(ax), []).append(raw)
                    y = np.maximum(np.abs(raw), LOG_FLOOR)
                    ax.semilogy(g["revolution"], y, ls, color=st.get("color"), lw=0.9,
                                label=f"{engine} {col}")
            ax.set_ylabel(ylabel, fontsize=LABEL_PT - 1)
    for ax, _, _ in panels:
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=LEGEND_PT - 1, loc="best")
        floor_note(ax, drawn.get(id(ax), []))  # exact zeros drawn at the floor, said so
    for ax in axes[1]:
        ax.set_xlabel("revolution")
    fig.suptitle(title, fontsize=TITLE_PT)
    fig.tight_layout()
    return _png(fig)


__all__ = ["branch_plot", "long_run_plot", "pareto_frontier_plot"]


def pareto_plot(rows, title: str, analytic_time: float | None = None) -> bytes:
    """Speed against error: ``rows`` of dicts with ``engine``, ``label``,
    ``seconds_per_rev`` and ``error`` (max normalised); the analytic solver's time per
    revolution as a vertical line."""
    fig, ax = plt.subplots(figsize=(7.2, 4.6))
    labels = []
    for engine in sorted({r["engine"] for r in rows}):
        rr = [r for r in rows if r["engine"] == engine and np.isfinite(r["error"])]
        if not rr:
            continue
        st = ENGINE_STYLE.get(engine, {})
        ax.loglog([r["seconds_per_rev"] for r in rr], [max(r["error"], 1e-9) for r in rr],
                  "o", color=st.get("color"), label=engine, ms=4)
        for r in rr:
            labels.append(ax.annotate(r["label"], (r["seconds_per_rev"], max(r["error"], 1e-9)),
                                      xytext=(4, 3), textcoords="offset points",
                                      fontsize=LABEL_PT, alpha=0.85))
    for tol in (1e-2, 1e-3, 1e-4):
        ax.axhline(tol, color="grey", lw=0.6, ls=":")
    if analytic_time:
        ax.axvline(analytic_time, color="black", lw=0.8)
        ax.annotate("analytic", (analytic_time, ax.get_ylim()[1]), fontsize=LABEL_PT,
                    rotation=90, va="top")
    ax.set_xlabel("wall-clock seconds per simulated revolution")
    ax.set_ylabel("max normalised error (accelerations, forces)")
    linear_if_narrow(ax, [r["seconds_per_rev"] for r in rows], "x")
    ax.set_title(title, fontsize=TITLE_PT)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=LEGEND_PT)
    fig.tight_layout()
    hidden = declutter(ax, labels)
    if hidden:
        ax.text(0.01, 0.01, f"{hidden} labels left out where they would overlap (see the "
                "table)", transform=ax.transAxes, fontsize=NOTE_PT, color="0.35")
    return _png(fig)
