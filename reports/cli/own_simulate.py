"""``xval simulate MODEL.xml [--engine mujoco]``: the user's own MJCF model released in
MuJoCo with nothing added, from its own state (``qpos0`` or ``--keyframe``), judged
against the exact free motion of its imported description (the verdict, trusted horizon,
energy and loop drifts of ``xval simulate --engine``), and diagnosed."""

from __future__ import annotations

import json

import numpy as np

from analytic.free_motion import simulate
from analytic.motion_spec import samples_problem
from reports.cli import options as opt
from reports.cli.own_import import own_closes
from reports.cli.paths import check_outputs
from reports.cli.simulate_engines import print_verdict, write_ci
from reports.comparison.compare import json_safe
from reports.comparison.free_compare import compare_free, reference_samples
from reports.comparison.progress import engine_progress
from reports.regression.own_model import STILL
from sim_models.own import DEFAULT_DURATION, import_model
from sim_models.own.diagnose import model_defects, run_findings
from sim_models.own.mujoco_own_free import run_free_own
from sim_models.own.pybullet_own import run_free_pybullet
from sim_models.runs.free_run import FreeRequest


def cmd_simulate_own(args, print_table) -> int:
    """See the module; ``print_table`` is ``xval simulate``'s table of the exact motion
    (handed over: no import cycle)."""
    urdf = str(args.case).lower().endswith(".urdf")
    if args.engine not in (None, "mujoco", "all") and not (urdf and args.engine == "pybullet"):
        raise opt.UsageError(f"--engine {args.engine}: a user's MJCF model runs in MuJoCo "
                             "only (--engine mujoco; a URDF also --engine pybullet)")
    for flag, value in (("--set", args.set), ("--integrator", args.integrator)):
        if value:
            raise opt.UsageError(f"{flag}: a user's model runs with its own options; change "
                                 "them in the file")
    check_outputs([("--junit", args.junit), ("--summary", args.summary)],
                  [("the model file", args.case)])
    imp = import_model(args.case, args.driver, args.keyframe,
                       args.duration or DEFAULT_DURATION, own_closes(args))
    mech = imp.mechanism
    if args.samples and (bad := samples_problem(mech, args.samples)):
        raise opt.UsageError(f"argument --samples: {bad}")  # a description's range
    n = args.samples or mech.motion.samples
    with engine_progress(f"exact integration: {args.case}, free motion "
                         f"{mech.motion.duration:g} s") as line:
        # under --wall-limit, as a description's run (reports.cli.simulate._exact)
        traj = simulate(mech, progress=line.time,
                        wall_limit=args.wall_limit or FreeRequest.wall_limit)
        traj.clock.sample_progress = line.samples
        smp = traj.at(np.linspace(0.0, traj.duration, n), forces=False, clock=traj.clock)
    if np.ptp(smp.x) <= STILL:  # nothing to judge a run against
        raise opt.UsageError(f"{args.case}: released from {imp.compiled.config} the model "
                             "does not move (at rest, no in-plane gravity, spring or motor); "
                             "give a keyframe with a velocity (--keyframe NAME)")
    if not args.engine:
        print_table(mech, smp, traj)
        return 0
    request = FreeRequest(duration=traj.duration, samples=max(1, n - 1),
                          wall_limit=args.wall_limit or FreeRequest.wall_limit)
    engine = "pybullet" if args.engine == "pybullet" else "mujoco"
    with engine_progress(f"{engine}: {args.case}, free motion {traj.duration:g} s"):
        run = (run_free_pybullet if engine == "pybullet" else run_free_own)(
            imp, request, traj, args.timestep)
    v = compare_free(run, traj, reference_samples(traj, request.times()))
    soft = ("PyBullet's point-to-point constraints" if engine == "pybullet"
            else "the model's solref/solimp")
    lines = [f"diagnosis: {x}" for x in model_defects(imp) + _free_findings(run, soft)]
    if args.json:
        print(json.dumps(json_safe({"file": str(args.case), "case": mech.name,
                                    "duration_s": traj.duration,
                                    "verdicts": [dict(v.as_json(), notes=list(run.notes))],
                                    "diagnosis": lines}), indent=2, allow_nan=False))
    else:
        print(f"model file: {args.case} ({imp.compiled.config}), released from its own state")
        print_verdict(v, run.notes)
        for line in lines:
            print(line)
    write_ci(args, mech, [(run, v)])
    return 0 if v.passed else 1


def _free_findings(run, soft: str) -> list[str]:
    """:func:`sim_models.own.diagnose.run_findings` for a free run (its loop gap)."""
    class _Seen:
        ok, reason, timestep = run.ok, run.reason, run.timestep
        extra = {"active": run.extra.get("active", {})}
        loop_violation = np.asarray(run.loop_gap, float)
    return run_findings(_Seen, soft)
