"""``xval baseline record`` and ``xval baseline check`` (see :mod:`reports.regression.baseline`,
:mod:`reports.regression.baseline_record` and :mod:`reports.regression.baseline_check`).

Exit status of ``check``: 0 every recorded run re-ran within its tolerance and within
``--factor`` of its baseline; 1 a drift, a quantity over its tolerance, a quantity,
case, model file or engine gone, a changed model file or a failed run; 2 a baseline
file that cannot be used (one line naming the file, entry and key).  ``record`` exits 1
(and writes nothing) when a run already fails its tolerance.
"""

from __future__ import annotations

import argparse
import math
import os

from analytic.cases import case_names, free_case_names
from analytic.input_display import format_input
from analytic.motion_spec import MAX_DURATION
from reports.cli import options as opt
from reports.cli.examples import help_kw
from reports.comparison.free_cases import (
    FREE_SAMPLES,
    MIN_DURATION,
    RELEASE_DURATION,
    command_case,
)
from reports.comparison.settings_file import apply_settings_file, given_keys, read_settings_file
from reports.regression import baseline as bl
from reports.regression import baseline_check as bc
from reports.regression import baseline_record as br
from reports.regression import baseline_settings as bset
from reports.regression import baseline_store as bs
from reports.regression import ci_formats
from reports.regression import own_model as own
from reports.regression.baseline_free import DEFAULT_SAMPLES, free_mechanism, free_request
from reports.regression.messages import report_lines
from sim_models.engines.registry import engine_names, get_engine, settings_from_options
from sim_models.runs.engine_run import RunRequest
from sim_models.runs.free import free_engine_names, free_session_class


# ============================================================================ record
def _with_file(settings: dict, args, engines, mode: str, classes=None) -> dict:
    """``settings`` with ``--settings FILE`` applied (keys ``--set`` does not give)."""
    if not getattr(args, "settings", None):
        return settings
    return apply_settings_file(settings, read_settings_file(args.settings, mode),
                               given_keys(engines, list(args.set or ()), None, classes))


def cmd_record(args) -> int:
    free = bool(getattr(args, "free", False))
    _free_options(args, free)
    engines = _engines(args.engine, free)
    models = []
    for m in args.models:
        models += list(case_names()) if m == "all" else [m]
    if free:
        classes = {e: free_session_class(e).settings_class for e in engines}
        settings = _with_file(settings_from_options(engines, args.set or (), classes=classes),
                              args, engines, "free", classes)
        req = free_request(args.duration or RELEASE_DURATION, args.samples)
        for m in dict.fromkeys(models):  # one line, status 2, before any run
            if own.is_model_file(m):  # a user's model: released from its own state
                continue
            mech, _ = command_case(m, req["duration"])  # a file without [motion]: refused
            free_mechanism(mech, req)
    else:
        settings = _with_file(settings_from_options(engines, args.set or ()), args, engines,
                              "run")
        req = br.request_dict(args.revolutions, args.samples)
    base = br.record(list(dict.fromkeys(models)), engines, args.out, settings, req,
                     args.tolerance, own_options=_own_options(args, models))
    problems = br.record_problems(base)
    for r in base.runs:
        w = max(r.quantities, key=lambda q: q.error if math.isfinite(q.error) else math.inf,
                default=None)
        of = "of range" if free else "of peak"
        worst = f"worst {w.quantity} {w.error:.3g} {of} at {format_input(w.at, w.at_unit)}" \
            if w else "nothing compared"
        if free and w:
            h = min(q.horizon for q in r.quantities)
            worst += "; trusted horizon " + ("whole run" if math.isinf(h) else f"{h:.4g} s")
        print(f"{r.label}: {len(r.quantities)} quantities, {worst}")
    if problems:
        for p in problems:
            print(f"not recorded: {p}")
        print(f"baseline not written: {len(problems)} quantities fail already "
              "(a baseline records a passing state)")
        return 1
    counts = None
    if not args.replace and os.path.exists(args.out):  # merge: nothing recorded is lost
        try:
            old = bs.load(args.out)
        except bl.BaselineError as e:  # never overwrite what cannot be read back
            raise bl.BaselineError(f"{e}; not overwritten (--replace writes a new "
                                   "file)") from None
        base, counts = br.merge(old, base)
    path = bs.save(base)
    print(f"wrote {len(base.runs)} runs to {path} (schema_version {bl.SCHEMA_VERSION})"
          + (f": {counts['updated']} updated, {counts['kept']} kept, {counts['added']} "
             "added (--replace writes only the runs recorded now)" if counts else
             " (replaced)" if args.replace and os.path.exists(args.out) else ""))
    return 0


def _own_options(args, models: list[str]) -> dict:
    """``--driver`` / ``--keyframe``: they apply to users' model files only."""
    given = {k: getattr(args, k) for k in ("driver", "keyframe") if getattr(args, k)}
    if given and not any(own.is_model_file(m) for m in models):
        raise opt.UsageError(f"--{next(iter(given))} applies to your own MJCF models "
                             "(.xml) only")
    for m in models:  # one line, status 2, before any run
        if own.is_model_file(m):
            for e in args.engine or ["all"]:
                if e not in own.OWN_ENGINES:
                    raise opt.UsageError(f"--engine {e}: {m} is your own MJCF model; it "
                                         "runs in MuJoCo only (--engine mujoco)")
    return given


def _engines(choice: list[str] | None, free: bool = False) -> list[str]:
    if free:
        if not choice or "all" in choice:
            return list(free_engine_names())
        for e in choice:
            free_session_class(e)  # an engine without a free run: one line, status 2
        return list(dict.fromkeys(choice))
    if not choice or "all" in choice:
        return list(engine_names())
    return list(dict.fromkeys(get_engine(e).name for e in choice))


def _free_options(args, free: bool) -> None:
    """The options that belong to one mode only: one line, status 2."""
    if free:
        bad = [k for k, v in (("--revolutions", args.revolutions),
                              ("--tolerance", args.tolerance)) if v is not None]
        if bad:
            raise opt.UsageError(f"{bad[0]} does not apply to --free (a free run is read "
                                 "over --duration at --samples times; its tolerances are "
                                 "the named ones of reports/comparison/free_compare.py)")
        args.samples = _checked_samples(args.samples, _judged_samples)
    elif args.duration is not None:
        raise opt.UsageError("--duration needs --free (a prescribed run is read over "
                             "--revolutions)")
    else:
        args.samples = _checked_samples(args.samples, opt.samples)


def _judged_samples(text: str) -> int:
    """``--samples`` with ``--free``: sample times of a judged free run
    (:data:`reports.comparison.free_cases.FREE_SAMPLES`, every door's range)."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    problem = FREE_SAMPLES.problem(v)
    if problem:
        raise argparse.ArgumentTypeError(problem)
    return v


def _checked_samples(text, typ):
    """``--samples`` through the argparse type of its mode (None: not given)."""
    if text is None:
        return None
    try:
        return typ(text)
    except argparse.ArgumentTypeError as e:
        raise opt.UsageError(f"argument --samples: {e}") from None


# ============================================================================ check
def cmd_check(args) -> int:
    base = bs.load(args.baseline)
    overrides = _check_overrides(args.set, base)
    keep = None
    if args.case or args.engine:
        cases, engines = set(args.case or ()), set(args.engine or ())

        def keep(rec):
            return (not cases or rec.case in cases or rec.model.name in cases) and \
                (not engines or rec.engine in engines)
    checks = bc.check(base, args.factor, select=keep, fail_loose=args.fail_loose,
                      overrides=overrides)
    if keep is not None and not checks:
        raise bl.BaselineError(f"{args.baseline}: no recorded run matches --case/--engine")
    lines = report_lines(base, checks, args.factor)
    if overrides:  # what --set changed, for a reader of the output
        lines.insert(2, "settings changed for this check (--set): " + ", ".join(
            f"{e}.{k}={v}" for e, kv in overrides.items() for k, v in kv.items()))
    print("\n".join(lines))
    if not all(c.passed for c in checks):
        sets = "".join(f" --set {e}.{k}={v}" for e, kv in overrides.items()
                       for k, v in kv.items())  # record what was checked
        print("if the change is intended, record the baseline again: "
              f"{br.record_command(base)}{sets}")
    ci_formats.write_outputs(f"xval baseline check {args.baseline}",
                             ci_formats.from_baseline(checks, base.base_dir), args.junit,
                             args.summary, intro=lines[:2],
                             properties=_override_props(overrides), command="baseline")
    return 0 if all(c.passed for c in checks) else 1


def _check_overrides(pairs, base: bl.Baseline) -> dict:
    """``--set`` of ``baseline check``: per-engine overrides of the recorded settings
    (parsed as ``xval compare --set`` is; :class:`SettingsError` is status 2)."""
    classes = bset.override_classes(base)
    return bset.overrides_for(pairs, [r.engine for r in base.runs if r.engine in classes],
                            classes)


def _override_props(overrides: dict) -> dict:
    return {f"set.{e}.{k}": v for e, kv in overrides.items() for k, v in kv.items()}


# ============================================================================ parser
_tolerance = opt.finite_float(bl.MAX_TOLERANCE, "of peak", lo=bl.MIN_TOLERANCE,
                              why="an error relative to the quantity's peak")


def _model(text: str) -> str:
    return text if text == "all" or text in free_case_names() else opt.case_or_file(text)


def register(sub) -> None:
    """``xval baseline record|check``."""
    p = sub.add_parser("baseline", help="record engine errors, later check them for drift")
    bsub = p.add_subparsers(dest="baseline_command", required=True, metavar="record|check")
    line = "run cases in engines and write a baseline file"
    r = bsub.add_parser("record", help=line, **help_kw("baseline record", line))
    r.add_argument("models", nargs="+", type=_model, metavar="CASE_OR_FILE",
                   help="built-in case names, TOML files, your own MJCF models (.xml, "
                        "with --engine mujoco), or 'all' (every built-in case)")
    engines = [*engine_names(), "all"]
    r.add_argument("--engine", action="append", choices=engines, metavar="ENGINE",
                   help=f"an engine (repeatable; default all): {opt.choices_text(engines)}")
    r.add_argument("--out", required=True, type=opt.output_file, metavar="FILE",
                   help="the baseline file to write (JSON)")
    r.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="an engine setting (ENGINE.KEY=VALUE for one engine only)")
    r.add_argument("--settings", metavar="FILE",
                   help="engine settings from a settings file (xval tune --out; a --free "
                        "file with --free)")
    r.add_argument("--revolutions", type=opt.revolutions, default=None,
                   help=f"1 to {opt.MAX_REVOLUTIONS} (default {RunRequest.revolutions})")
    r.add_argument("--samples", default=None,  # its range depends on --free: _free_options
                   help=f"samples per revolution, 2 to {opt.MAX_SAMPLES} (default "
                        f"{RunRequest.samples}); with --free, sample times over the run, "
                        f"{FREE_SAMPLES.text()} (default {DEFAULT_SAMPLES})")
    r.add_argument("--free", action="store_true",
                   help="record free-motion runs: each case released from the exact "
                        "state (a built-in case without [motion] released at rest under "
                        "gravity, as the report does) and judged over --duration")
    r.add_argument("--duration", type=opt.finite_float(MAX_DURATION, "s", lo=MIN_DURATION),
                   help=f"with --free: seconds, {MIN_DURATION:g} to {MAX_DURATION:g} "
                        f"(default {RELEASE_DURATION:g})")
    r.add_argument("--driver", help="with your own MJCF model: its input joint (default: "
                   "the one actuated joint)")
    r.add_argument("--keyframe", help="with your own MJCF model: its reference "
                   "configuration and, with --free, the state it is released from "
                   "(default: qpos0)")
    r.add_argument("--tolerance", type=_tolerance, default=None,
                   help="relative to peak, recorded per quantity (default 1e-3)")
    r.add_argument("--replace", action="store_true",
                   help="replace an existing file (default: record these runs into it, "
                        "keeping the others)")
    r.set_defaults(func=cmd_record)
    line = "re-run a baseline's runs and fail on drift"
    c = bsub.add_parser("check", help=line, **help_kw("baseline check", line))
    c.add_argument("baseline", metavar="BASELINE_JSON",
                   help="the baseline file that xval baseline record wrote")
    c.add_argument("--factor", type=opt.drift_factor, default=bl.DEFAULT_FACTOR,
                   help=f"largest allowed growth over the baseline (default "
                        f"{bl.DEFAULT_FACTOR:g}; errors below {bl.DRIFT_FLOOR:g} of peak "
                        "count as that floor)")
    c.add_argument("--case", action="append", metavar="CASE",
                   help="check only this case (repeatable)")
    c.add_argument("--engine", action="append", metavar="ENGINE",
                   help="check only this engine (repeatable)")
    c.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="run with this setting instead of the recorded one "
                        "(ENGINE.KEY=VALUE for one engine only; named in the output)")
    c.add_argument("--fail-loose", action="store_true",
                   help="fail when an error shrank by more than the factor (the baseline "
                        "is loose; default: a warning)")
    opt.add_ci_outputs(c)
    c.set_defaults(func=cmd_check)


__all__ = ["cmd_check", "cmd_record", "register", "report_lines"]
