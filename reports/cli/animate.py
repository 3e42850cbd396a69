"""``xval animate CASE|FILE --out F.gif|F.mp4|F.html``: the linkage moving through a cycle
(drawn by :mod:`reports.figures.animation` from :mod:`reports.figures.poses`); the
options, the output checks and the engine runs asked for."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib import animation

from analytic.errors import OutputError
from analytic.motion_spec import MAX_DURATION
from reports.cli import options as opt
from reports.cli.plot import check_out, load_for_figure
from reports.cli.simulate import MIN_DURATION
from reports.comparison.progress import engine_progress
from reports.comparison.runs import engine_list
from reports.figures.animation import build_animation, write
from reports.figures.free_plots import (
    FreeOptionError,
    is_free,
    swing_note,
    trajectory,
)
from reports.figures.poses import (
    FORMATS,
    FRAMES,
    analytic_frames,
    engine_poses,
    engine_run,
    free_frames,
)
from sim_models import compile_linkage
from sim_models.engines.registry import engine_names


def cmd_animate(args) -> int:
    if args.out is None:
        raise OutputError("option --out is required: F.gif, F.mp4 or F.html")
    check_out(args.out, FORMATS)
    if Path(args.out).suffix.lower() == ".mp4":
        if not animation.writers.is_available("ffmpeg"):
            raise OutputError(f"--out {args.out!r}: MP4 needs ffmpeg, which is not on PATH; "
                              "write .gif or .html instead (or install ffmpeg)")
    mech, release = load_for_figure(args)  # --free: what xval simulate releases
    if is_free(mech, args.free, args.driven):
        if release is not None:
            print(release.text)
        return _animate_free(args, mech)
    if args.duration is not None:
        raise FreeOptionError("option --duration is for free motion (a description with "
                              "[motion]); a prescribed animation runs one cycle")
    # the compiled linkage (analytic solution + simulation tree): the frames' times come
    # from the engines' plan where the input does not turn fully
    tree = compile_linkage(mech)
    fr = analytic_frames(tree.linkage, args.frames, args.forces, tree)
    notes = []
    if args.engine:
        for e in engine_list(args.engine):
            with engine_progress(f"{e}: {mech.name}, {fr.n} frames"):
                r = engine_run(mech, tree, e, args.frames, times=fr.times)  # a frame a sample
            if not r.ok:
                notes.append(f"{e}: run failed: {r.reason}")
            poses = engine_poses(r, tree, fr.values, False, times=fr.times)
            missing = int(np.sum(~np.all(np.isfinite(poses.theta), axis=1)))
            if missing == fr.n:
                notes.append(f"{e}: not drawn: no pose at any frame ("
                             + (r.reason or "the run recorded no body poses") + ")")
            elif missing:
                notes.append(f"{e}: no pose at {missing} of {fr.n} frames (drawn where it "
                             "has one" + (f"; {r.reason}" if r.reason else "") + ")")
            fr.engines.append(poses)
    label = "analytic" + ("".join(f" + {e.label} (dashed)" for e in fr.engines))
    an = build_animation(fr, f"{mech.name}: {label}")
    write(an, args.out, args.fps)
    for n in notes:
        print("note:", n)
    print(f"wrote {args.out} ({fr.n} frames, {fr.times[-1]:.4g} s of motion)")
    return 0


def _animate_free(args, mech) -> int:
    """The free motion of ``[motion]``: poses at ``--frames`` evenly spaced times from 0
    to the duration, with the clock."""
    if args.engine:
        raise FreeOptionError(f"option --engine: {mech.name!r} is animated in free motion (its "
                              "[motion] table), which draws no engine run; add --driven for "
                              "the prescribed cycle")
    traj = trajectory(mech, args.duration)
    fr = free_frames(traj, args.frames, args.forces)
    an = build_animation(fr, f"{mech.name}: free motion, {traj.duration:g} s "
                             f"({len(traj.events)} events)")
    write(an, args.out, args.fps)
    note = swing_note(traj, traj.duration / (fr.n - 1), "frames")
    if note:
        print("note:", note)
    print(f"wrote {args.out} (free motion, {fr.n} frames every "
          f"{traj.duration / (fr.n - 1):.4g} s over {traj.duration:g} s)")
    return 0


def register(sub) -> None:
    s = sub.add_parser("animate", help="the linkage moving through a cycle, or its free "
                       "motion (GIF, MP4, HTML)")
    s.add_argument("case", help="built-in case name or TOML file")
    mode = s.add_mutually_exclusive_group()
    mode.add_argument("--free", action="store_true",
                      help="animate the free motion of the description's [motion] table (the "
                           "default when it has one): poses at evenly spaced times, clock shown")
    mode.add_argument("--driven", action="store_true",
                      help="animate the prescribed cycle of [driver] even when the "
                           "description has a [motion] table")
    s.add_argument("--out", type=opt.output_file, help="F.gif, F.mp4 (needs ffmpeg) or F.html")
    engines = [*engine_names(), "all"]
    s.add_argument("--engine", choices=engines, metavar="ENGINE",
                   help="draw this engine's poses (dashed) over the analytic ones: "
                        f"{opt.choices_text(engines)}")
    s.add_argument("--forces", action="store_true",
                   help="joint forces as arrows on one scale, with a key")
    s.add_argument("--frames", type=opt.int_range(36, 720, "frames per cycle"),
                   default=FRAMES, help=f"frames per cycle (free motion: over the run), 36 "
                                        f"to 720 (default {FRAMES})")
    s.add_argument("--duration", type=opt.finite_float(MAX_DURATION, "s", lo=MIN_DURATION),
                   help=f"free motion: seconds, {MIN_DURATION:g} to {MAX_DURATION:g} "
                        "(default the description's)")
    s.add_argument("--fps", type=opt.int_range(1, 60, "frames per second"), default=24,
                   help="frames per second, 1 to 60 (default 24)")
    s.set_defaults(func=cmd_animate)
