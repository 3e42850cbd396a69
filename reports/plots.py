"""Figures of the validation report (matplotlib, Agg backend, PNG bytes out).

Every function takes arrays already computed elsewhere and returns PNG bytes, so
the report can embed them (base64) and also write them to files.
"""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ENGINE_STYLE = {"analytic": dict(color="black", lw=1.6),
                "mujoco": dict(color="tab:blue", lw=1.0, ls="--"),
                "pybullet": dict(color="tab:orange", lw=1.0, ls=":")}


def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    plt.close(fig)
    return buf.getvalue()


def draw_linkage(linkage, values, title: str = "") -> bytes:
    """The linkage drawn at a few input values (lines between each body's joint
    points, ground pivots as triangles, slider lines dashed)."""
    from analytic.mechanism import Prismatic
    mech = linkage.mech
    kin = linkage.kinematics(values, on_singular="flag")
    fig, ax = plt.subplots(figsize=(5.2, 4.0))
    cmap = plt.get_cmap("viridis")
    for i in range(kin.n):
        col = cmap(i / max(kin.n - 1, 1))
        for body in mech.moving_bodies:
            pts = [kin.point(body.name, jt.point_a if jt.body_a == body.name else jt.point_b)[0][i]
                   for jt in mech.joints if body.name in jt.bodies]
            extra = [kin.point(body.name, pn)[0][i] for pn in body.points]
            pts = np.array(pts + extra)
            if len(pts) >= 2:
                # convex outline of the body's points
                c = pts.mean(axis=0)
                order = np.argsort(np.arctan2(pts[:, 1] - c[1], pts[:, 0] - c[0]))
                poly = pts[order]
                ax.fill(poly[:, 0], poly[:, 1], color=col, alpha=0.15, lw=0)
                ax.plot(np.r_[poly[:, 0], poly[:1, 0]], np.r_[poly[:, 1], poly[:1, 1]],
                        color=col, lw=1.2)
            ax.plot(pts[:, 0], pts[:, 1], "o", color=col, ms=3)
    g = mech.body(mech.ground)
    gp = np.array(list(g.points.values()))
    ax.plot(gp[:, 0], gp[:, 1], "^", color="k", ms=8)
    for jt in mech.joints:
        if isinstance(jt, Prismatic) and jt.guide == mech.ground:
            q = np.array(g.points[jt.origin])
            u = np.array([np.cos(jt.direction), np.sin(jt.direction)])
            span = np.ptp(kin.slider(jt.name)[0]) + 0.2 * _size(linkage)
            s = kin.slider(jt.name)[0]
            a, b = q + (s.min() - 0.1 * span) * u, q + (s.max() + 0.1 * span) * u
            ax.plot([a[0], b[0]], [a[1], b[1]], "k--", lw=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title or mech.name, fontsize=10)
    ax.grid(alpha=0.3)
    return _png(fig)


def _size(linkage) -> float:
    from analytic.positions import size_of
    return size_of(linkage.topo)


def cycle_plot(x, series: dict[str, dict[str, np.ndarray]], ylabel: str, title: str,
               xlabel: str = "input (deg)") -> bytes:
    """Quantities over the cycle: ``series[label][source] = values`` where source is
    ``analytic`` (a line over the fine sweep ``x``) or an engine (markers at its samples,
    NaN elsewhere).  One colour per quantity, one marker per engine."""
    fig, ax = plt.subplots(figsize=(6.0, 3.2))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    markers = {"mujoco": dict(marker="o", mfc="none", ms=5),
               "pybullet": dict(marker="x", ms=5)}
    for i, (label, by_source) in enumerate(series.items()):
        col = colors[i % len(colors)]
        for source, y in by_source.items():
            y = np.asarray(y, float)
            if source == "analytic":
                ax.plot(x, y, color=col, lw=1.4, label=f"{label}")
            else:
                ok = np.isfinite(y)
                ax.plot(np.asarray(x)[ok], y[ok], ls="none", color=col,
                        **markers.get(source, dict(marker=".")))
    for source, mk in markers.items():
        if any(source in s for s in series.values()):
            ax.plot([], [], ls="none", color="grey", label=source, **mk)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title + " (lines: analytic; markers: engines)", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return _png(fig)


def error_plot(x, errors: dict[str, np.ndarray], twin: tuple[str, np.ndarray] | None,
               title: str, xlabel: str = "input (deg)") -> bytes:
    """Normalised error against the input, log scale, with the transmission angle
    (or the Jacobian condition) on a second axis."""
    fig, ax = plt.subplots(figsize=(6.0, 3.2))
    for label, e in errors.items():
        ax.semilogy(x, np.maximum(np.abs(e), 1e-16), label=label, lw=1)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("|error| / peak")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=2, loc="upper left")
    if twin is not None:
        ax2 = ax.twinx()
        ax2.plot(x, twin[1], color="grey", lw=0.8, alpha=0.7)
        ax2.set_ylabel(twin[0], color="grey")
    ax.set_title(title, fontsize=10)
    return _png(fig)


def pareto_plot(rows, title: str, analytic_time: float | None = None) -> bytes:
    """Speed against error: ``rows`` of dicts with ``engine``, ``label``,
    ``seconds_per_rev`` and ``error`` (max normalised); the analytic solver's time per
    revolution as a vertical line."""
    fig, ax = plt.subplots(figsize=(6.0, 3.8))
    for engine in sorted({r["engine"] for r in rows}):
        rr = [r for r in rows if r["engine"] == engine and np.isfinite(r["error"])]
        if not rr:
            continue
        st = ENGINE_STYLE.get(engine, {})
        ax.loglog([r["seconds_per_rev"] for r in rr], [max(r["error"], 1e-9) for r in rr],
                  "o", color=st.get("color"), label=engine, ms=4)
        for r in rr:
            ax.annotate(r["label"], (r["seconds_per_rev"], max(r["error"], 1e-9)),
                        fontsize=5, alpha=0.7)
    for tol in (1e-2, 1e-3, 1e-4):
        ax.axhline(tol, color="grey", lw=0.6, ls=":")
    if analytic_time:
        ax.axvline(analytic_time, color="black", lw=0.8)
        ax.annotate("analytic", (analytic_time, ax.get_ylim()[1]), fontsize=7,
                    rotation=90, va="top")
    ax.set_xlabel("wall-clock seconds per simulated revolution")
    ax.set_ylabel("max normalised error (accelerations, forces)")
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    return _png(fig)


def timeseries_plot(t, series: dict[str, np.ndarray], title: str, ylabel: str) -> bytes:
    """Long-run diagnostics against time (log scale of magnitudes)."""
    fig, ax = plt.subplots(figsize=(6.0, 3.0))
    for label, y in series.items():
        ax.semilogy(t, np.maximum(np.abs(y), 1e-18), label=label, lw=0.8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    ax.set_title(title, fontsize=10)
    return _png(fig)
