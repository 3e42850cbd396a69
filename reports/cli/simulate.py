"""``xval simulate CASE|FILE``: a released linkage's exact trajectory, tabulated.

Reads the description's ``[motion]`` (initial joint coordinate and rate, duration) and
its springs, dampers and motors; integrates the exact equation of motion
(:mod:`analytic.free_motion`) and prints, at evenly spaced times, every joint's
coordinate (deg or m) and the energies, then the events met.  ``--csv`` writes every
joint's coordinate, rate and acceleration, the energies and the motors' power (SI);
``--json`` prints one JSON object (SI).  ``--engine NAME|all`` also releases the
linkage in the engines and judges each run against the exact trajectory
(:mod:`reports.cli.simulate_engines`; status 1 on a failed verdict).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd

from analytic.errors import OutputError
from analytic.free_motion import simulate
from analytic.mechanism import Revolute
from analytic.motion_spec import MAX_DURATION, MAX_SAMPLES, samples_problem
from reports.cli import options as opt
from reports.cli.own_options import add_own_options
from reports.cli.paths import write_csv
from reports.cli.simulate_engines import (
    add_options,  # --engine, --set, ..., --junit, --summary
    cmd_engines,
    engine_options_given,
)
from reports.comparison.free_cases import (
    MIN_DURATION,  # one definition for every door
    command_case,
    free_request_problem,
)
from reports.comparison.progress import engine_progress
from sim_models.runs.free_run import FreeRequest


def register(sub) -> None:
    s = sub.add_parser("simulate", help="free motion: integrate a released linkage")
    s.add_argument("case", help="built-in case name or TOML file with a [motion] table (a "
                        "built-in case without one is released at rest under gravity, as "
                        "the report's free-motion section releases it), or your own MJCF "
                        "or URDF model (.xml, .urdf, read as xval import reads it)")
    add_own_options(s)
    s.add_argument("--duration", type=opt.finite_float(MAX_DURATION, "s", lo=MIN_DURATION),
                   help=f"seconds, {MIN_DURATION:g} to {MAX_DURATION:g} (default: the "
                        "description's)")
    s.add_argument("--samples", type=opt.int_range(2, MAX_SAMPLES),
                   help=f"output samples, 2 to {MAX_SAMPLES} (fewer for a mechanism of more "
                        "than 4 joints: memory; default: the description's)")
    s.add_argument("--csv", type=opt.output_file,
                   help="write the samples to this CSV file ('-': standard output)")
    s.add_argument("--json", action="store_true", help="print one JSON object (SI)")
    add_options(s)
    s.set_defaults(func=cmd_simulate)


def _frame(mech, smp):
    cols = {"t_s": smp.t}
    for k, j in enumerate(mech.joints):
        u = ("rad", "rad/s", "rad/s^2") if isinstance(j, Revolute) else ("m", "m/s", "m/s^2")
        cols[f"{j.name}_{u[0]}"] = smp.x[:, k]
        cols[f"{j.name}_rate_{u[1]}"] = smp.xd[:, k]
        cols[f"{j.name}_accel_{u[2]}"] = smp.xdd[:, k]
    cols["coordinate"] = smp.coordinate
    cols["kinetic_J"] = smp.kinetic
    cols["potential_J"] = smp.potential
    cols["motor_work_J"] = smp.work_motor
    cols["load_work_J"] = smp.work_loads
    cols["dissipated_J"] = smp.dissipated
    cols["energy_residual_J"] = smp.energy_residual
    cols["motor_power_W"] = smp.motor_power
    return pd.DataFrame(cols)


def cmd_simulate(args) -> int:
    # a user's engine model (an SDF file is refused there, in one line)
    if str(args.case).lower().endswith((".xml", ".urdf", ".sdf")):
        from reports.cli.own_simulate import cmd_simulate_own
        return cmd_simulate_own(args, _print_table)
    if args.json and args.csv == "-":
        raise OutputError("--json and --csv - both write to standard output; give --csv a "
                          "file name")
    if not getattr(args, "engine", None) and (given := engine_options_given(args)):
        raise opt.UsageError(f"{', '.join(given)} need(s) --engine NAME|all (the engines' "
                             "free runs); without it xval simulate prints the exact "
                             "trajectory only")
    if getattr(args, "engine", None) and args.csv == "-":
        raise OutputError("--engine prints its verdicts to standard output; give --csv a "
                          "file name")
    mech, release = command_case(args.case, args.duration)
    if args.samples and (bad := samples_problem(mech, args.samples)):
        raise opt.UsageError(f"argument --samples: {bad}")  # the file's range (memory)
    n = args.samples or (mech.motion.samples if mech.motion is not None else None)
    bad = free_request_problem(None, n) if getattr(args, "engine", None) else None
    if bad:  # judged runs: every door's range (reports.comparison.free_cases.FREE_SAMPLES)
        raise opt.UsageError(("argument --samples: " if args.samples else
                              f"{args.case}: [motion] samples with --engine: ") + bad[2])
    traj, smp = _exact(args, mech, n)
    if release is not None and not args.json:
        print(release.text)
    if getattr(args, "engine", None):
        if args.csv:
            write_csv(_frame(mech, smp), args.csv, args.stdout)
        return cmd_engines(args, mech, traj, n, release)
    frame = _frame(mech, smp)
    if args.json:
        out = {"case": mech.name, "duration_s": traj.duration, "rtol": traj.rtol,
               "method": traj.method, "evaluations": traj.nfev,
               "switch_check": {"switches_checked": traj.switches_checked,
                                "defect": traj.switch_defect},
               "released": release.as_json() if release else None,
               "events": [{"t_s": e.t, "kind": e.kind, "joint": e.joint,
                           "detail": e.detail} for e in traj.events],
               "samples": {c: frame[c].tolist() for c in frame.columns}}
        print(json.dumps(out, allow_nan=False))
    if args.csv:
        write_csv(frame, args.csv, args.stdout)
    if args.json:
        return 0
    _print_table(mech, smp, traj)
    if args.csv and args.csv != "-":
        print(f"wrote {args.csv}")
    return 0


def _exact(args, mech, n: int):
    """The exact trajectory and its ``n`` samples (None with ``--engine`` and no
    ``--csv``: the engines sample it at their own times), both under one wall clock
    (``--wall-limit``), with their progress on a terminal: ``t`` of the duration while
    it integrates, the samples done of ``n`` while it samples."""
    T = args.duration or (mech.motion.duration if mech.motion else 0.0)
    with engine_progress(f"exact integration: {mech.name}, free motion {T:g} s") as line:
        traj = simulate(mech, args.duration, progress=line.time,
                        wall_limit=getattr(args, "wall_limit", None) or FreeRequest.wall_limit)
        if getattr(args, "engine", None) and not args.csv:
            return traj, None
        traj.clock.sample_progress = line.samples
        return traj, traj.at(np.linspace(0.0, traj.duration, n), forces=False,
                             clock=traj.clock)


def _print_table(mech, smp, traj) -> None:
    rows = np.unique(np.linspace(0, len(smp.t) - 1, min(len(smp.t), 11)).round().astype(int))
    heads = ["t s"] + [f"{j.name} {'deg' if isinstance(j, Revolute) else 'm'}"
                       for j in mech.joints] + ["KE J", "PE J", "balance J"]
    print(f"{mech.name}: free motion, {traj.duration:g} s, DOP853 rtol {traj.rtol:g},")
    print(f"  {traj.nfev} evaluations, {len(traj.segments)} segment(s)")
    print("  ".join(f"{h:>12}" for h in heads))
    for i in rows:
        vals = [smp.t[i]] + [math.degrees(v) if isinstance(j, Revolute) else v
                             for j, v in zip(mech.joints, smp.x[i], strict=True)]
        vals += [smp.kinetic[i], smp.potential[i], smp.energy_residual[i]]
        print("  ".join(f"{v:>12.6g}" for v in vals))
    scale = float(np.max(smp.kinetic) + np.ptp(smp.potential)) or 1.0
    print(f"work-energy balance: max |residual| {np.max(np.abs(smp.energy_residual)):.3g} J "
          f"({np.max(np.abs(smp.energy_residual)) / scale:.3g} of the energy scale)")
    if traj.switches_checked:
        print(f"switch self-check: two coordinates agree past {traj.switches_checked} of "
              f"{len(traj.switches)} switch(es) to {traj.switch_defect:.2g} of scale "
              "(analytic.free_motion.switch_check)")
    if traj.events:
        print(f"events ({len(traj.events)}):")
        for e in traj.events[:50]:
            print(f"  t = {e.t:.12g} s  {e.kind:8s} {e.joint}: {e.detail}")
        if len(traj.events) > 50:
            print(f"  ... {len(traj.events) - 50} more (--json lists all)")
