"""Figures of the validation report (matplotlib, Agg backend, PNG bytes out).

Every function takes arrays already computed elsewhere and returns PNG bytes, which
the report writes to files (``img/``) that its pages and its Markdown refer to.
"""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")
import re
import textwrap

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.ticker import LogLocator, MaxNLocator, NullLocator

from analytic.input_display import convention_of, format_input, input_text
from analytic.mechanism import Prismatic
from analytic.positions import size_of

ENGINE_STYLE = {"analytic": dict(color="black", lw=1.6),
                "mujoco": dict(color="tab:blue", lw=1.0, ls="--"),
                "pybullet": dict(color="tab:orange", lw=1.0, ls=":"),
                "exudyn": dict(color="tab:green", lw=1.0, ls="-.")}


#: Resolution of every PNG figure: sharp when a reader zooms (a figure half the page
#: wide, ~620 px of 1240, is drawn from ~1100 px).
DPI = 150
#: Text sizes (pt at the figure's own size; a 7.4 in figure shown half a 1240 px page
#: wide is drawn at ~83 px/in, so 9 pt is ~10 px on screen): legends, notes and labels
#: at least 9 pt, titles 10 pt.
LEGEND_PT = 9.0
NOTE_PT = 9.0
LABEL_PT = 9.0
TITLE_PT = 10.0


def _png(fig, tight: bool = True) -> bytes:
    """PNG bytes at :data:`DPI` (zlib level 1: a report of ~80 figures otherwise spends
    its time compressing).  ``tight=False``: the caller laid the figure out itself
    (``subplots_adjust``), saving the extra draw a tight bounding box costs."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, bbox_inches="tight" if tight else None,
                pil_kwargs={"compress_level": 1})
    plt.close(fig)
    return buf.getvalue()


#: Offsets (points) tried, in order, to move a label off the labels drawn before it.
_NUDGES = [(0, 0)] + [(dx * r, dy * r) for r in (8, 16, 26, 38)
                      for dx, dy in ((0, 1), (0, -1), (1, 0), (-1, 0), (1, 1), (-1, 1),
                                     (1, -1), (-1, -1))]


def declutter(ax, texts, hide: bool = True, avoid=()) -> int:
    """Move each annotation of ``texts`` (``ax.annotate`` with ``textcoords="offset
    points"``) to the first offset of :data:`_NUDGES` where its box overlaps no label
    placed before it and stays inside the figure, off the legend and the artists
    ``avoid``; a label with no free place is hidden (``hide``) or left where it was.  A
    label moved away from its point gets a thin leader line.  Returns how many were
    hidden."""
    fig = ax.figure
    r = fig.canvas.get_renderer()
    leg = ax.get_legend()
    placed, hidden = ([leg.get_window_extent(r)] if leg is not None else []), 0
    placed += [a.get_window_extent(r) for a in avoid]
    fb = fig.bbox
    for t in texts:
        x0, y0 = t.xyann
        for dx, dy in _NUDGES:
            t.xyann = (x0 + dx, y0 + dy)
            bb = t.get_window_extent(r).expanded(1.05, 1.15)
            inside = bb.x0 >= fb.x0 and bb.x1 <= fb.x1 and bb.y0 >= fb.y0 and bb.y1 <= fb.y1
            if inside and not any(bb.overlaps(o) for o in placed):
                placed.append(bb)
                if abs(dx) + abs(dy) > 12:  # far from its point: a leader line
                    ax.annotate("", t.xy, xytext=t.xyann, textcoords="offset points",
                                arrowprops=dict(arrowstyle="-", lw=0.5, color="0.55",
                                                shrinkA=0, shrinkB=3))
                break
        else:
            t.xyann = (x0, y0)
            if hide:
                t.set_visible(False)
                hidden += 1
            else:
                placed.append(t.get_window_extent(r))
    return hidden


#: Line styles of the successive inputs of a linkage drawing, widest first: poses that
#: coincide (a quick-return's rocker at 90 and 270 deg) stay visible under later ones.
_POSE_STYLES = ("-", "--", "-.", ":")


def draw_linkage(linkage, values, title: str = "") -> bytes:
    """The linkage drawn at a few input values (each body's outline through its joint
    points, ground pivots as triangles at the ground's revolute joints, slider lines
    dashed), one colour and line style per input value with a key, later values drawn
    thinner over earlier ones; bodies and joints named at the first value, each name
    moved off the names before it (:func:`declutter`)."""
    mech = linkage.mech
    kin = linkage.kinematics(values, on_singular="flag")
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    cmap = plt.get_cmap("viridis")
    conv = convention_of(linkage)
    labels = []
    for i in range(kin.n):
        col = cmap(i / max(kin.n - 1, 1))
        ls = _POSE_STYLES[i % len(_POSE_STYLES)]
        lw = 3.2 - 2.0 * i / max(kin.n - 1, 1)
        ax.plot([], [], color=col, lw=2, ls=ls,
                label=f"input {input_text(float(kin.value[i]), conv)}")
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
                ax.fill(poly[:, 0], poly[:, 1], color=col, alpha=0.12, lw=0)
                ax.plot(np.r_[poly[:, 0], poly[:1, 0]], np.r_[poly[:, 1], poly[:1, 1]],
                        color=col, lw=lw, ls=ls)
            if i == 0:
                labels.append(ax.annotate(
                    body.name, pts.mean(axis=0), xytext=(0, 0), textcoords="offset points",
                    fontsize=LABEL_PT, fontweight="bold", ha="center", va="center",
                    color="0.15", bbox=dict(fc="white", ec="none", alpha=0.7, pad=0.5),
                    zorder=6))
            ax.plot(pts[:, 0], pts[:, 1], "o", color=col, ms=3)
    for jt in mech.joints:  # joint names at the first input value
        try:
            p = kin.point(jt.body_b, jt.point_b)[0][0] if jt.body_b != mech.ground else \
                kin.point(jt.body_a, jt.point_a)[0][0]
        except Exception:  # noqa: BLE001 - a name is decoration
            continue
        labels.append(ax.annotate(jt.name, p, xytext=(6, -10), textcoords="offset points",
                                  fontsize=LABEL_PT - 1, color="darkred", zorder=6))
    g = mech.body(mech.ground)
    # ground pivots: the ground's points that carry a revolute joint (a slider line's
    # origin is a point on the line, not a pivot)
    piv = [g.points[jt.point_a if jt.body_a == mech.ground else jt.point_b]
           for jt in mech.joints if not isinstance(jt, Prismatic) and mech.ground in jt.bodies]
    if piv:
        gp = np.array(piv, float)
        ax.plot(gp[:, 0], gp[:, 1], "^", color="k", ms=8, label="ground pivot", zorder=5)
    for jt in mech.joints:
        if isinstance(jt, Prismatic) and jt.guide == mech.ground:
            q = np.array(g.points[jt.origin])
            u = np.array([np.cos(jt.direction), np.sin(jt.direction)])
            span = np.ptp(kin.slider(jt.name)[0]) + 0.2 * _size(linkage)
            s = kin.slider(jt.name)[0]
            a, b = q + (s.min() - 0.1 * span) * u, q + (s.max() + 0.1 * span) * u
            ax.plot([a[0], b[0]], [a[1], b[1]], "k--", lw=0.8)
    # equal scales by widening the data limits, not by shrinking the axes: a tall,
    # narrow linkage keeps a readable width and its tick labels room
    ax.set_aspect("equal", adjustable="datalim")
    ax.xaxis.set_major_locator(MaxNLocator(nbins=6))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title or mech.name, fontsize=TITLE_PT)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=LEGEND_PT, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0,
              title="colour key (later\ninputs drawn thinner)", title_fontsize=LEGEND_PT)
    fig.tight_layout()
    declutter(ax, labels, hide=False)
    return _png(fig)


def _size(linkage) -> float:
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
    ax.legend(fontsize=LEGEND_PT, ncol=2)
    return _png(fig)


def error_plot(x, errors: dict[str, np.ndarray], twin: tuple[str, np.ndarray] | None,
               title: str, xlabel: str = "input (deg)") -> bytes:
    """Normalised error against the input, log scale, with the transmission angle
    (or the Jacobian condition) on a second axis."""
    fig, ax = plt.subplots(figsize=(6.0, 3.2))
    for label, e in errors.items():
        ax.semilogy(x, np.maximum(np.abs(e), 1e-16), label=label, lw=1)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("|error| / peak (-)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=LEGEND_PT, ncol=2, loc="upper center", bbox_to_anchor=(0.5, -0.2))
    if twin is not None:
        ax2 = ax.twinx()
        ax2.plot(x, twin[1], color="grey", lw=0.8, alpha=0.7)
        ax2.set_ylabel(twin[0], color="grey")
    ax.set_title(title, fontsize=TITLE_PT)
    return _png(fig)


def linear_if_narrow(ax, values, axis: str) -> None:
    """A log axis over less than a decade labels its minor ticks in colliding
    ``1.05x10^-2`` form: such an axis is drawn linear, with a few plain ticks."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v) & (v > 0)]
    if v.size and np.log10(v.max() / v.min()) < 1.0:
        getattr(ax, f"set_{axis}scale")("linear")
        getattr(ax, f"{axis}axis").set_major_locator(MaxNLocator(nbins=5))


#: Magnitudes below this are drawn at it on the long-run log axes (a log axis has no
#: zero); the figure says how many were (an exact zero is a value, not round-off).
LOG_FLOOR = 1e-18


def floor_note(ax, arrays, floor: float = LOG_FLOOR) -> int:
    """Say on ``ax`` how many finite values of ``arrays`` are below ``floor`` in
    magnitude (drawn at it), and whether they are exact zeros; returns that count."""
    v = np.concatenate([np.abs(np.asarray(a, float)).ravel() for a in arrays]) \
        if len(arrays) else np.zeros(0)
    low = v[np.isfinite(v) & (v < floor)]
    if low.size:
        what = "exact zeros" if np.all(low == 0) else \
            f"{int(np.sum(low == 0))} exact zeros, the rest round-off"
        ax.text(0.01, 0.01, f"{low.size} values below {floor:g} ({what}) drawn at {floor:g}",
                transform=ax.transAxes, fontsize=NOTE_PT - 1, color="0.3", va="bottom",
                bbox=dict(fc="white", ec="none", alpha=0.8, pad=1))
    return int(low.size)


def timeseries_plot(t, series: dict[str, np.ndarray], title: str, ylabel: str) -> bytes:
    """Long-run diagnostics against time (log scale of magnitudes; values under
    :data:`LOG_FLOOR`, exact zeros among them, drawn at it and counted on the figure)."""
    fig, ax = plt.subplots(figsize=(7.4, 3.6))
    for label, y in series.items():
        ax.semilogy(t, np.maximum(np.abs(y), LOG_FLOOR), label=label, lw=0.8)
    floor_note(ax, list(series.values()))
    ax.set_xlabel("time (s)")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=LEGEND_PT, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    ax.set_title(title, fontsize=TITLE_PT)
    return _png(fig)


# ----------------------------------------------------------------------------- case figures
#: Marker of each engine in the case figures (others cycle through _MORE_MARKERS).
ENGINE_MARKERS = {"mujoco": dict(marker="o", mfc="none", ms=5),
                  "pybullet": dict(marker="x", ms=5),
                  "exudyn": dict(marker="s", mfc="none", ms=4)}
_MORE_MARKERS = ("^", "v", "D", "P", "*")
#: A curve axis is clipped only when its full range exceeds this many times the range of
#: its central 99 % of values (a spike near a limit position flattening the rest).
CLIP_RATIO = 5.0


def engine_marker(engine: str, k: int = 0) -> dict:
    return ENGINE_MARKERS.get(engine, dict(marker=_MORE_MARKERS[k % len(_MORE_MARKERS)],
                                           mfc="none", ms=4))


def _robust_ylim(values: np.ndarray):
    """(lo, hi, n_clipped, (min, max)) when a few values dwarf the rest, else None."""
    v = values[np.isfinite(values)]
    if v.size < 10:
        return None
    lo, hi = np.percentile(v, [0.5, 99.5])
    full = float(v.max() - v.min())
    core = float(hi - lo)
    if core <= 0 or full <= CLIP_RATIO * core:
        return None
    pad = 0.3 * core
    lo, hi = lo - pad, hi + pad
    return lo, hi, int(np.sum((v < lo) | (v > hi))), (float(v.min()), float(v.max()))


def curve_plot(fig_data) -> bytes:
    """A :class:`reports.figures.case_figures.CurveFigure`: analytic lines (one colour per
    quantity), engine markers at their samples (grey: samples the verdict does not
    judge), limit/singular positions, the part of the input range no engine reached
    shaded, and the axis clipped (and said so) when a spike would flatten the rest."""
    fig, ax = plt.subplots(figsize=(7.4, 3.3))
    draw_curve_axes(ax, fig_data)
    return _png(fig)  # a tight box: the legend at the right and the notes fit


#: Event marks' colours by a word of their kind (a prescribed plot's limit and singular
#: positions and change points; a free run's coordinate switches and turning points too).
EVENT_COLOURS = {"limit": "red", "switch": "tab:green", "turning": "tab:brown"}


def event_colour(kind: str) -> str:
    """The colour of an event mark of ``kind`` (purple: singular positions and others)."""
    return next((c for w, c in EVENT_COLOURS.items() if w in kind), "purple")


def draw_curve_axes(ax, fig_data) -> None:
    """:func:`curve_plot` onto the axes ``ax`` (``xval plot`` stacks several)."""
    d = fig_data
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    engines: list[str] = []
    allv = []
    for i, c in enumerate(d.curves):
        col = colors[i % len(colors)]
        brk = list(getattr(d, "breaks", ()))
        for k, (xs, ys) in enumerate(zip(np.split(np.asarray(c.x), brk),
                                         np.split(np.asarray(c.y, float), brk), strict=True)):
            ax.plot(xs, ys, color=col, lw=1.3, label=c.label if k == 0 else None)
        allv.append(np.asarray(c.y, float))
        for e, (x, y, judged) in c.markers.items():
            if e not in engines:
                engines.append(e)
            y = np.asarray(y, float)
            ok = np.isfinite(y)
            mk = engine_marker(e, engines.index(e))
            ax.plot(np.asarray(x)[ok & judged], y[ok & judged], ls="none", color=col, **mk)
            if (ok & ~judged).any():
                ax.plot(np.asarray(x)[ok & ~judged], y[ok & ~judged], ls="none",
                        color="0.6", **mk)
            allv.append(y)
    for k, e in enumerate(engines):
        ax.plot([], [], ls="none", color="0.3", label=e, **engine_marker(e, k))
    seen = set()
    for kind, xv in d.events:
        lab = kind if kind not in seen else None
        seen.add(kind)
        ax.axvline(xv, color=event_colour(kind), lw=0.8, ls="--", label=lab)
    notes = []
    if d.feasible is not None and d.covered is not None:
        lo, hi = d.feasible
        ax.set_xlim(lo - 0.02 * (hi - lo), hi + 0.02 * (hi - lo))
        for a, b in ((lo, d.covered[0]), (d.covered[1], hi)):
            if b - a > 1e-3 * (hi - lo):
                ax.axvspan(a, b, color="0.85", lw=0)
        if d.covered[1] - d.covered[0] < 0.999 * (hi - lo):
            notes.append(f"engines covered {d.covered[0]:.4g} to {d.covered[1]:.4g} of "
                         f"{lo:.4g} to {hi:.4g} (grey: not reached)")
    brk = [int(i) for i in getattr(d, "breaks", ()) if 0 < int(i) < len(d.curves[0].x)] \
        if d.curves else []
    if brk and not d.xlabel.startswith("time"):
        x0 = np.asarray(d.curves[0].x, float)
        gaps = ", ".join(f"{x0[i - 1]:.4g} to {x0[i]:.4g}" for i in brk[:3])
        notes.append(f"line broken at {gaps}: the sampled motion starts and ends there "
                     "(at different rates)")
    ax.ticklabel_format(axis="y", useOffset=False)
    clip = None
    if allv:
        v = np.concatenate(allv)
        v = v[np.isfinite(v)]
        mag = float(np.max(np.abs(v))) if v.size else 0.0
        if v.size and mag > 0 and np.ptp(v) < 0.02 * mag:
            # a quantity (nearly) constant over the range: an axis around its round-off
            # scatter would magnify it; show it against its own size
            mid = 0.5 * (float(v.max()) + float(v.min()))
            ax.set_ylim(mid - 0.1 * mag, mid + 0.1 * mag)
        else:
            clip = _robust_ylim(v)
    if clip is not None:
        lo, hi, n, (mn, mx) = clip
        ax.set_ylim(lo, hi)
        notes.append(f"axis clipped: {n} values beyond it (range {mn:.3g} to {mx:.3g})")
    ax.set_xlabel(d.xlabel)
    ax.set_ylabel(d.ylabel)
    # notes under the title, never over the data
    ax.set_title(d.title, fontsize=TITLE_PT)
    if notes:
        ax.set_title("\n".join(textwrap.wrap("; ".join(notes), 95)), fontsize=NOTE_PT,
                     loc="left", color="0.3")
        ax.set_title(d.title + "\n\n", fontsize=TITLE_PT)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=LEGEND_PT, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0,
              title="lines: analytic" + ("\nmarkers: engines" if engines else ""),
              title_fontsize=LEGEND_PT)


_FAMILY_COLOURS = {"body alpha": "tab:blue", "slider s''": "tab:green",
                   "drive effort": "tab:red", "joint forces": "tab:purple",
                   "prismatic normal, moment": "tab:brown"}
#: Errors below this are drawn at it (a log axis has no zero).
ERROR_FLOOR = 1e-16


def error_panels(fig_data) -> bytes:
    """A :class:`reports.figures.case_figures.ErrorFigure`: one panel per engine, the largest
    normalised error of each judged family against the input (log axis), the tolerance
    line labelled, the worst quantity named, the transmission angle (or condition
    number) in grey on a second axis."""
    d = fig_data
    n = len(d.panels)
    height = 2.1 * n + 1.1
    fig, axes = plt.subplots(n, 1, figsize=(7.4, height), sharex=True, squeeze=False)
    # laid out by hand: a tight layout of log axes with twins redraws every tick label
    fig.subplots_adjust(left=0.11, right=0.86, top=1 - 0.62 / height, bottom=0.85 / height,
                        hspace=0.45)
    for ax, (engine, p) in zip(axes[:, 0], d.panels.items(), strict=True):
        draw_error_axes(ax, d, engine, p)
        ax.yaxis.set_major_locator(LogLocator(numticks=6))
        ax.yaxis.set_minor_locator(NullLocator())
        ax.set_ylabel("error / peak (-)", fontsize=8)
        if ax is not axes[-1, 0]:
            ax.set_xlabel("")
    h, lab = axes[0, 0].get_legend_handles_labels()
    fig.legend(h, lab, fontsize=LEGEND_PT, loc="lower center", ncol=len(lab),
               bbox_to_anchor=(0.5, 0.0))
    fig.suptitle(d.title, fontsize=TITLE_PT)
    return _png(fig, tight=False)


def worst_at(d, p: dict) -> str:
    """Where an error panel's worst error is, as text: the input in the one convention
    of :mod:`analytic.input_display` (what the verdict table and JUnit print), in the
    units of the panel's axis (``--units rad``: radians); a panel against time adds
    the time."""

    at = p["worst"][2]
    unit = re.search(r"\(([^()]*)\)\s*$", d.xlabel)
    if p.get("by_time"):
        return f"input {p.get('worst_input', '')} (t = {at:.6g} s)"
    if unit is None:
        return p.get("worst_input", "")
    return format_input(at, unit.group(1))


def draw_error_axes(ax, d, engine: str, p: dict) -> None:
    """One engine's panel of :func:`error_panels` onto the axes ``ax``."""
    for fam, e in p["families"].items():
        ax.semilogy(p["x"], np.maximum(np.asarray(e, float), ERROR_FLOOR), lw=1,
                    marker=".", ms=3, color=_FAMILY_COLOURS.get(fam), label=fam)
    ax.axhline(d.tolerance, color="red", lw=0.9, ls="--",
               label=f"tolerance {d.tolerance:g}")
    ax.set_title(f"{engine}: worst {p['worst'][0]} {p['worst'][1]:.2g} at {worst_at(d, p)}",
                 fontsize=TITLE_PT)
    ax.set_xlabel(d.xlabel)
    ax.grid(alpha=0.3, which="both")
    if p.get("twin") is not None:
        ax2 = ax.twinx()
        ax2.plot(p["x"], p["twin"][1], color="0.55", lw=0.8, alpha=0.8)
        ax2.set_ylabel(p["twin"][0], color="0.45", fontsize=8)
        ax2.tick_params(labelsize=7, colors="0.45")
