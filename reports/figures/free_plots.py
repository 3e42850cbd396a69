"""``xval plot`` and ``xval animate`` of a released linkage (free motion).

The trajectory is :func:`analytic.free_motion.simulate`'s, sampled with
:meth:`~analytic.free_motion.FreeTrajectory.at` at evenly spaced times from 0 to the
duration (the samples ``xval simulate`` tabulates with the same ``--duration`` and
``--samples``); every point drawn is a sample, every event mark an event's time
(:attr:`~analytic.free_motion.FreeTrajectory.events`, located by root-finding).  The
panels are :class:`reports.figures.case_figures.CurveFigure` objects drawn by the report's
:func:`reports.figures.plots.draw_curve_axes`, built here in the display units of
:class:`reports.figures.display_units.DisplayUnits`; the events get a strip of their own where
each one is marked, and lines across the panels when they are few.

The animation's frames (:func:`reports.cli.animate.free_frames`) are the bodies' poses at
evenly spaced times, from the same solver calls that give the samples
(:func:`free_poses`), drawn like a prescribed run's, with the clock.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analytic.errors import LinkageError
from analytic.free_motion import simulate
from analytic.free_motion.dynamics import coefficients
from analytic.mechanism import Revolute
from reports.comparison.progress import engine_progress
from reports.figures import plots
from reports.figures.case_figures import Curve, CurveFigure

#: ``--what`` words of a free-motion plot -> what each panel shows.
FREE_WHAT = {"coordinate": "every joint's coordinate", "rate": "their rates",
             "acceleration": "their accelerations",
             "energy": "energies and the work-energy residual", "torque": "motor efforts",
             "forces": "joint reaction magnitudes"}
FREE_DEFAULT_WHAT = "coordinate,energy"
#: Event lines are drawn across the curve panels up to this many events (more would
#: hide the curves); the event strip marks every one.
MAX_EVENT_LINES = 40
#: Fewer samples (or frames) than this between turning points of the motion: the lines
#: cannot follow each swing, and a note says so.
MIN_PER_SWING = 4
#: Event kinds in the order the strip lists them, with their legend words.
EVENT_WORDS = {"singular": "singular position crossed",
               "limit": "limit position (a joint reverses)",
               "switch": "coordinate switch", "turn": "turning point (motion reverses)"}


class FreeOptionError(LinkageError):
    """An option that does not apply to the chosen motion: one line, status 2."""


def is_free(mech, free: bool, driven: bool) -> bool:
    """Whether the command draws the free motion: ``--free``, or a description with a
    ``[motion]`` table and no ``--driven``."""
    if free and mech.motion is None:
        raise FreeOptionError(f"--free: {mech.source or mech.name}: the description has no "
                              "[motion] table (initial joint, value, rate, duration); see "
                              "docs/tutorials/free-motion.md")
    return bool(free or (mech.motion is not None and not driven))


def parse_free_what(text: str | None) -> list[str]:
    words = [w.strip().lower() for w in (text or FREE_DEFAULT_WHAT).split(",") if w.strip()]
    bad = [w for w in words if w not in FREE_WHAT]
    if bad or not words:
        raise FreeOptionError(f"option --what: {', '.join(map(repr, bad)) or 'nothing'} is "
                              "not a quantity of a free-motion plot; use a comma-separated "
                              f"list of {', '.join(FREE_WHAT)}")
    return list(dict.fromkeys(words))


def trajectory(mech, duration: float | None = None):
    """:func:`analytic.free_motion.simulate` of ``mech`` (``duration`` s, default the
    description's), with a spinner, the time reached of the duration and the elapsed time
    on a terminal's standard error after a few seconds (a long run is not a hang)."""
    T = mech.motion.duration if duration is None else duration
    with engine_progress(f"free motion: {mech.name}, {T:g} s") as line:
        return simulate(mech, duration, progress=line.time)


def sample_times(traj, n: int) -> np.ndarray:
    """``n`` evenly spaced times from 0 to the duration (s): ``xval simulate``'s."""
    return np.linspace(0.0, traj.duration, n)


# ============================================================================ figures
@dataclass(frozen=True)
class _Kind:
    """A joint quantity's display kind for revolute and prismatic joints."""

    title: str
    revolute: str
    prismatic: str


_JOINT_KINDS = {"coordinate": _Kind("joint coordinates", "angle", "length"),
                "rate": _Kind("joint rates", "omega", "velocity"),
                "acceleration": _Kind("joint accelerations", "alpha", "acceleration")}
_JOINT_WORDS = {"angle": "joint angle", "length": "slider displacement",
                "omega": "joint angular rate", "velocity": "slider velocity",
                "alpha": "joint angular acceleration", "acceleration": "slider acceleration"}


def _fig(name, title, ylabel, curves, events) -> CurveFigure:
    return CurveFigure(name, title, "time (s)", ylabel, curves, events=list(events))


def joint_figures(mech, smp, word: str, units, events) -> list[CurveFigure]:
    """Joint coordinates, rates or accelerations (``word``) against time: one panel for
    the revolute joints (relative angles, continuous over turns) and one for the
    prismatic joints, in ``units``."""
    arr = {"coordinate": smp.x, "rate": smp.xd, "acceleration": smp.xdd}[word]
    k = _JOINT_KINDS[word]
    out = []
    for rev in (True, False):
        cols = [i for i, j in enumerate(mech.joints) if isinstance(j, Revolute) == rev]
        if not cols:
            continue
        kind = k.revolute if rev else k.prismatic
        f = units.factor(kind)
        curves = [Curve(mech.joints[i].name, smp.t, arr[:, i] * f, {}) for i in cols]
        out.append(_fig(f"free_{word}_{kind}", f"{mech.name}: {k.title}",
                        f"{_JOINT_WORDS[kind]} ({units.unit(kind)})", curves, events))
    return out


def energy_scale(smp) -> float:
    """The run's energy scale (J): the largest kinetic energy plus the potential
    energy's range (``xval simulate``'s), 1 J if both are zero."""
    return float(np.max(smp.kinetic) + np.ptp(smp.potential)) or 1.0


def energy_figures(mech, smp, events) -> list[CurveFigure]:
    """Kinetic, potential and total energy with the motors' and loads' work and the
    dissipated energy (J, since t = 0); then the work-energy residual on its own panel."""
    t, fm = smp.t, mech.motion
    curves = [Curve("kinetic T", t, smp.kinetic, {}),
              Curve("potential V (gravity, springs)", t, smp.potential, {}),
              Curve("total T + V", t, smp.kinetic + smp.potential, {})]
    if fm.motors:
        curves.append(Curve("motor work", t, smp.work_motor, {}))
    if mech.loads:
        curves.append(Curve("loads' work", t, smp.work_loads, {}))
    if fm.dampers:
        curves.append(Curve("dissipated", t, smp.dissipated, {}))
    res = np.asarray(smp.energy_residual, float)
    worst = float(np.max(np.abs(res)))
    return [_fig("free_energy", f"{mech.name}: energies", "energy (J)", curves, events),
            _fig("free_residual", f"work-energy residual: max |r| {worst:.3g} J, "
                 f"{worst / energy_scale(smp):.3g} of the energy scale",
                 "residual (J)", [Curve("r = T + V - E0 - work + dissipated", t, res, {})],
                 events)]


def effort_figures(mech, smp, events) -> list[CurveFigure]:
    """Each motor's effort (N m or N) against time."""
    cs = [Curve(f"motor at {j}", smp.t, v, {}) for j, v in smp.motor_effort.items()]
    return [_fig("free_torque", f"{mech.name}: motor efforts", "effort (N m or N)", cs,
                 events)] if cs else []


def force_figures(mech, smp, events) -> list[CurveFigure]:
    """Each joint's reaction magnitude (N), the solver's kinetostatics at the sample
    with every force element applied."""
    cs = [Curve(f"|F| at {j}", smp.t, np.linalg.norm(f, axis=1), {})
          for j, f in smp.reactions.items()]
    return [_fig("free_forces", f"{mech.name}: joint reactions", "force (N)", cs, events)]


def free_figures(mech, traj, smp, what: list[str], units) -> tuple[list[CurveFigure], list]:
    """``(panels in the order asked, notes)``: the curve figures of ``what`` from the
    samples ``smp``, with the events as lines when there are at most
    :data:`MAX_EVENT_LINES`."""
    events = [(EVENT_WORDS.get(e.kind, e.kind), e.t) for e in traj.events]
    lines = events if len(events) <= MAX_EVENT_LINES else []
    figs, notes = [], []
    for w in what:
        if w in _JOINT_KINDS:
            figs += joint_figures(mech, smp, w, units, lines)
        elif w == "energy":
            figs += energy_figures(mech, smp, lines)
        elif w == "torque":
            got = effort_figures(mech, smp, lines)
            if not got:
                notes.append(f"--what torque: nothing to plot for {mech.name!r} (no "
                             "[[motors]])")
            figs += got
        elif w == "forces":
            figs += force_figures(mech, smp, lines)
    if events and not lines:
        notes.append(f"{len(events)} events: marked in the event strip only (lines across "
                     f"the panels up to {MAX_EVENT_LINES})")
    return figs, notes


def swing_note(traj, spacing: float, what: str) -> str | None:
    """A note when ``what`` (samples, frames) ``spacing`` s apart are too few to follow
    each swing: fewer than :data:`MIN_PER_SWING` between turning points on average."""
    turns = sum(e.kind == "turn" for e in traj.events)
    if turns < 2 or spacing <= 0:
        return None
    per = traj.duration / turns / spacing
    if per >= MIN_PER_SWING:
        return None
    return (f"the motion reverses {turns} times in {traj.duration:g} s (every "
            f"{traj.duration / turns:.3g} s on average) but the {what} are {spacing:.3g} s "
            f"apart: they cannot follow each swing (give more, or a shorter --duration)")


def motion_header(mech, traj, n: int, units) -> str:
    """One line: the release state, the run and its samples, the integrator."""
    fm = mech.motion
    rev = isinstance(next(j for j in mech.joints if j.name == fm.joint), Revolute)
    kv, kw = ("angle", "omega") if rev else ("length", "velocity")
    return (f"released at {fm.joint} = {fm.value * units.factor(kv):.6g} {units.unit(kv)}, "
            f"{fm.rate * units.factor(kw):.6g} {units.unit(kw)}; {traj.duration:g} s, {n} "
            f"samples every {traj.duration / (n - 1):.4g} s; {traj.method} rtol "
            f"{traj.rtol:g}, {traj.nfev} evaluations; {len(traj.events)} events")


def draw_events(ax, traj) -> None:
    """The event strip: one row per kind met, every event marked at its time."""
    kinds = [k for k in EVENT_WORDS if any(e.kind == k for e in traj.events)]
    kinds += sorted({e.kind for e in traj.events} - set(kinds))
    for r, k in enumerate(kinds):
        t = [e.t for e in traj.events if e.kind == k]
        ax.plot(t, np.full(len(t), r), ls="none", marker="|", ms=12, mew=1.4,
                color=plots.event_colour(EVENT_WORDS.get(k, k)))
    ax.set_yticks(range(len(kinds)))
    ax.set_yticklabels([f"{EVENT_WORDS.get(k, k)} ({sum(e.kind == k for e in traj.events)})"
                        for k in kinds], fontsize=plots.LABEL_PT)
    ax.set_ylim(-0.7, max(len(kinds), 1) - 0.3)
    ax.set_xlim(0.0, traj.duration)
    ax.set_xlabel("time (s)")
    ax.set_title(f"events ({len(traj.events)})" if kinds else "events: none met",
                 fontsize=plots.TITLE_PT)
    ax.grid(alpha=0.3, axis="x")


def draw_free(figs, traj, title: str, header: str, units):
    """One matplotlib figure: a panel per curve figure (time shared), then the event
    strip."""
    plt = plots.plt
    n = len(figs)
    fig = plt.figure(figsize=(9.0, 2.7 * n + 1.5 + 0.6))
    grid = fig.add_gridspec(n + 1, 1, height_ratios=[1.0] * n + [0.55])
    first = None
    for i, f in enumerate(figs):
        ax = fig.add_subplot(grid[i, 0], sharex=first)
        first = first or ax
        plots.draw_curve_axes(ax, f)
    draw_events(fig.add_subplot(grid[n, 0], sharex=first), traj)
    fig.suptitle(f"{title}\n{header}\n{units.header()}", fontsize=plots.TITLE_PT)
    fig.tight_layout()
    return fig


# ============================================================================ animation
def free_poses(traj, times) -> tuple[np.ndarray, np.ndarray]:
    """``(theta (F, B) rad, origin (F, B, 2) m)``: every body frame at ``times`` (s),
    from the solver's kinematics at the integrated coordinate of the segment each time
    falls in (the calls :meth:`FreeTrajectory.at` makes for the samples)."""
    y, si = traj.state(times)
    B = len(traj.mech.bodies)
    theta, origin = np.empty((len(y), B)), np.empty((len(y), B, 2))
    for k in np.unique(si):
        m = si == k
        kin = coefficients(traj.segments[k].lk, y[m, 0]).kin
        theta[m], origin[m] = kin.theta, kin.origin
    return theta, origin


__all__ = ["EVENT_WORDS", "FREE_DEFAULT_WHAT", "FREE_WHAT", "FreeOptionError", "draw_free",
           "free_figures", "free_poses", "is_free",
           "motion_header", "parse_free_what", "sample_times", "swing_note", "trajectory"]
