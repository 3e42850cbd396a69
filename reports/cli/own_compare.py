"""``xval compare MODEL.xml --engine mujoco``: the user's own MJCF model, run by MuJoCo
with its own options and driven along the imported description's prescribed motion
(:func:`sim_models.own.mujoco_own.run_prescribed`), judged against that description's
exact reference with the verdicts, JSON, JUnit and Markdown of ``xval compare``, and
diagnosed (:mod:`sim_models.own.diagnose`)."""

from __future__ import annotations

import json

from reports.cli import options as opt
from reports.cli.own_import import own_closes
from reports.cli.paths import check_outputs
from reports.comparison.compare import compare_run, json_safe
from reports.comparison.progress import engine_progress
from reports.comparison.runs import Verdict
from reports.regression.ci_formats import write_compare_outputs
from sim_models.engines.pybullet.driven import PybulletSettings
from sim_models.own import import_model
from sim_models.own.diagnose import model_defects, run_findings
from sim_models.own.mujoco_own import run_prescribed
from sim_models.own.pybullet_own import run_prescribed_pybullet
from sim_models.runs.engine_run import RunRequest


def cmd_compare_own(args, print_text, verdict_json) -> int:
    """``xval compare MODEL.xml``: see the module.  ``print_text`` and ``verdict_json``
    are ``xval compare``'s table printer and JSON object (handed over: no import cycle)."""
    urdf = str(args.case).lower().endswith(".urdf")
    if args.engine not in ("mujoco", "all") and not (urdf and args.engine == "pybullet"):
        raise opt.UsageError(f"--engine {args.engine}: a user's MJCF model runs in MuJoCo "
                             "only (--engine mujoco; a URDF also --engine pybullet)")
    if args.mode != "run":
        raise opt.UsageError("--mode instantaneous is for the harness's own models; a "
                             "user's model is judged on its run (--mode run)")
    for flag, value in (("--set", args.set), ("--integrator", args.integrator)):
        if value:
            raise opt.UsageError(f"{flag}: a user's model runs with its own options; change "
                                 "them in the file (--timestep alone may override its step, "
                                 "to see whether an error falls with it)")
    check_outputs([("--junit", args.junit), ("--summary", args.summary)],
                  [("the model file", args.case)])
    imp = import_model(args.case, args.driver, args.keyframe, closes=own_closes(args))
    mech = imp.mechanism
    request = RunRequest(args.revolutions, args.samples)
    engine = "pybullet" if args.engine == "pybullet" else "mujoco"
    with engine_progress(f"{engine}: {args.case}, {args.revolutions} revolutions"):
        if engine == "pybullet":
            tree, r = run_prescribed_pybullet(imp, request, PybulletSettings(
                **({"timestep": args.timestep} if args.timestep else {})))
        else:
            tree, r = run_prescribed(imp, request, args.timestep)
    v = Verdict(tree, r, tuple(compare_run(r)))
    soft = ("PyBullet's point-to-point constraints" if engine == "pybullet"
            else "the model's solref/solimp")
    lines = [f"diagnosis: {x}" for x in model_defects(imp) + run_findings(r, soft)]
    if args.json:
        obj = verdict_json(v, "run") | {"file": str(args.case),
                                                      "diagnosis": lines}
        print(json.dumps(json_safe([obj]), indent=2, allow_nan=False))
    else:
        print(f"model file: {args.case} ({imp.compiled.config}), driver "
              f"{mech.driver.joint!r} at {mech.driver.velocity:g} "
              f"{'rad/s' if tree.linkage.driver_is_revolute else 'm/s'}")
        print_text(mech, "run", [v], tree.linkage.driver_is_revolute)
        for line in lines:
            print(line)
    write_compare_outputs(mech, [v], str(args.case), args.junit, args.summary)
    return 0 if v.ok else 1
