"""``xval simulate CASE --engine NAME|all``: the engines released from the exact state,
each judged against the exact trajectory (:mod:`reports.comparison.free_compare`).

Options (added to ``xval simulate`` by :func:`add_options`): ``--engine``, ``--set
KEY=VALUE`` (``ENGINE.KEY=VALUE`` for one engine; the ranges of
:mod:`sim_models.ranges`, through :func:`sim_models.registry.settings_from_options`
with the free-motion settings classes), ``--integrator`` (MuJoCo's), ``--timestep``,
``--json``, ``--junit``, ``--summary``.  Exit status 1 when any verdict fails, 2 on bad
input (one line).
"""

from __future__ import annotations

import json
import math
import shutil
import textwrap
from pathlib import Path

import pandas as pd

from reports.cli import options as opt
from reports.cli.paths import check_outputs
from reports.comparison.compare import json_safe
from reports.comparison.free_compare import compare_free, reference_samples
from reports.comparison.progress import engine_progress
from reports.comparison.settings_file import apply_settings_file, given_keys, read_settings_file
from reports.regression.baseline import versions
from reports.regression.ci_formats import CiCase, write_outputs
from sim_models.free_engine import free_engine_names, free_session_class, run_free
from sim_models.free_run import FreeRequest
from sim_models.ranges import WALL_LIMIT
from sim_models.registry import settings_from_options

#: MuJoCo's integrators (``--integrator``: the same as ``--set mujoco.integrator=...``).
INTEGRATORS = ("RK4", "implicitfast", "implicit", "Euler")


def add_options(s) -> None:
    """The engine options of ``xval simulate``."""
    s.add_argument("--engine", choices=[*free_engine_names(), "all"],
                   help="release the linkage in this engine (or all) and judge its run "
                        "against the exact trajectory; exit status 1 on a failed verdict")
    s.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="an engine setting (repeatable; ENGINE.KEY=VALUE for one engine "
                        "only), e.g. --set mujoco.solref=-1e4,-200 (needs --engine)")
    s.add_argument("--integrator", choices=INTEGRATORS,
                   help="MuJoCo's integrator (same as --set mujoco.integrator=...; needs "
                        "--engine)")
    s.add_argument("--timestep", type=opt.timestep,
                   help=f"every engine's largest step, {opt.MIN_TIMESTEP:g} to "
                        f"{opt.MAX_TIMESTEP:g} s (needs --engine)")
    s.add_argument("--settings", metavar="FILE",
                   help="engine settings from a free-motion settings file (xval tune --free "
                        "--out; needs --engine)")
    s.add_argument("--wall-limit", type=opt.sim_range("WALL_LIMIT"), metavar="SECONDS",
                   help="end each engine's run after this much wall-clock time, "
                        f"{WALL_LIMIT.text()} (default {FreeRequest.wall_limit:g} s; a run "
                        "that reaches it ends as a result that says so; needs --engine)")
    opt.add_ci_outputs(s)


def engine_options_given(args) -> list[str]:
    """The engine-only options given without ``--engine`` (for the one-line refusal)."""
    named = {"--set": args.set, "--integrator": args.integrator, "--timestep": args.timestep,
             "--settings": args.settings,
             "--wall-limit": args.wall_limit, "--junit": args.junit, "--summary": args.summary}
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


def run_engines(mech, traj, args, samples: int):
    """Every chosen engine's free run, judged: a list of :class:`FreeVerdict`."""
    engines = list(free_engine_names()) if args.engine == "all" else [args.engine]
    settings = free_settings_for(engines, args)
    request = FreeRequest(duration=traj.duration, samples=max(1, samples - 1),
                          wall_limit=args.wall_limit or FreeRequest.wall_limit)
    ref = reference_samples(traj, request.times())
    out = []
    for eng in engines:
        with engine_progress(f"{eng}: {mech.name}, free motion {traj.duration:g} s"):
            run = run_free(mech, eng, settings[eng], request, traj)
        out.append((run, compare_free(run, traj, ref)))
    return out


def cmd_engines(args, mech, traj, samples: int, release=None) -> int:
    """The engine part of ``xval simulate``: run, judge, print; 0 pass, 1 fail.
    ``release``: the :class:`reports.comparison.free_cases.Release` of a built-in case without
    ``[motion]`` (in the JSON as ``released``; the text output says it before)."""
    check_outputs([("--junit", args.junit), ("--summary", args.summary)],
                  [("the case file", args.case)])
    results = run_engines(mech, traj, args, samples)
    verdicts = [v for _, v in results]
    if args.json:
        print(json.dumps(json_safe({
            "case": mech.name, "duration_s": traj.duration,
            "released": release.as_json() if release else None, "reference": {
                "method": traj.method, "rtol": traj.rtol,
                "events": [{"t_s": e.t, "kind": e.kind, "joint": e.joint,
                            "detail": e.detail} for e in traj.events]},
            "verdicts": [dict(v.as_json(), notes=list(r.notes)) for r, v in results]}),
            indent=2, allow_nan=False))
    else:
        for r, v in results:
            print_verdict(v, r.notes)
    write_ci(args, mech, results)
    return 0 if all(v.passed for v in verdicts) else 1


def _say(text: str) -> None:
    width = max(60, min(shutil.get_terminal_size((100, 24)).columns, 120))
    print(textwrap.fill(text, width, subsequent_indent="  ", break_on_hyphens=False))


def horizon_text(h: float, duration: float) -> str:
    """The trusted horizon in words."""
    return f"whole run ({duration:g} s)" if math.isinf(h) else f"{h:.4g} s"


def print_verdict(v, notes=()) -> None:
    """One engine's verdict as text: heading, the drifts, IFToMM, the table."""
    print(f"== {v.case} / {v.engine} (free motion, {v.duration:g} s): "
          f"{'PASS' if v.passed else 'FAIL'}")
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
    return CiCase(case=v.case, engine=v.engine, status="pass" if v.passed else "fail",
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
    write_outputs(f"xval simulate {mech.name}", [ci_case(r, v, file) for r, v in results],
                  args.junit, args.summary, command="simulate", error_label="error / scale")
