"""``xval tune CASE|FILE --engine NAME``: the cheapest settings of one engine whose
verdict passes at ``--tolerance`` (:mod:`reports.tune`), verified by a fresh run;
``--out`` writes them as a settings file (``--settings FILE`` of ``compare``,
``simulate``, ``baseline record``), ``--write-model`` a tuned MJCF (MuJoCo).

Exit status: 0 the verified answer passes; 1 no setting passes within the budget or the
engine's limits (the best reached and what limits it are printed), or the verification
run fails; 2 a bad input (one line)."""

from __future__ import annotations

from pathlib import Path

from analytic.motion_spec import MAX_DURATION
from reports.cli import options as opt
from reports.cli.paths import check_outputs
from reports.comparison.free_cases import MIN_DURATION
from sim_models.engines.registry import engine_names


def cmd_tune(args) -> int:
    from reports.tune.measure import TuneCase
    from reports.tune.tune import TuneInputError, check_inputs
    check_outputs([("--out", args.out), ("--write-model", args.write_model),
                   ("--plot", args.plot)], [("the case file", args.case)])
    if args.write_model and args.engine != "mujoco":
        raise opt.UsageError(f"argument --write-model: writes MJCF, MuJoCo's model: it needs "
                             f"--engine mujoco, not {args.engine!r}")
    if args.duration is not None and not args.free:
        raise opt.UsageError("argument --duration: the free run's duration; it needs --free")
    tc = TuneCase(args.case, bool(args.free), args.duration if args.free else None)
    try:
        check_inputs(tc, args.tolerance, args.budget, args.quantity)
    except TuneInputError as e:
        raise opt.UsageError(str(e)) from None
    _check_engine(args.engine, args.free)
    _check_case(tc)
    return _run(args, tc)


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
    if tc.free:
        free_reference(tc.case, tc.duration)
    else:
        prescribed_tree(tc.case)


def _pool(args):
    if args.dask:
        from reports.studies.scheduler import dask_executor
        return dask_executor(args.dask)
    return None


def _run(args, tc) -> int:
    from reports.tune import output
    from reports.tune.tune import tune
    pool = _pool(args)
    try:
        res = tune(tc, args.engine, args.tolerance, args.quantity, args.budget, args.seed,
                   args.workers, pool)
    finally:
        client = getattr(pool, "client_to_close", None)
        if client is not None:
            client.close()
    print(output.full_text(res))
    if args.plot:
        Path(args.plot).write_bytes(output.figure(res))
        print(f"wrote {args.plot}")
    if res.answer is None:
        return 1
    if args.out:
        output.write_settings(res, args.out)
        dur = f" --duration {tc.duration:g}" if tc.free and tc.duration else ""
        print(f"wrote {args.out} (use it: xval {'simulate' if tc.free else 'compare'} "
              f"{tc.case}{dur} --engine {args.engine} --settings {args.out})")
    if args.write_model:
        text, changes = output.model_text(res)
        Path(args.write_model).write_text(text)
        print(f"wrote {args.write_model}: {len(changes)} attributes changed, each named in "
              "a comment")
    return 0 if res.passed else 1


def register(sub) -> None:
    """Add ``tune`` to ``xval``'s subparsers."""
    s = sub.add_parser("tune", help="the cheapest engine settings that pass a tolerance")
    s.add_argument("case", type=opt.case_or_file, help="built-in case name or TOML file")
    s.add_argument("--engine", required=True, choices=engine_names(), metavar="ENGINE",
                   help=f"the engine to tune: {opt.choices_text(engine_names())}")
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
    s.add_argument("--workers", type=opt.workers, default=None,
                   help="local worker processes (default: one per core)")
    s.add_argument("--dask", metavar="SCHEDULER_ADDRESS", type=opt.scheduler_address,
                   help="run the candidates on an existing Dask scheduler")
    s.set_defaults(func=cmd_tune)
