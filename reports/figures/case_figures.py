"""The figures of one case: drawn from the runs' own analytic reference.

Every curve figure holds the arrays it plots (:class:`CurveFigure`, :class:`ErrorFigure`),
so a test can recompute from them what a reader sees and hold it against the verdict
(``tests/reports/test_case_figures.py``).  The analytic lines are
:func:`reports.comparison.reference.analytic_line` (the prescribed motion the engines were driven
at, through every sample); the engine markers sit at the samples, and each engine's
error panel is :func:`reports.comparison.reference.sample_errors` of
:func:`reports.comparison.reference.reference_of`, the reference the verdict compares with.
Angles: the analytic line is unwrapped along the input and moved by whole turns to start
in the tables' range, (-180, 180] deg (:func:`table_turn`); an engine's angle is drawn at
the line's value plus the engine-minus-analytic difference wrapped to [-180, 180) deg.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from analytic import Linkage
from analytic.errors import LinkageError
from analytic.input_display import convention_of, input_text
from analytic.sweep import input_values
from reports.comparison.reference import (
    analytic_line,
    axis_of,
    engine_slider_positions,
    family_of,
    line_breaks,
    reference_of,
    sample_errors,
    wrap_deg,
)
from reports.figures import plots
from reports.figures.display_units import DisplayUnits

#: Families of judged quantities, in the order the error panels draw them.
FAMILIES = ("body alpha", "slider s''", "drive effort", "joint forces",
            "prismatic normal, moment")


@dataclass
class Curve:
    """One quantity: the analytic line ``(x, y)`` and each engine's markers
    ``markers[engine] = (x, y, judged)``; ``quantity`` the verdict's name for it when
    it is judged (None: drawn only)."""

    label: str
    x: np.ndarray
    y: np.ndarray
    markers: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]
    quantity: str | None = None
    measure: str = "value"   # "value" or "magnitude" (|F| of a vector quantity)


@dataclass
class CurveFigure:
    name: str
    title: str
    xlabel: str
    ylabel: str
    curves: list[Curve]
    events: list[tuple[str, float]] = field(default_factory=list)  # (kind, x) to mark
    feasible: tuple[float, float] | None = None   # x range the input can reach
    covered: tuple[float, float] | None = None    # x range the engines covered
    png: bytes = b""
    breaks: tuple[int, ...] = ()  # line indices that start a new stretch (not joined)


@dataclass
class ErrorFigure:
    """Per engine: ``x`` (the judged samples' axis values) and the largest normalised
    error of each family at each sample; ``worst`` (quantity, error, at) per engine."""

    name: str
    title: str
    xlabel: str
    panels: dict[str, dict]      # engine -> {"x", "families": {fam: (N,)}, "worst", "twin"}
    tolerance: float
    png: bytes = b""


def _index_in(line_u: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Indices of ``u`` (sample axis values) in the sorted line axis ``line_u``."""
    k = np.clip(np.searchsorted(line_u, u), 0, len(line_u) - 1)
    km = np.clip(k - 1, 0, len(line_u) - 1)
    return np.where(np.abs(line_u[km] - u) < np.abs(line_u[k] - u), km, k)


def curve_figures(label: str, runs: dict, linkage, reference=reference_of,
                  line=analytic_line, plan=None, extra=(), tree=None) -> list[CurveFigure]:
    """The body angle, omega, alpha, slider s'', drive effort and joint-force figures
    of the (case) ``label`` from its engine runs (``{engine: EngineRun}``, one plan).
    ``reference(run)`` gives each run's samples' reference (the verdict's: that of
    ``run.linkage``, the compiled Linkage it carries) and ``line(runs, linkage)`` the
    analytic lines (a test swaps in a wrong one to show
    that the plot-against-verdict check catches it).  Without runs, ``plan`` (anything
    with a run's ``times, values, driver_velocity, driver_acceleration, by_time,
    has_forces``: :func:`reports.cli.plot.plan_samples_of`) places the analytic lines
    (``xval plot`` without engines).  ``extra``: figures drawn on request only,
    ``"transmission"`` (transmission angles) and ``"slider_s"`` (slider positions;
    the engines' own, from their tree coordinates, as markers when ``tree``, the
    compiled :class:`sim_models.builders.tree.SimTree`, is given)."""
    runs = {e: r for e, r in runs.items() if r is not None}
    basis = list(runs.values()) or ([plan] if plan is not None else [])
    if not basis:
        return []
    line_fn = line
    line = line(basis, linkage)
    if line is None:
        return []
    lu, lkin, lfrc = line
    r0 = basis[0]
    _, xl = axis_of(r0, linkage)
    refs = {e: reference(r) for e, r in runs.items()}
    idx = {e: _index_in(lu, refs[e].u) for e in runs}
    events, feasible, covered = _range_marks(r0, linkage, lu)

    def fig(name, title, ylabel, curves):
        return CurveFigure(name, f"{label}: {title}", xl, ylabel, curves, events, feasible,
                           covered)

    out = [fig(*spec) for spec in _motion_figures(linkage, lu, lkin, runs, refs, idx)]
    if lfrc is not None:
        out += [fig(*spec) for spec in _force_figures(linkage, lu, lfrc, runs, refs)]
    out += [fig(*spec) for spec in _extra_figures(linkage, lu, lkin, runs, refs, extra, tree)]
    if line_fn is analytic_line:  # a drawn line must not join samples of other turns
        brk = tuple(int(i) for i in line_breaks(basis, linkage))
        for f in out:
            f.breaks = brk
    return out


def _motion_figures(linkage, lu, lkin, runs, refs, idx) -> list[tuple]:
    """(name, title, ylabel, curves) of the body angles, omegas and alphas and, with
    sliders, the slider accelerations: the analytic line ``lkin`` at ``lu`` and each
    engine's samples at its reference's inputs."""
    mech = linkage.mech
    moving = [b for b in range(len(mech.bodies)) if b != linkage.topo.ground]
    out = []
    # body angle: one convention for both (the analytic line unwrapped along the input;
    # the engine at the line plus the wrapped difference at its own sample)
    curves = []
    for b in moving:
        y = table_turn(np.degrees(np.unwrap(lkin.theta[:, b])))
        mk = {}
        for e, r in runs.items():
            at = y[idx[e]]
            mk[e] = (refs[e].u, at + wrap_deg(np.degrees(r.theta[:, b]) - at),
                     refs[e].judged)
        curves.append(Curve(mech.bodies[b].name, lu, y, mk))
    out.append(("angle", "body angles", "angle (deg)", curves))
    for what, unit in (("omega", "rad/s"), ("alpha", "rad/s^2")):
        curves = []
        for b in moving:
            name = mech.bodies[b].name
            mk = {e: (refs[e].u, getattr(r, what)[:, b], refs[e].judged)
                  for e, r in runs.items()}
            curves.append(Curve(name, lu, getattr(lkin, what)[:, b], mk,
                                f"{name}.alpha" if what == "alpha" else None))
        out.append((what, f"body {what}", f"{what} ({unit})", curves))
    if linkage.topo.prismatic:
        curves = []
        for j in linkage.topo.prismatic:
            jn = linkage.topo.joint_names[j]
            mk = {e: (refs[e].u, r.slider_acc[:, r.prismatic_names.index(jn)], refs[e].judged)
                  for e, r in runs.items()}
            curves.append(Curve(jn, lu, lkin.slider(jn)[2], mk, f"{jn}.a"))
        out.append(("slider", "slider accelerations", "s'' (m/s^2)", curves))
    return out


def table_turn(y: np.ndarray) -> np.ndarray:
    """An unwrapped body-angle line (deg, along the plotted input) moved by whole turns
    so that it starts in (-180, 180] deg, the range of the tables' ``angle_deg``
    (:func:`analytic.sweep.to_frame`): a crank sampled on its second turn (an
    accelerating input's verdict turn) reads 0 to 360 deg, as its input does on the
    axis, not 360 to 720."""
    y = np.asarray(y, float)
    finite = y[np.isfinite(y)]
    if not finite.size:
        return y
    return y - 360.0 * math.ceil((float(finite[0]) - 180.0) / 360.0)


def _extra_figures(linkage, lu, lkin, runs, refs, extra, tree) -> list[tuple]:
    """The figures drawn on request only (``extra``): slider positions (not judged;
    the engines' own from ``tree``) and transmission angles."""
    out = []
    if "slider_s" in extra and linkage.topo.prismatic:  # not judged: drawn only
        pos = {e: engine_slider_positions(r, tree) for e, r in runs.items()}
        curves = []
        for j in linkage.topo.prismatic:
            jn = linkage.topo.joint_names[j]
            mk = {e: (refs[e].u, pos[e][jn], refs[e].judged) for e in runs if jn in pos[e]}
            curves.append(Curve(jn, lu, lkin.slider(jn)[0], mk))
        out.append(("slider_s", "slider positions", "s (m)", curves))
    if "transmission" in extra and lkin.transmission:
        curves = [Curve(f"at {k}", lu, np.asarray(v, float), {})
                  for k, v in lkin.transmission.items()]
        out.append(("transmission", "transmission angles", "angle (deg)", curves))
    return out


def _force_figures(linkage, lu, lfrc, runs, refs) -> list[tuple]:
    """``(name, title, ylabel, curves)`` of the drive-effort and joint-force figures."""
    rev = linkage.driver_is_revolute
    mk = {e: (refs[e].u, r.drive_effort, refs[e].judged) for e, r in runs.items()}
    out = [("drive", "drive effort", "torque (N m)" if rev else "force (N)",
            [Curve("drive", lu, lfrc.effort, mk, "drive.effort")])]
    curves = []
    for jt in linkage.mech.joints:
        mk = {}
        for e, r in runs.items():
            k = r.joint_names.index(jt.name)
            mk[e] = (refs[e].u, np.linalg.norm(r.joint_force[:, k], axis=1), refs[e].judged)
        curves.append(Curve(jt.name, lu, np.linalg.norm(lfrc.joint_force[jt.name], axis=1),
                            mk, f"{jt.name}.force", "magnitude"))
    out.append(("forces", "joint force magnitudes", "|F| (N)", curves))
    return out


def _range_marks(r0, linkage, lu):
    """Limit and singular positions on the plotted axis, the feasible input range and
    the range the engines covered (input axis only; a time axis gets none)."""
    covered = (float(np.min(lu)), float(np.max(lu)))
    if r0.by_time:
        return [], None, covered
    rev = linkage.driver_is_revolute
    ev = _events(linkage)
    feas = linkage.feasible_ranges()
    feasible = None
    conv = math.degrees if rev else float
    full = rev and len(feas) == 1 and feas[0][1] - feas[0][0] >= 2 * math.pi * (1 - 1e-9)
    if not full:
        lo = min(conv(a) for a, _ in feas)
        hi = max(conv(b) for _, b in feas)
        feasible = (lo, hi)
    marks = []
    for kind, v in ev:
        if rev and full:  # onto the plotted axis: a full turn wrapped to [0, 360) deg
            v = v % 360.0
        marks.append((kind, float(v)))
    return marks, feasible, covered


_EVENT_KINDS = {"limit": "limit position", "singular": "singular position",
                "change_point": "change point"}


def _events(linkage) -> list[tuple[str, float]]:
    """Input limit positions, singular positions and change points of the linkage's
    sweep as ``(kind, input)`` (deg or m); not a rocker's extreme angle."""
    try:
        e = linkage.sweep(720, forces=False).events
    except LinkageError:  # marks are advice; a linkage whose sweep fails gets none
        return []
    keep = (e["kind"] != "limit") | e["detail"].astype(str).str.contains("input limit")
    e = e[keep & e["kind"].isin(list(_EVENT_KINDS))]
    return [(_EVENT_KINDS[k], float(v)) for k, v in zip(e["kind"], e["input"], strict=True)]


def error_figure(label: str, runs: dict, comparisons: dict, linkage, tolerance: float,
                 reference=reference_of) -> ErrorFigure | None:
    """Per engine, the largest normalised error of each judged family at each judged
    sample (:func:`reports.comparison.reference.sample_errors`), the worst quantity named, and the
    transmission angle (or the loop condition number) on a second axis.
    ``comparisons[engine]``: the verdict's comparisons of that run (their peaks)."""
    panels = {}
    xl = ""
    for e, r in runs.items():
        if r is None:
            continue
        ref = reference(r)
        _, xl = axis_of(r, linkage)
        errs = sample_errors(r, ref, comparisons.get(e, []))
        if not errs:
            continue
        keep = ref.judged & np.isfinite(ref.u)
        order = np.argsort(ref.u[keep], kind="stable")
        x = ref.u[keep][order]
        fam: dict[str, np.ndarray] = {}
        for q, v in errs.items():
            f = family_of(q)
            v = v[keep][order]
            fam[f] = v if f not in fam else np.fmax(fam[f], v)
        worst_q = max(errs, key=lambda q: np.nanmax(errs[q]) if np.isfinite(errs[q]).any()
                      else math.inf)
        wv = errs[worst_q]
        k = int(np.nanargmax(np.where(np.isnan(wv), -np.inf, wv)))
        kin = ref.kin
        if kin.transmission:
            name, tr = next(iter(kin.transmission.items()))
            twin = (f"transmission angle at {name} (deg)", np.asarray(tr)[keep][order])
        else:
            twin = ("loop Jacobian condition number (-)", kin.condition[keep][order])
        conv = convention_of(linkage)
        panels[e] = {"x": x, "families": {f: fam[f] for f in FAMILIES if f in fam},
                     "worst": (worst_q, float(wv[k]), float(ref.u[k])), "twin": twin,
                     # where, as the verdict table and JUnit say it (the one convention)
                     "worst_input": input_text(float(r.values[k]), conv),
                     "by_time": bool(r.by_time)}
    if not panels:
        return None
    return ErrorFigure("error", f"{label}: |engine - analytic| / peak, every judged quantity",
                       xl, panels, tolerance)


def motion_text(linkage, times, units=None) -> str:
    """One line saying how the input moves over the plotted samples, in the units of
    the figures' axes (``units``: a :class:`reports.figures.display_units.DisplayUnits`,
    default deg and rad/s): the prescribed rate actually reached between the first and
    last sample time ``times`` (s; NaN: unreached), and the description's law.  An
    accelerating crank's plotted turn runs at 5.8 to 7.7 rad/s, not its reference 3."""
    u = units or DisplayUnits()
    d = linkage.mech.driver
    kv, kw, ka = u.input_kinds(linkage.driver_is_revolute)
    fv, fw = u.factor(kv), u.factor(kw)
    uv, uw, ua = u.unit(kv), u.unit(kw), u.unit(ka)
    law = (f"{d.value * fv:.4g} {uv}, {d.velocity * fw:.4g} {uw}"
           + (f", {d.acceleration * u.factor(ka):.4g} {ua} at t = 0" if d.acceleration
              else " (constant rate)"))
    t = np.asarray(times, float)
    t = t[np.isfinite(t)]
    if not t.size or not d.acceleration:
        return f"input {d.joint}: {law}"  # the rate reached is the reference rate
    w0, w1 = (d.velocity + d.acceleration * np.array([t.min(), t.max()])) * fw
    return (f"input {d.joint}: {w0:.4g} to {w1:.4g} {uw} over the plotted samples "
            f"(t = {t.min():.4g} to {t.max():.4g} s); prescribed {law}")


def render(fig) -> bytes:
    """PNG bytes of a :class:`CurveFigure` or :class:`ErrorFigure`."""
    if isinstance(fig, ErrorFigure):
        return plots.error_panels(fig)
    return plots.curve_plot(fig)


def case_figure_data(label: str, runs: dict, comparisons: dict, linkage: Linkage,
                     tolerance: float, reference=reference_of) -> list:
    """Every data figure of a case (curves, then errors), not yet rendered; ``linkage``
    draws the analytic lines (each run's markers and errors read its own reference)."""
    lk = linkage
    figs = curve_figures(label, runs, lk, reference)
    ef = error_figure(label, runs, comparisons, lk, tolerance, reference)
    return figs + ([ef] if ef is not None else [])


def linkage_figure(label: str, linkage: Linkage) -> bytes:
    """The drawing of the linkage at four inputs over its range."""
    lk = linkage
    vals, full, _ = input_values(lk, 4)
    if not full:
        vals = np.linspace(vals[0], vals[-1], 4)
    return plots.draw_linkage(lk, vals, f"{label}: the linkage at four inputs")


def render_case(label: str, runs: dict, comparisons: dict, mech, tolerance: float
                ) -> dict[str, bytes]:
    """PNG bytes of every figure of a case, by name (a picklable pool task).  The
    analytic lines are those of the runs' own compiled Linkage (a pool worker's copy of
    it); ``mech``'s is built only when no engine ran."""
    carried = [r.linkage for r in runs.values() if r is not None]
    lk = carried[0] if carried else Linkage(mech)
    out = {"linkage": linkage_figure(label, lk)}
    for f in case_figure_data(label, runs, comparisons, lk, tolerance):
        out[f.name] = render(f)
    return out


__all__ = ["Curve", "CurveFigure", "ErrorFigure", "FAMILIES", "case_figure_data",
           "motion_text",
           "curve_figures", "error_figure", "linkage_figure", "render", "render_case",
           "table_turn"]
