"""Engine and report commands of ``xval`` (``models``, ``compare``, ``report``).

Kept apart from :mod:`reports.cli` so that ``xval solve`` never imports an engine.
"""

from __future__ import annotations

import json
import sys
from dataclasses import asdict


def cmd_models(args) -> int:
    from sim_models.models import MODELS_DIR, write_models
    paths = write_models(args.out or MODELS_DIR)
    print(f"wrote {len(paths)} files to {args.out or MODELS_DIR}")
    return 0


def engine_settings(engine: str, timestep: float | None = None):
    """The recommended (default) settings of an engine, optionally with another step."""
    from dataclasses import replace

    from sim_models.mjcf import MujocoSettings
    if engine == "mujoco":
        s = MujocoSettings()
    elif engine == "pybullet":
        from sim_models.pybullet_sim import PybulletSettings
        s = PybulletSettings()
    else:
        from analytic import LinkageError
        raise LinkageError(f"unknown engine {engine!r}; use mujoco, pybullet or all")
    return replace(s, timestep=timestep) if timestep else s


def run_comparison(mech, engine: str, mode: str = "run", revolutions: int = 2,
                   samples: int = 36, timestep: float | None = None):
    """Run one engine on a mechanism and compare: ``(run, comparisons)``."""
    from analytic import Linkage
    from analytic.sweep import input_values
    from reports.compare import compare_run
    from sim_models.engines import mujoco_instantaneous, run
    settings = engine_settings(engine, timestep)
    if mode == "instantaneous":
        if engine != "mujoco":
            from analytic import LinkageError
            raise LinkageError("the instantaneous mode exists for MuJoCo only (mj_forward at "
                               "the analytic state); PyBullet has no forward-dynamics call")
        vals = input_values(Linkage(mech), samples)[0]
        r = mujoco_instantaneous(mech, settings, vals)
    else:
        r = run(mech, engine, settings, revolutions=revolutions, samples=samples)
    return r, compare_run(r, mech)


def cmd_compare(args) -> int:
    from analytic import load_case
    from reports.compare import comparison_frame, verdict
    mech = load_case(args.case)
    engines = ["mujoco", "pybullet"] if args.engine == "all" else [args.engine]
    out, all_ok = [], True
    for eng in engines:
        r, comps = run_comparison(mech, eng, args.mode, args.revolutions, args.samples,
                                  args.timestep)
        ok = r.ok and verdict(comps)
        all_ok &= ok
        out.append((r, comps, ok))
    if args.json:
        print(json.dumps([{
            "case": mech.name, "engine": r.engine, "mode": args.mode, "settings": r.settings,
            "run_ok": r.ok, "reason": r.reason, "verdict": "pass" if ok else "fail",
            "wall_seconds_per_revolution": r.wall_per_rev, "timestep": r.timestep,
            "notes": list(r.notes),
            "comparisons": [asdict(c) for c in comps]} for r, comps, ok in out], indent=2))
    else:
        import pandas as pd
        with pd.option_context("display.width", 160, "display.max_columns", 20):
            for r, comps, ok in out:
                print(f"== {mech.name} / {r.engine} ({args.mode}) : "
                      f"{'PASS' if ok else 'FAIL'}")
                print(f"settings: {r.settings}")
                if not r.ok:
                    print(f"run failed: {r.reason}")
                df = comparison_frame(r, comps)[["quantity", "max_abs", "peak", "normalised",
                                                 "at", "tolerance", "passed"]]
                print(df.to_string(index=False, float_format=lambda v: f"{v:.3g}"))
                if any(c.quantity.endswith("[engine]") for c in comps):
                    print("rows marked [engine] are the engine's own readings, reported but "
                          "not judged: PyBullet's jointReactionForces are known wrong for "
                          "links with a moving parent or children (README, Engines)")
                for n in r.notes:
                    print("note:", n)
                print(f"wall time {r.wall_per_rev * 1e3:.1f} ms per revolution, "
                      f"dt {r.timestep:.3g} s")
    return 0 if all_ok else 1


def cmd_report(args) -> int:
    from reports.report import main as report_main
    return report_main(args)


def register(sub) -> None:
    s = sub.add_parser("models", help="write the MJCF/URDF files of every built-in case")
    s.add_argument("--out", help="directory (default sim_models/models)")
    s.set_defaults(func=cmd_models)
    s = sub.add_parser("compare", help="run engines and compare with the analytic solution")
    s.add_argument("case", help="built-in case name or TOML file")
    s.add_argument("--engine", choices=["mujoco", "pybullet", "all"], default="all")
    s.add_argument("--mode", choices=["run", "instantaneous"], default="run",
                   help="run: step N revolutions at constant input speed; instantaneous: "
                        "MuJoCo mj_forward at the analytic state")
    s.add_argument("--revolutions", type=int, default=2)
    s.add_argument("--samples", type=int, default=36)
    s.add_argument("--timestep", type=float, help="override the recommended step, s")
    s.add_argument("--json", action="store_true")
    s.set_defaults(func=cmd_compare)
    try:
        import reports.report as _  # noqa: F401
    except ImportError:
        return
    s = sub.add_parser("report", help="the validation report (HTML, Markdown, CSV)")
    s.add_argument("--out", help="output directory (default reports/out/<timestamp>)")
    s.add_argument("--quick", action="store_true", help="the quick variant (< 90 s)")
    s.add_argument("--cases", nargs="+", help="only these cases")
    s.add_argument("--workers", type=int, help="process-pool size (default: cores)")
    s.add_argument("--dask", metavar="SCHEDULER_ADDRESS",
                   help="run the study tasks on an existing Dask distributed scheduler")
    s.set_defaults(func=cmd_report)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(1)
