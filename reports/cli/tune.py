"""``xval tune CASE|FILE --engine NAME`` or ``xval tune MODEL.xml``: the cheapest settings
of one engine whose verdict passes at ``--tolerance`` (:mod:`reports.tune`), verified by
a fresh run; ``--out`` writes them as a settings file (``--settings FILE`` of
``compare``, ``simulate``, ``baseline record``), ``--write-model`` a tuned MJCF
(MuJoCo: the case's model, or the user's file with only the tuned attributes changed).

Exit status: 0 the verified answer passes; 1 no setting passes within the budget or the
engine's limits (the best reached and what limits it are printed), or the verification
run fails; 2 a bad input (one line)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from analytic.motion_spec import MAX_DURATION
from reports.cli import options as opt
from reports.cli.paths import check_outputs
from reports.comparison.free_cases import MIN_DURATION
from sim_models.engines.registry import engine_names

#: ``xval tune --json``: the keys of its object (:func:`reports.tune.output.json_document`),
#: the command's help epilog.
JSON_KEYS = """\
--json writes one object (non-finite numbers as null; errors are normalised by
each quantity's peak, prescribed, or scale, free; CPU in process CPU seconds):
  case, engine, mode ("prescribed" | "free"), duration_s, tolerance, budget_s,
    seed, unit ("revolution" | "simulated s"), quantity (family, or "all")
  passed        the verification run passes at the tolerance (exit status 0)
  answer        null when no setting passes; else the chosen candidate:
                levels {knob: level}, steps_per_unit, error (worst, the
                search's run), worst_quantity, model_cost_s (per unit),
                changed {setting: [from, to]}, settings (one line)
  verification  fresh run of the answer: passed, error, quantity, run_ok,
                reason, cpu_s (per unit, median of 3), recommended_cpu_s,
                cpu_ratio, cpu_spread, stepping_only_ratio (model costs)
  knob          the knob that sets the error at the answer (one line)
  limit         why nothing passes (null when something does)
  search        runs, cpu_s, wall_s, budget_hit, knobs, stopped_mattering,
                not_tried
  candidates    every run of the search, cheapest model cost first: levels,
                steps_per_unit, error, worst_quantity, passed, run_ok, reason,
                model_cost_s, run_cpu_s, on_front (Pareto front), answer
  files         what was written: settings, model, model_read_back"""


def cmd_tune(args) -> int:
    from reports.tune.measure import TuneCase
    from reports.tune.tune import TuneInputError, check_inputs
    own = _check_own(args)
    for flag, value in (("--out", args.out), ("--write-model", args.write_model),
                        ("--plot", args.plot)):
        if value == "-":
            raise opt.UsageError(f"argument {flag}: '-' (standard output) is not written "
                                 "by xval tune; give a file name (--json prints the "
                                 "result)")
    check_outputs([("--out", args.out), ("--write-model", args.write_model),
                   ("--plot", args.plot)],
                  [("the model file" if own else "the case file", args.case)])
    if args.write_model and args.engine != "mujoco":
        raise opt.UsageError(f"argument --write-model: writes MJCF, MuJoCo's model: it needs "
                             f"--engine mujoco, not {args.engine!r}")
    if args.duration is not None and not args.free:
        raise opt.UsageError("argument --duration: the free run's duration; it needs --free")
    tc = TuneCase(args.case, bool(args.free), args.duration if args.free else None,
                  driver=args.driver, keyframe=args.keyframe)
    try:
        check_inputs(tc, args.tolerance, args.budget, args.quantity)
    except TuneInputError as e:
        raise opt.UsageError(str(e)) from None
    _check_engine(args.engine, args.free)
    _check_case(tc)
    if own and args.write_model:
        _check_writable(tc)
    return _run(args, tc)


def _check_own(args) -> bool:
    """Whether the case is a user's MJCF model; its engine is MuJoCo (the default there),
    a built-in case or TOML file needs ``--engine``; the model options need a model."""
    low = str(args.case).lower()
    if low.endswith((".urdf", ".sdf")):
        raise opt.UsageError(f"{args.case}: xval tune reads a user's MJCF model (.xml); a "
                             "URDF or SDF model is not tuned (xval compare runs a URDF)")
    own = low.endswith(".xml")
    if not own:
        if args.engine is None:
            raise opt.UsageError("argument --engine is required for a built-in case or "
                                 f"TOML file (one of {', '.join(engine_names())})")
        for flag, value in (("--driver", args.driver), ("--keyframe", args.keyframe)):
            if value is not None:
                raise opt.UsageError(f"argument {flag}: an option of a user's MJCF model "
                                     f"(.xml), not of {args.case!r}")
        return False
    if args.engine not in (None, "mujoco"):
        raise opt.UsageError(f"argument --engine: {args.engine!r}: a user's MJCF model "
                             f"{args.case} runs in MuJoCo only (--engine mujoco)")
    args.engine = "mujoco"
    if args.out:
        raise opt.UsageError("argument --out: a user's model carries its settings in its "
                             "file: write them with --write-model TUNED.xml")
    return True


def _check_engine(engine: str, free: bool) -> None:
    """A free run needs the engine's free session (one line otherwise)."""
    if free:
        from sim_models.runs.free import free_engine_names
        if engine not in free_engine_names():
            raise opt.UsageError(f"argument --engine: {engine!r} has no free-motion runs; "
                                 f"engines: {', '.join(free_engine_names())}")
    from sim_models.engines.registry import get_engine
    get_engine(engine)  # a missing optional library: one line


def _check_case(tc) -> None:
    """Load the case as the search will (a bad file or a case that cannot be released
    is one line here, not a failed run in every worker)."""
    from reports.tune.measure import free_reference, prescribed_tree
    if tc.own:
        from reports.tune.own import check_moves, check_runs, model_of
        model_of(tc)  # the model as xval compare reads it (a refusal: one line)
        check_runs(tc)
        if tc.free:
            check_moves(tc)
        return
    if tc.free:
        free_reference(tc.case, tc.duration)
    else:
        prescribed_tree(tc.case)


def _check_writable(tc) -> None:
    """The user's file is one --write-model can edit (UTF-8 MJCF text with a <mujoco>
    root; MuJoCo also reads a URDF named .xml): one line before the search, not after."""
    from reports.tune.model import ModelWriteError
    from reports.tune.own import tuned_text
    try:
        tuned_text(tc, {}, {}, "")
    except ModelWriteError as e:
        raise opt.UsageError(f"argument --write-model: {e}") from None


def _pool(args):
    if args.dask:
        from reports.studies.scheduler import dask_executor
        return dask_executor(args.dask)
    return None


def _run(args, tc) -> int:
    from reports.tune.tune import tune
    pool = _pool(args)
    try:
        res = tune(tc, args.engine, args.tolerance, args.quantity, args.budget, args.seed,
                   args.workers, pool)
    finally:
        client = getattr(pool, "client_to_close", None)
        if client is not None:
            client.close()
    lines, files, code = _write(args, tc, res)
    from reports.tune import output
    if args.json:
        print(json.dumps(output.json_document(res, files), indent=2, allow_nan=False))
    else:
        print("\n".join([output.full_text(res), *lines]))
    return code


def _write(args, tc, res) -> tuple[list[str], dict, int]:
    """Write what was asked (--plot, --out, --write-model): the lines saying so, the
    files written (the JSON's ``files``) and the exit status."""
    from reports.tune import output
    lines: list[str] = []
    files: dict = {}
    if args.plot:
        Path(args.plot).write_bytes(output.figure(res))
        lines.append(f"wrote {args.plot}")
        files["plot"] = args.plot
    if res.answer is None:
        return lines, files, 1
    code = 0 if res.passed else 1
    if args.out:
        output.write_settings(res, args.out)
        dur = f" --duration {tc.duration:g}" if tc.free and tc.duration else ""
        lines.append(f"wrote {args.out} (use it: xval {'simulate' if tc.free else 'compare'} "
                     f"{tc.case}{dur} --engine {args.engine} --settings {args.out})")
        files["settings"] = args.out
    if args.write_model:
        text, changes = output.model_text(res)
        Path(args.write_model).write_text(text)
        lines.append(f"wrote {args.write_model}: {len(changes)} attributes changed, each "
                     "named in a comment")
        files["model"] = args.write_model
        if tc.own:
            line, ok = _read_back(args, tc, res)
            lines.append(line)
            files["model_read_back"] = ok
            code = code if ok else 1
    return lines, files, code


def _read_back(args, tc, res) -> tuple[str, bool]:
    """Whether the written file read by MuJoCo carries the verified settings, and a line
    saying so (naming what differs where it does not, e.g. set in an included file)."""
    from reports.tune.own import read_back
    diff = read_back(args.write_model, tc, {k: v for k, (_old, v) in res.changed.items()})
    if diff:
        return (f"{args.write_model}: MuJoCo reads other settings than the verified run's "
                f"(file / run): {'; '.join(diff)}"), False
    mode = f"simulate {args.write_model} --engine mujoco" if tc.free else \
        f"compare {args.write_model} --engine mujoco"
    return (f"read back by MuJoCo: the file carries the verified settings (use it: xval "
            f"{mode})"), True


def register(sub) -> None:
    """Add ``tune`` to ``xval``'s subparsers."""
    s = sub.add_parser("tune", help="the cheapest engine settings that pass a tolerance",
                       epilog=JSON_KEYS,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    s.add_argument("case", type=opt.case_or_file,
                   help="built-in case name, TOML file, or your own MJCF model (.xml, read "
                        "as xval compare reads it)")
    s.add_argument("--engine", choices=engine_names(), default=None, metavar="ENGINE",
                   help="the engine tuned (required for a case or TOML file; a model "
                        f"file: mujoco): {opt.choices_text(engine_names())}")
    s.add_argument("--driver", help="with a model file: its input joint (default: the one "
                   "actuated joint)")
    s.add_argument("--keyframe", help="with a model file: the reference configuration "
                   "(default: qpos0)")
    s.add_argument("--tolerance", type=opt.finite_number, default=1e-3,
                   help="largest normalised error (of peak) on every judged quantity "
                        "(default 1e-3)")
    s.add_argument("--quantity", metavar="FAMILY", default=None,
                   help="judge only this family: acceleration, force (prescribed); joint "
                        "angle, joint rate, angle, angular rate, angular acceleration, "
                        "reaction, energy, loop (free); default all")
    s.add_argument("--free", action="store_true",
                   help="tune the free motion (released under gravity, or the file's "
                        "[motion]) instead of the prescribed run")
    s.add_argument("--duration", type=opt.finite_float(MAX_DURATION, "s", lo=MIN_DURATION),
                   default=None,
                   help="free run duration, s (default: the release rule's 2 s, or the "
                        "file's)")
    s.add_argument("--budget", type=opt.finite_number, default=60.0,
                   help="CPU seconds the search's runs may take (default 60)")
    s.add_argument("--seed", type=opt.int_range(0, 2 ** 31 - 1), default=0,
                   help="orders the search's waves (same seed and budget: same answer)")
    s.add_argument("--out", type=opt.output_file, metavar="SETTINGS_JSON",
                   help="write the answer as a settings file")
    s.add_argument("--write-model", type=opt.output_file, metavar="TUNED_XML",
                   help="write a tuned copy of the MJCF model (MuJoCo)")
    s.add_argument("--plot", type=opt.output_file, metavar="PNG",
                   help="write the cost/error figure of the search")
    s.add_argument("--json", action="store_true",
                   help="print the result as JSON (its keys: below)")
    s.add_argument("--workers", type=opt.workers, default=None,
                   help="local worker processes (default: one per core)")
    s.add_argument("--dask", metavar="SCHEDULER_ADDRESS", type=opt.scheduler_address,
                   help="run the candidates on an existing Dask scheduler")
    s.set_defaults(func=cmd_tune)
