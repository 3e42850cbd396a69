"""``xval compare CASE|FILE``: engines run on a linkage and compared with the analytic
solution (:func:`reports.comparison.runs.run_verdict`), as tables, JSON, JUnit XML or
a Markdown summary."""

from __future__ import annotations

import json
import shutil
import sys
import textwrap

import pandas as pd

from analytic import load_case
from analytic.input_display import format_input, input_number
from reports.cli import options as opt
from reports.cli.own_options import add_own_options
from reports.comparison import runs as verdict_runs
from reports.comparison.compare import FAIL, PASS, json_safe, step_note, verdict_word
from reports.comparison.progress import engine_progress
from reports.comparison.quantities import is_engine_reading
from reports.comparison.runs import engine_list, settings_for
from reports.comparison.settings_file import apply_settings_file, given_keys, read_settings_file
from reports.regression.ci_formats import write_compare_outputs  # --junit, --summary
from sim_models import compile_linkage
from sim_models.engines.registry import engine_names, skipped_engines
from sim_models.runs.engine_run import RunRequest


def cmd_compare(args) -> int:
    """``xval compare``: verdict runs of the chosen engines on one compiled linkage."""
    # a user's engine model (an SDF file is refused there, in one line)
    if str(args.case).lower().endswith((".xml", ".urdf", ".sdf")):
        from reports.cli.own_compare import cmd_compare_own
        return cmd_compare_own(args, _print_compare_text, _verdict_json)
    mech = load_case(args.case)
    engines = engine_list(args.engine, args.mode)
    flags = {"--timestep": ("timestep", args.timestep),
             "--integrator": ("integrator", args.integrator)}
    settings = settings_for(engines, list(args.set or ()), flags)
    if args.settings:  # a settings file (xval tune --out): the options may not repeat it
        settings = apply_settings_file(
            settings, read_settings_file(args.settings, "run"),
            given_keys(engines, list(args.set or ()), flags))
    if args.engine == "all":  # after every input is checked: bad input stays one line
        note_skipped_engines()
    tree = compile_linkage(mech)  # the analytic solution, once, for every engine
    request = RunRequest(args.revolutions, args.samples, mode=args.mode)
    out = verdict_runs.run_verdicts(
        tree, engines, settings, request,
        lambda eng: engine_progress(f"{eng}: {mech.name}, {args.revolutions} revolutions"))
    all_ok = all(v.ok for v in out)
    if args.json:
        print(json.dumps(json_safe([_verdict_json(v, args.mode) for v in out]), indent=2,
                         allow_nan=False))
    else:
        _print_compare_text(mech, args.mode, out, tree.linkage.driver_is_revolute)
    write_compare_outputs(mech, out, str(args.case or ""), args.junit, args.summary)
    return 0 if all_ok else 1


def _verdict_json(v, mode: str) -> dict:
    """One engine's object in ``xval compare --json`` (a :class:`reports.comparison.runs.
    Verdict`)."""
    r = v.run
    word = verdict_word(list(v.comparisons), r.ok)  # pass, precision limit (float32), FAIL
    return {
        "case": r.case, "engine": r.engine, "mode": mode,
        "settings": r.settings_text, "settings_fields": r.settings.as_dict(),
        "sampled_by": "time" if r.by_time else "input",
        "run_ok": r.ok, "reason": r.reason,
        "verdict": "fail" if not v.ok else (PASS if word == PASS else word),
        "precision": r.settings.arithmetic.name,
        "near_event": v.near_event, "wall_seconds_per_revolution": r.wall_per_rev,
        "timestep": r.timestep, "notes": list(r.notes),
        "step_note": None if v.ok else step_note(r, v.tree.linkage.driver_is_revolute),
        "comparisons": [c.as_json() for c in v.comparisons]}


def _table(comps) -> list[list[str]]:
    """The compare table's cells: numbers to 3 figures; a quantity the run did not reach
    (a failed run's samples after it stopped) is "not measured", not the infinity that
    stands for it."""
    rows = []
    for c in comps:
        err = [f"{c.max_abs:.3g}", f"{c.normalised:.3g}"] if c.measured else \
            ["not measured"] * 2
        # the engines' own readings are reported, not judged (reports.comparison.compare.verdict)
        judged = "not judged" if is_engine_reading(c.quantity) else c.status
        rows.append([c.quantity, err[0], f"{c.peak:.3g}", err[1], input_number(c.at),
                     f"{c.tolerance:.3g}", judged])
    return rows


def _print_compare_text(mech, mode: str, out, revolute: bool) -> None:
    """``xval compare``'s table per engine; prose lines wrapped to the terminal's width
    (settings strings run to ~190 characters)."""


    width = max(60, min(shutil.get_terminal_size((100, 24)).columns, 120))

    def say(text: str) -> None:
        print(textwrap.fill(text, width, subsequent_indent="  ", break_on_hyphens=False))

    with pd.option_context("display.width", width, "display.max_columns", 20):
        for v in out:
            r, comps, ok, near = v.run, v.comparisons, v.ok, v.near_event
            word = verdict_word(list(comps), r.ok)
            print(f"== {mech.name} / {r.engine} ({mode}) : "
                  f"{word.upper() if word in (PASS, FAIL) else word}")
            say(f"settings: {r.settings_text}")
            if r.by_time:
                say(f"sampled at {r.n} equal times over {r.extra.get('t_end', 0):.4g} s "
                    "(the input is not a monotonic turn); 'at' is the input there")
            if not r.ok:
                say(f"run failed: {r.reason}")
            if near:
                say(f"near an event: {near}")
            if not ok and r.ok and (sn := step_note(r, revolute)):
                say(f"step: {sn}")
            df = pd.DataFrame(_table(comps), columns=["quantity", "max_abs", "peak",
                                                      "normalised", "at", "tolerance",
                                                      "passed"])
            print(df.to_string(index=False))
            lim = [c for c in comps if c.limited]
            if lim:
                w = max(lim, key=lambda c: c.normalised)
                say(f"{w.status}: {len(lim)} quantities over the tolerance but within the "
                    f"engine's {w.precision} error floor ({w.quantity}: "
                    f"{w.normalised:.3g} of peak, floor {w.floor:.2g} from the steps taken "
                    "and the loop condition number there, sim_models/runs/precision.py): a "
                    "precision limit of the engine, not a failure (status 0)")
            if any(not c.measured for c in comps):
                first = min(c.at for c in comps if not c.measured)
                say(f"not measured: the engine has no values from the sample at "
                    f"{format_input(first, 'deg' if revolute else 'm')} on (the run stopped "
                    "there); the verdict is a failure")
            if any(is_engine_reading(c.quantity) for c in comps):
                say("rows marked [engine] are the engine's own readings, reported but not "
                    "judged: PyBullet's jointReactionForces are known wrong for links with "
                    "a moving parent or children (docs/explanation/engine-findings.md)")
            for n in r.notes:
                say(f"note: {n}")
            print(f"wall time {r.wall_per_rev * 1e3:.1f} ms per revolution, "
                  f"dt {r.timestep:.3g} s")


def note_skipped_engines() -> None:
    """One stderr line per registered engine whose optional library is missing (what
    ``--engine all`` and the report leave out, and how to install it)."""
    for why in skipped_engines().values():
        print(f"xval: note: {why}; skipped", file=sys.stderr)


def register(sub) -> None:
    """Add ``compare`` to ``xval``'s subparsers."""
    s = sub.add_parser("compare", help="run engines and compare with the analytic solution")
    s.add_argument("case", help="built-in case name, TOML file, or your own MJCF or URDF "
                   "model (.xml, .urdf, read as xval import reads it)")
    engines = [*engine_names(), "all"]
    s.add_argument("--engine", choices=engines, default="all", metavar="ENGINE",
                   help=f"the engine to run: {opt.choices_text(engines)} (default all)")
    add_own_options(s)
    s.add_argument("--mode", choices=["run", "instantaneous"], default="run",
                   help="run: step through the driver's motion; instantaneous: the "
                        "engine's forward dynamics at the analytic state (MuJoCo)")
    s.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="an engine setting (repeatable; ENGINE.KEY=VALUE for one engine "
                        "only), e.g. --set integrator=Euler --set pybullet.erp=0.2")
    s.add_argument("--integrator", type=opt.word_choice(opt.MUJOCO_INTEGRATORS),
                   metavar="{" + ",".join(opt.MUJOCO_INTEGRATORS) + "}",
                   help="MuJoCo's integrator (same as --set mujoco.integrator=...)")
    s.add_argument("--settings", metavar="FILE",
                   help="engine settings from a settings file (xval tune --out); the "
                        "options may not set the same keys again")
    s.add_argument("--revolutions", type=opt.revolutions, default=RunRequest.revolutions,
                   help=f"1 to {opt.MAX_REVOLUTIONS}")
    s.add_argument("--samples", type=opt.samples, default=RunRequest.samples,
                   help=f"samples per revolution, 2 to {opt.MAX_SAMPLES}")
    s.add_argument("--timestep", type=opt.timestep,
                   help=f"override the recommended step, {opt.MIN_TIMESTEP:g} to "
                        f"{opt.MAX_TIMESTEP:g} s")
    s.add_argument("--json", action="store_true", help="print one JSON object (SI)")
    opt.add_ci_outputs(s)
    s.set_defaults(func=cmd_compare)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(1)
