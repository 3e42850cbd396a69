"""``xval simulate CASE --engine NAME|all``: the engines released from the exact state,
each judged against the exact trajectory (:mod:`reports.comparison.free_compare`).

Options (added to ``xval simulate`` by :func:`add_options`): ``--engine``, ``--set
KEY=VALUE`` (``ENGINE.KEY=VALUE`` for one engine; the ranges of
:mod:`sim_models.engines.ranges`, through :func:`sim_models.engines.registry.settings_from_options`
with the free-motion settings classes), ``--integrator`` (MuJoCo's), ``--timestep``,
``--json``, ``--junit``, ``--summary``.  Exit status 1 when any verdict fails, 2 on bad
input (one line).
"""

from __future__ import annotations

import json
import math
import shutil
import textwrap
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from analytic import LinkageError
from reports.cli import options as opt
from reports.comparison.compare import json_safe
from reports.comparison.free_compare import compare_free, reference_samples
from reports.comparison.free_limits import verdict_of_free
from reports.comparison.progress import engine_progress
from reports.comparison.runs import crash_text
from reports.comparison.settings_file import apply_settings_file, given_keys, read_settings_file
from reports.regression.baseline import versions
from reports.regression.ci_formats import CiCase, write_outputs
from sim_models.engines.ranges import WALL_LIMIT
from sim_models.engines.registry import settings_from_options, split_overrides
from sim_models.runs.free import free_engine_names, free_session_class, run_free
from sim_models.runs.free_run import FreeRequest

#: MuJoCo's integrators (``--integrator``: the same as ``--set mujoco.integrator=...``).
INTEGRATORS = opt.MUJOCO_INTEGRATORS


def add_options(s) -> None:
    """The engine options of ``xval simulate``."""
    engines = [*free_engine_names(), "all"]
    s.add_argument("--engine", choices=engines, metavar="ENGINE",
                   help="release the linkage in this engine (or all) and judge its run "
                        "against the exact trajectory; exit status 1 on a failed verdict: "
                        f"{opt.choices_text(engines)}")
    s.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="an engine setting (repeatable; ENGINE.KEY=VALUE for one engine "
                        "only), e.g. --set mujoco.solref=-1e4,-200 (needs --engine)")
    s.add_argument("--integrator", type=opt.word_choice(INTEGRATORS),
                   metavar="{" + ",".join(INTEGRATORS) + "}",
                   help="MuJoCo's integrator (same as --set mujoco.integrator=...; needs "
                        "--engine)")
    s.add_argument("--timestep", type=opt.timestep,
                   help=f"every engine's largest step, {opt.MIN_TIMESTEP:g} to "
                        f"{opt.MAX_TIMESTEP:g} s (needs --engine)")
    s.add_argument("--settings", metavar="FILE",
                   help="engine settings from a free-motion settings file (xval tune --free "
                        "--out; needs --engine)")
    s.add_argument("--wall-limit", type=opt.sim_range("WALL_LIMIT"), metavar="SECONDS",
                   help="end the exact integration, its sampling and each engine's run "
                        f"after this much wall-clock time, {WALL_LIMIT.text()} (default "
                        f"{FreeRequest.wall_limit:g} s; an engine run that reaches it ends "
                        "as a result that says so, the exact side with one line, "
                        "status 2)")
    opt.add_ci_outputs(s)


def engine_options_given(args) -> list[str]:
    """The engine-only options given without ``--engine`` (for the one-line refusal)."""
    named = {"--set": args.set, "--integrator": args.integrator, "--timestep": args.timestep,
             "--settings": args.settings, "--junit": args.junit, "--summary": args.summary}
    return [k for k, v in named.items() if v]


def free_settings_for(engines, args) -> dict:
    """Each engine's free-motion settings: recommended, then the flags, then ``--set``,
    then ``--settings FILE`` (keys the options do not give)."""
    flags = {"--timestep": ("timestep", args.timestep),
             "--integrator": ("integrator", args.integrator)}
    classes = {e: free_session_class(e).settings_class for e in engines}
    out = settings_from_options(engines, list(args.set or ()), flags, classes=classes)
    if getattr(args, "settings", None):
        out = apply_settings_file(out, read_settings_file(args.settings, "free"),
                                  given_keys(engines, list(args.set or ()), flags, classes))
    return out


def step_set_by_user(engines, args) -> dict[str, bool]:
    """Per engine: whether ``--timestep`` or a ``--set`` item gives its step (then that
    step wins over the one chosen from the motion, :mod:`sim_models.runs.free_step`)."""
    per = split_overrides(list(args.set or ()), engines,
                          {e: free_session_class(e).settings_class for e in engines})
    return {e: args.timestep is not None or "timestep" in per.get(e, {}) for e in engines}


@dataclass(frozen=True)
class EngineCrash:
    """An engine whose free run raised (a bug of the harness or the engine, never the
    input's fault: bad input is refused before any engine runs): a failed verdict whose
    ``cause`` is the exception in one line."""

    case: str
    engine: str
    duration: float
    cause: str
    passed: bool = False

    def as_json(self) -> dict:
        return {"case": self.case, "engine": self.engine, "duration_s": self.duration,
                "passed": False, "verdict": "FAIL", "note": "",
                "run_ok": False, "reason": f"engine crashed: {self.cause}"}


def run_engines(mech, traj, args, samples: int):
    """Every chosen engine's free run, judged: ``(run, FreeVerdict)`` per engine, or
    ``(None, EngineCrash)`` for one that raised.  Of several engines, one that refuses
    the model is an :class:`EngineCrash` too (saying so); the only engine's refusal
    stays the one-line error of status 2."""
    engines = list(free_engine_names()) if args.engine == "all" else [args.engine]
    settings = free_settings_for(engines, args)
    request = FreeRequest(duration=traj.duration, samples=max(1, samples - 1),
                          wall_limit=args.wall_limit or FreeRequest.wall_limit)
    ref = reference_samples(traj, request.times())
    set_step = step_set_by_user(engines, args)
    out = []
    for eng in engines:
        with engine_progress(f"{eng}: {mech.name}, free motion {traj.duration:g} s"):
            try:
                run = run_free(mech, eng, settings[eng], request, traj,
                               step_from_motion=not set_step[eng])
            except LinkageError as e:
                if len(engines) == 1:
                    raise
                out.append((None, EngineCrash(mech.name, eng, traj.duration,
                                              f"refused: {e}")))
                continue
            except Exception as e:  # noqa: BLE001 - one engine's crash is its failed verdict
                out.append((None, EngineCrash(mech.name, eng, traj.duration, crash_text(e))))
                continue
        out.append((run, compare_free(run, traj, ref)))
    return out


def label_of(v) -> tuple[str, str]:
    """``(word, note)``: ``pass``, ``known limit`` or ``FAIL``, the report's rule
    (:func:`reports.comparison.free_limits.verdict_of_free`); a crash is a ``FAIL``."""
    return ("FAIL", "") if isinstance(v, EngineCrash) else verdict_of_free(v)


def exit_code(verdicts) -> int:
    """1 when any verdict is a ``FAIL`` (a listed known engine limit is not: the report's
    exit rule, :func:`reports.cli.report.exit_status`), else 0."""
    return 1 if any(label_of(v)[0] == "FAIL" for v in verdicts) else 0


def summary_line(case: str, verdicts) -> str:
    """The line that closes ``xval simulate --engine``: passes, known limits and
    failures by engine, and the exit status they make."""
    words = [(v.engine, label_of(v)[0]) for v in verdicts]
    ok = [e for e, w in words if w == "pass"]
    lim = [e for e, w in words if w == "known limit"]
    bad = [e for e, w in words if w == "FAIL"]
    parts = [f"{len(ok)} of {len(words)} engines pass"]
    if lim:
        parts.append(f"{len(lim)} known engine limit ({', '.join(lim)}; not counted)")
    if bad:
        parts.append(f"{len(bad)} failed ({', '.join(bad)})")
    return f"simulate {case}: {', '.join(parts)}; exit status {exit_code(verdicts)}"


def cmd_engines(args, mech, traj, samples: int, release=None) -> int:
    """The engine part of ``xval simulate``: run, judge, print; 0 pass (or a listed
    known engine limit), 1 fail.
    ``release``: the :class:`reports.comparison.free_cases.Release` of a built-in case without
    ``[motion]`` (in the JSON as ``released``; the text output says it before)."""
    results = run_engines(mech, traj, args, samples)
    verdicts = [v for _, v in results]
    if args.json:
        print(json.dumps(json_safe({
            "case": mech.name, "duration_s": traj.duration,
            "released": release.as_json() if release else None, "reference": {
                "method": traj.method, "rtol": traj.rtol,
                "events": [{"t_s": e.t, "kind": e.kind, "joint": e.joint,
                            "detail": e.detail} for e in traj.events]},
            "verdicts": [_verdict_json(r, v) for r, v in results],
            "exit_status": exit_code(verdicts)}),
            indent=2, allow_nan=False))
    else:
        for r, v in results:
            print_verdict(v, r.notes if r is not None else ())
        print(summary_line(mech.name, verdicts))
    write_ci(args, mech, results)
    return exit_code(verdicts)


def _verdict_json(run, v) -> dict:
    if run is None:
        return v.as_json()
    word, note = label_of(v)
    return dict(v.as_json(), notes=list(run.notes), verdict=word, note=note)


def _say(text: str) -> None:
    width = max(60, min(shutil.get_terminal_size((100, 24)).columns, 120))
    print(textwrap.fill(text, width, subsequent_indent="  ", break_on_hyphens=False))


def horizon_text(h: float, duration: float) -> str:
    """The trusted horizon in words."""
    return f"whole run ({duration:g} s)" if math.isinf(h) else f"{h:.4g} s"


def print_verdict(v, notes=()) -> None:
    """One engine's verdict as text: heading, the drifts, IFToMM, the table."""
    word, note = label_of(v)
    print(f"== {v.case} / {v.engine} (free motion, {v.duration:g} s): "
          f"{word.upper() if word != 'FAIL' else word}")
    if isinstance(v, EngineCrash):
        _say(f"engine crashed: {v.cause}")
        return
    if word == "known limit":
        _say(f"known engine limit (reports/comparison/free_limits.py; not counted in the "
             f"exit status): {note}")
    elif note:
        _say(f"note: {note}")
    _say(f"settings: {v.settings}")
    if not v.run_ok:
        _say(f"run ended at t = {v.t_fail:.4g} s: {v.reason}; the quantities are not "
             "measured from there on")
    w, lost = v.worst, v.lost_by
    by = f" ({lost.quantity} exceeds its tolerance first)" if lost else ""
    _say(f"trusted horizon: {horizon_text(v.horizon, v.duration)}{by}; worst: {w.quantity}, "
         f"{w.normalised:.3g} of its {w.normalisation} (tolerance {w.tolerance:g})")
    loop = (f"max {v.loop.normalised:.3g} of the mechanism size {v.loop.scale:.4g} m"
            if v.has_loop else "none, the mechanism has no loop")
    _say(f"energy drift: max {v.energy.normalised:.3g} of the {v.energy.normalisation} "
         f"{v.energy.scale:.4g} J, at t = {v.energy.at:.4g} s; loop-closure drift: {loop}")
    if v.iftomm:
        a = v.iftomm
        _say(f"IFToMM accuracy: {a.body}.{a.point} position error max {a.max_error:.3g} m at "
             f"t = {a.at:.4g} s: class {a.level} (levels 1e-1 and 1e-3 m)")
    if v.near_event:
        _say(f"near an event: {v.near_event}")
    if v.step_note:
        _say(f"step: {v.step_note}")
    # 80 columns: the unit beside its value, the run's length said once above
    rows = [[c.quantity, f"{c.max_abs:.3g} {c.unit}" if math.isfinite(c.max_abs) else
             "not measured", f"{c.scale:.3g}",
             f"{c.normalised:.3g}" if c.measured else "not measured", f"{c.at:.4g}",
             ("whole run" if math.isinf(c.horizon) else f"{c.horizon:.4g} s") if c.measured
             else f"stopped {c.measured_until:.4g} s", f"{c.tolerance:g}",
             "pass" if c.passed else "FAIL"]
            for c in v.judged if v.has_loop or c is not v.loop]
    with pd.option_context("display.width", 200, "display.max_columns", 20):
        print(pd.DataFrame(rows, columns=["quantity", "max_abs", "scale", "normalised",
                                          "at s", "horizon", "tol", "verdict"])
              .to_string(index=False))
    if v.not_read:
        _say(f"not read by {v.engine} (reported, not judged): {', '.join(v.not_read)}")
    for n in notes:
        _say(f"note: {n}")
    print(f"CPU {v.cpu_per_simulated_second:.3g} s per simulated second (stepping loop "
          f"only; dt {v.timestep:.3g} s, {v.integrator})")


def ci_case(run, v, file: str = ""):
    """A :class:`reports.regression.ci_formats.CiCase` of one free verdict."""
    w = v.worst
    kind, msg = "", ""
    if not v.run_ok:
        kind, msg = "run failed", f"the run ended at t = {v.t_fail:.4g} s: {v.reason}"
    elif not v.passed:
        kind = "tolerance"
    if not v.passed:
        msg = (msg + "; " if msg else "") + (
            f"{w.quantity}: error {w.normalised:.3g} of its {w.normalisation} exceeds the "
            f"tolerance {w.tolerance:g} from t = {w.horizon:.4g} s" if w.measured else
            f"{w.quantity}: not measured from t = {w.measured_until:.4g} s on")
        if v.near_event:
            msg += f" ({v.near_event})"
    details = [str(c) for c in v.judged] + [f"settings: {v.engine} {v.settings}"]
    word, note = label_of(v)
    if word == "known limit":  # the report's rule: reported, not a failure
        kind, msg = "known engine limit", f"{msg}; known engine limit: {note}"
    return CiCase(case=v.case, engine=v.engine,
                  status={"pass": "pass", "known limit": "limit"}.get(word, "fail"),
                  quantity=w.quantity, error=w.normalised,
                  at=f"t = {w.at:.4g} s" if math.isfinite(w.at) else "",
                  tolerance=w.tolerance, kind=kind, message=msg, details="\n".join(details),
                  settings=f"{v.engine} {v.settings}", time=float(run.wall),
                  notes=tuple(run.notes), file=file, version=versions(v.engine)["engine"])


def write_ci(args, mech, results) -> None:
    """``--junit`` / ``--summary`` of ``xval simulate --engine``."""
    if not (getattr(args, "junit", None) or getattr(args, "summary", None)):
        return

    given = str(getattr(args, "case", "") or "")
    file = Path(given).as_posix() if given.endswith(".toml") else ""
    write_outputs(f"xval simulate {mech.name}",
                  [ci_case(r, v, file) if r is not None else
                   CiCase(case=v.case, engine=v.engine, status="fail", kind="crashed",
                          message=f"engine crashed: {v.cause}",
                          details=f"engine crashed: {v.cause}", file=file)
                   for r, v in results],
                  args.junit, args.summary, command="simulate", error_label="error / scale")
