"""``xval plot CASE|FILE``: the full-cycle curves of one linkage, with engine runs overlaid.

One implementation with the report: the curves are
:func:`reports.figures.case_figures.curve_figures` (the analytic line of
:func:`reports.comparison.reference.analytic_line`), the engines' errors
:func:`reports.figures.case_figures.error_figure` (the verdict's reference and peaks), drawn by
:func:`reports.figures.plots.draw_curve_axes` /
:func:`reports.figures.plots.draw_error_axes` onto one figure, in the display units of
:mod:`reports.figures.display_units`.

Without ``--engine`` the analytic lines follow :func:`cycle_plan`: the sweep's inputs
over the full turn (or the feasible range) at the description's constant rate; a driver
that accelerates is placed by the engines' own sampling plan instead.  With
``--engine`` the lines follow the runs, exactly as in the report.

A description with a ``[motion]`` table is plotted in free motion (``--driven``: its
prescribed cycle instead; ``--free`` insists): :mod:`reports.figures.free_plots` draws the
trajectory of ``xval simulate`` (same ``--duration`` and ``--samples``) against time.
"""

from __future__ import annotations

import argparse
import os
import sys
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import numpy as np

from analytic import Linkage, load_case
from analytic.errors import LinkageError, OutputError
from analytic.motion_spec import MAX_DURATION, MAX_SAMPLES
from analytic.sweep import input_values
from analytic.tolerances import ENGINE_RELATIVE
from reports.cli import options as opt
from reports.cli.options import UsageError
from reports.cli.paths import check_outputs, safe_stem
from reports.cli.simulate import MIN_DURATION
from reports.comparison import runs as verdict_runs
from reports.comparison.free_cases import command_case
from reports.comparison.progress import engine_progress
from reports.comparison.runs import engine_list, settings_for
from reports.figures import free_plots, plots
from reports.figures import free_plots as fp
from reports.figures.case_figures import curve_figures, error_figure, motion_text
from reports.figures.display_units import DisplayUnits, convert_figure
from reports.figures.free_plots import FREE_DEFAULT_WHAT, FREE_WHAT, FreeOptionError
from reports.figures.plots import DPI
from sim_models import compile_linkage
from sim_models.engines.protocol import plan_samples
from sim_models.engines.registry import engine_names
from sim_models.runs.engine_run import RunRequest
from sim_models.runs.free_run import FreeRequest

#: ``--what`` words -> curve figure names of :func:`reports.figures.case_figures.curve_figures`.
WHAT = {"angle": ("angle",), "omega": ("omega",), "alpha": ("alpha",),
        "slider": ("slider_s", "slider"), "forces": ("forces",), "torque": ("drive",),
        "transmission": ("transmission",)}
DEFAULT_WHAT = "angle,omega,alpha,slider,torque"
FORMATS = (".png", ".svg", ".pdf")
#: Analytic line points of a plot without engines (the report's line uses the runs').
CYCLE_POINTS = 360


class NoDisplay(LinkageError):
    """``--show`` (or ``xval view``) without a display: one line, status 2."""


@dataclass(frozen=True)
class PlanSamples:
    """Where the analytic lines of a plot without engines are placed: the fields of an
    engine run that :func:`reports.comparison.reference.analytic_line` reads (SI; ``times`` s from
    the reference value, negative behind it)."""

    times: np.ndarray
    values: np.ndarray
    driver_velocity: np.ndarray
    driver_acceleration: np.ndarray
    by_time: bool = False
    has_forces: bool = True


def cycle_plan(linkage, tree=None, points: int = CYCLE_POINTS) -> PlanSamples:
    """The sweep's inputs (full turn from 0 deg, or the feasible range) at
    the times the description's constant rate reaches them; for an accelerating or
    standing driver, the engines' plan (:func:`sim_models.engines.protocol.plan_samples`)."""
    d = linkage.mech.driver
    if d.acceleration == 0.0 and d.velocity != 0.0:
        vals, _, _ = input_values(linkage, points, start=0.0)  # a full turn: 0 to 360 deg
        vals = np.asarray(vals, float)
        t = (vals - d.value) / d.velocity
        n = len(vals)
        return PlanSamples(t, vals, np.full(n, d.velocity), np.zeros(n))
    p = plan_samples(tree or compile_linkage(linkage.mech), RunRequest.revolutions, 72)
    return PlanSamples(p.times, p.values, p.velocity, p.acceleration, p.by_time)


def parse_what(text: str | None) -> list[str]:
    words = [w.strip().lower() for w in (text or DEFAULT_WHAT).split(",") if w.strip()]
    bad = [w for w in words if w not in WHAT]
    if bad or not words:
        raise LinkageError(f"option --what: {', '.join(map(repr, bad)) or 'nothing'} is not a "
                           f"quantity; use a comma-separated list of {', '.join(WHAT)}")
    return words


def case_figures(mech, what: list[str], engines: list[str], settings: dict,
                 revolutions: int | None = None, samples: int | None = None,
                 quiet: tuple[str, ...] = (), wall_limit: float | None = None):
    """``(curve figures in the order asked, error figure or None, runs, notes)`` of one
    case: the report's figure code on the analytic solution and the engine runs
    (``revolutions``/``samples`` None: :class:`sim_models.runs.engine_run.RunRequest`'s;
    ``wall_limit``: s of stepping per engine run, None: none)."""
    revolutions = RunRequest.revolutions if revolutions is None else revolutions
    samples = RunRequest.samples if samples is None else samples

    tree = compile_linkage(mech)  # the analytic solution, once, for every engine
    lk = tree.linkage
    runs, comps, notes = {}, {}, []
    if engines:
        for e in engines:
            with engine_progress(f"{e}: {mech.name}, {revolutions} revolutions"):
                r, c = verdict_runs.run_comparison(tree, e, settings[e], "run", revolutions,
                                                   samples, wall_limit)
            runs[e], comps[e] = r, c
            if not r.ok:
                notes.append(f"{e}: run failed: {r.reason}")
    names = [n for w in what for n in WHAT[w]]
    extra = tuple(n for n in ("transmission", "slider_s") if n in names)
    plan = None if runs else cycle_plan(lk, tree)
    figs = curve_figures(mech.name, runs, lk, plan=plan, extra=extra, tree=tree)
    by = {f.name: f for f in figs}
    chosen = [by[n] for n in names if n in by]
    for w in what:
        if w not in quiet and not any(n in by for n in WHAT[w]):
            notes.append(f"--what {w}: nothing to plot for {mech.name!r}"
                         + (" (no masses: no forces)" if w in ("forces", "torque") else
                            " (no prismatic joint)" if w == "slider" else ""))
    err = None
    if runs:
        err = error_figure(mech.name, runs, comps, lk, ENGINE_RELATIVE)
    return chosen, err, runs, notes


def motion_line(mech, runs: dict, units) -> str:
    """The header line of the input's motion over the plotted samples
    (:func:`reports.figures.case_figures.motion_text`): the runs' sample times, or those of
    :func:`cycle_plan` without engines."""
    lk = Linkage(mech)
    if runs:
        times = np.concatenate([np.asarray(r.times, float) for r in runs.values()])
    else:
        times = cycle_plan(lk).times
    return motion_text(lk, times, units)


def draw(figs, err, units, title: str, motion: str = ""):
    """One matplotlib figure: a panel per curve figure, then a row of error panels."""
    plt = plots.plt
    figs = [convert_figure(f, units) for f in figs]
    err = convert_figure(err, units) if err is not None else None
    n = len(figs) + (1 if err is not None else 0)
    ne = len(err.panels) if err is not None else 0
    fig = plt.figure(figsize=(9.0, 2.7 * max(n, 1) + 0.6))
    grid = fig.add_gridspec(max(n, 1), max(ne, 1))
    for i, f in enumerate(figs):
        ax = fig.add_subplot(grid[i, :])
        plots.draw_curve_axes(ax, f)
    if err is not None:
        axes = []
        for k, (engine, p) in enumerate(err.panels.items()):
            ax = fig.add_subplot(grid[n - 1, k], sharey=axes[0] if axes else None)
            plots.draw_error_axes(ax, err, engine, p)
            axes.append(ax)
        axes[0].set_ylabel("|engine - analytic| / peak (-)")
        axes[0].legend(fontsize=plots.LEGEND_PT, loc="upper left",
                       bbox_to_anchor=(0.0, -0.28), ncol=5)
    fig.suptitle(f"{title}\n{motion + chr(10) if motion else ''}{units.header()}",
                 fontsize=plots.TITLE_PT)
    fig.tight_layout()
    return fig


def has_display() -> tuple[bool, str]:
    """``(True, "")`` when a window can open, else ``(False, why)``."""
    if sys.platform.startswith(("win", "darwin")):
        return True, ""
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return True, ""
    return False, "no display (neither DISPLAY nor WAYLAND_DISPLAY is set)"


def check_out(out: str | None, formats=FORMATS) -> None:
    if out is not None and Path(out).suffix.lower() not in formats:
        raise OutputError(f"option --out {out!r}: the file name must end in "
                          f"{', '.join(formats)} (the format is taken from it)")


def cmd_plot(args) -> int:
    check_out(args.out)
    if args.show:
        ok, why = has_display()
        if not ok and not args.out:
            raise NoDisplay(f"--show: {why}; write the figure with --out F.png|svg|pdf")
    mech, release = load_for_figure(args)
    free = free_plots.is_free(mech, args.free, args.driven)
    # the default name is made safe from the description's (never '../x' or '/x')
    stem = f"{safe_stem(mech.name)}-{'free-' if free else ''}plot.png"
    out = args.out or (None if args.show else stem)
    check_outputs([("--out" if args.out else "the figure", out)], [("the case file", args.case)])
    units = DisplayUnits.parse(args.units)
    make, summary, notes = (_free_plot if free else _driven_plot)(args, mech, units)
    cannot_show = None
    if args.show:
        ok, why = has_display()
        try:
            if not ok:
                raise NoDisplay(f"--show: {why}")
            _interactive_backend()  # before the figure exists, so it gets a window
        except NoDisplay as e:
            cannot_show = e
    fig = make()
    if release is not None:
        print(release.text)
    for n in notes:
        print("note:", n)
    if out:
        try:
            fig.savefig(out, dpi=DPI, bbox_inches="tight")
        except OSError as e:
            raise OutputError(f"cannot write {out!r}: {e.strerror or e}") from None
        print(f"wrote {out} ({summary}; {units.header()})")
    if cannot_show is not None:
        raise NoDisplay(f"{cannot_show}; the figure was written to {out}")
    if args.show:
        import matplotlib.pyplot as plt
        plt.show()  # pragma: no cover - needs a display
    return 0


def load_for_figure(args):
    """``(mech, release)``: the case of ``xval plot``/``xval animate``; with ``--free``, a
    built-in case without ``[motion]`` released exactly as ``xval simulate`` releases it
    (:func:`reports.comparison.free_cases.command_case`: the same case, the same
    refusals), with the :class:`~reports.comparison.free_cases.Release` to state
    (``None`` otherwise)."""
    if getattr(args, "free", False):
        return command_case(args.case, args.duration)
    return load_case(args.case), None


def _option_range(option: str, parse, value) -> None:
    """``value`` of ``option`` through the argparse type ``parse``: one line if refused."""

    try:
        parse(str(value))
    except argparse.ArgumentTypeError as e:
        raise UsageError(f"argument {option}: {e} (see 'xval plot --help')") from None


def _integer(text: str) -> int:
    """An integer option whose range depends on the motion plotted (checked by
    :func:`_option_range` once the description is read)."""
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None


def _driven_plot(args, mech, units):
    """``(draw, summary, notes)`` of the prescribed cycle (with engine runs)."""
    if args.duration is not None:
        raise FreeOptionError("option --duration is for free motion (a description with "
                              "[motion]); the prescribed cycle's length is --revolutions")
    if args.samples is not None:
        _option_range("--samples", opt.samples, args.samples)
    if args.revolutions is not None:
        _option_range("--revolutions", opt.revolutions, args.revolutions)
    if args.wall_limit is not None and not args.engine:
        raise UsageError("option --wall-limit bounds an engine's run; it needs --engine")
    what = parse_what(args.what)
    engines, settings = [], {}
    if args.engine:
        engines = engine_list(args.engine)
        settings = settings_for(engines)
    quiet = tuple(what) if args.what is None else ()  # no notes for the default
    figs, err, runs, notes = case_figures(mech, what, engines, settings,
                                          args.revolutions, args.samples, quiet,
                                          args.wall_limit or DEFAULT_WALL_LIMIT)
    title = f"{mech.name}: " + ("analytic (lines)" + (", " + ", ".join(runs) +
                                " (markers; errors in the last row)" if runs else
                                "; no engine run (add --engine for markers)"))
    summary = f"{len(figs)} panels{', with ' + ', '.join(runs) if runs else ''}"
    return (lambda: draw(figs, err, units, title, motion_line(mech, runs, units))), \
        summary, notes


#: Wall-clock seconds of stepping an engine's run for a figure may take (``--wall-limit``;
#: the free runs' default, :class:`sim_models.runs.free_run.FreeRequest`'s): PyBullet's 1000
#: revolutions of the seed four-bar take about 10 minutes.
DEFAULT_WALL_LIMIT = FreeRequest.wall_limit
#: Most samples a free-motion figure draws: its panels are 9 in wide at ``DPI`` (1350
#: pixels at 150 dpi), so 10001 samples already put about 7 in every pixel column and
#: more draw nothing the eye can see, while each costs about 0.75 ms of CPU with the
#: forces (measured: 20001 samples 18 s, 1e6 samples no figure in minutes).  Every
#: sample is in ``xval simulate --csv`` (to 1e6).
MAX_FIGURE_SAMPLES = 10_001


def _figure_holds(n: int, source: str) -> None:
    """Refuse (one line) a free figure of more than :data:`MAX_FIGURE_SAMPLES` samples."""
    if n > MAX_FIGURE_SAMPLES:
        raise UsageError(f"{source} {n}: a figure draws at most {MAX_FIGURE_SAMPLES} samples "
                         "(its panels are 1350 pixels wide; more draw nothing more); give "
                         f"--samples {MAX_FIGURE_SAMPLES} or fewer, or write them all with "
                         f"xval simulate --csv FILE --samples {n}")


def _free_plot(args, mech, units):
    """``(draw, summary, notes)`` of the free motion: the trajectory of ``[motion]`` at
    evenly spaced times (``xval simulate``'s samples)."""
    for given, option in ((args.engine, "--engine"), (args.revolutions, "--revolutions"),
                          (args.wall_limit, "--wall-limit")):
        if given is not None:
            raise fp.FreeOptionError(
                f"option {option}: {mech.name!r} is plotted in free motion (its [motion] "
                f"table), which draws no engine run; add --driven for the prescribed cycle")
    if args.samples is not None:
        _option_range("--samples", opt.int_range(2, MAX_SAMPLES), args.samples)
    n = args.samples or mech.motion.samples
    _figure_holds(n, "--samples" if args.samples else "the description's [motion] samples")
    what = fp.parse_free_what(args.what)
    traj = fp.trajectory(mech, args.duration)
    smp = traj.at(fp.sample_times(traj, n), forces="forces" in what)
    figs, notes = fp.free_figures(mech, traj, smp, what, units)
    note = fp.swing_note(traj, traj.duration / (n - 1), "samples")
    notes += [note] if note else []
    title = f"{mech.name}: free motion (the description's [motion]; --driven: the prescribed cycle)"
    header = fp.motion_header(mech, traj, n, units)
    summary = (f"free motion, {len(figs)} panels and the events, {n} samples over "
               f"{traj.duration:g} s")
    return (lambda: fp.draw_free(figs, traj, title, header, units)), summary, notes


def _interactive_backend() -> None:  # pragma: no cover - needs a display
    """Switch matplotlib (set to Agg by :mod:`reports.figures.plots`) to a toolkit that opens
    windows; a NoDisplay error when none can."""
    import matplotlib.pyplot as plt
    for backend in ("TkAgg", "QtAgg", "GTK4Agg", "GTK3Agg", "MacOSX"):
        try:
            plt.switch_backend(backend)
            plt.close(plt.figure())  # a toolkit that cannot reach the display fails here
            return
        except Exception:  # noqa: BLE001 - try the next toolkit
            plt.switch_backend("Agg")
            continue
    raise NoDisplay(f"--show: no interactive matplotlib backend can open a window (have "
                    f"{matplotlib.get_backend()})")


def register(sub) -> None:
    s = sub.add_parser("plot", help="full-cycle curves of one linkage (engines optional), or "
                       "its free motion against time")
    s.add_argument("case", help="built-in case name or TOML file")
    mode = s.add_mutually_exclusive_group()
    mode.add_argument("--free", action="store_true",
                      help="plot the free motion of the description's [motion] table (the "
                           "default when it has one): joint coordinates, energies and "
                           "events against time, as xval simulate computes them")
    mode.add_argument("--driven", action="store_true",
                      help="plot the prescribed cycle of [driver] even when the description "
                           "has a [motion] table")
    s.add_argument("--what",
                   help=f"comma-separated: {', '.join(WHAT)} (default {DEFAULT_WHAT}); free "
                        f"motion: {', '.join(FREE_WHAT)} (default {FREE_DEFAULT_WHAT})")
    engines = [*engine_names(), "all"]
    s.add_argument("--engine", choices=engines, metavar="ENGINE",
                   help="overlay this engine's run (markers) and plot its error below: "
                        f"{opt.choices_text(engines)}")
    s.add_argument("--units", type=opt.units_option, help=opt.UNITS_HELP)
    s.add_argument("--out", type=opt.output_file,
                   help="output file; .png, .svg or .pdf (default <case>-plot.png; free "
                        "motion <case>-free-plot.png)")
    s.add_argument("--show", action="store_true", help="open a window (needs a display)")
    s.add_argument("--revolutions", type=_integer,
                   help=f"engine revolutions (the last is plotted; default "
                        f"{RunRequest.revolutions}; not in free motion)")
    s.add_argument("--samples", type=_integer,
                   help=f"engine samples per revolution (default {RunRequest.samples}); free "
                        f"motion: samples of the trajectory, 2 to {MAX_FIGURE_SAMPLES} (what "
                        "a figure draws; default the description's)")
    s.add_argument("--duration", type=opt.finite_float(MAX_DURATION, "s", lo=MIN_DURATION),
                   help=f"free motion: seconds, {MIN_DURATION:g} to {MAX_DURATION:g} "
                        "(default the description's)")
    s.add_argument("--wall-limit", type=opt.sim_range("WALL_LIMIT"), metavar="SECONDS",
                   help=f"end each engine's run after this much wall-clock stepping "
                        f"(default {DEFAULT_WALL_LIMIT:g} s, as xval simulate's; the run "
                        "is drawn up to there and a note says so)")
    s.set_defaults(func=cmd_plot)


__all__ = ["NoDisplay", "PlanSamples", "case_figures", "cmd_plot", "cycle_plan", "draw",
           "has_display", "parse_what", "register"]
