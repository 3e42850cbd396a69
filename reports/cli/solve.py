"""The commands ``xval solve`` and ``xval sweep``: the analytic solver on the command
line.

``xval solve CASE_OR_FILE --angle DEG``  one configuration, tabulated as in the notes
``xval sweep CASE_OR_FILE``            the full-cycle table (CSV)
"""

from __future__ import annotations

import json
import math
import shutil
import sys
import textwrap

import numpy as np

from analytic import Linkage, LinkageError, load_case
from analytic.mechanism import Prismatic, Revolute
from analytic.stream import STREAM_POINTS, sweep_csv
from reports.cli import options as opt
from reports.cli.paths import write_csv
from reports.figures.display_units import DisplayUnits, convert_frame, convert_result, text

CONVENTIONS = {
    "units": "SI: m, rad, s, kg, N; angle_deg in degrees",
    "frame": "world: x right, y up; angles, omega, alpha counter-clockwise positive",
    "joint_force": "force exerted by the joint's body_a (prismatic: the guide) on body_b "
                   "(the slider), world axes, N",
    "prismatic": "normal: force along the line normal (direction rotated +90 deg) on the "
                 "slider, N; moment: couple on the slider, N m",
    "drive": "torque (N m, ccw on body_b) or force (N, on the slider along the line); "
             "power = effort x input velocity, W",
}


def _solve_one(args):
    mech = load_case(args.case)
    lk = Linkage(mech)
    rev = isinstance(mech.driver_joint, Revolute)
    value = None
    if args.angle is not None:
        if not rev:
            raise LinkageError(f"case {mech.name!r} is driven by prismatic joint "
                               f"{mech.driver.joint!r}: give --value (m), not --angle")
        value = math.radians(args.angle)
    if args.value is not None:
        if rev:
            raise LinkageError(f"case {mech.name!r} is driven by revolute joint "
                               f"{mech.driver.joint!r}: give --angle (deg), not --value")
        value = args.value
    kin = lk.kinematics(value, args.omega, args.alpha)
    frc = lk.forces(kin) if mech.has_mass else None
    return mech, lk, kin, frc


def _result_dict(mech, lk, kin, frc) -> dict:
    topo = lk.topo
    rev = isinstance(mech.driver_joint, Revolute)
    out = {
        "case": mech.name,
        "input": {"joint": mech.driver.joint,
                  ("angle_deg" if rev else "s"): float(np.degrees(kin.value[0]) if rev
                                                       else kin.value[0]),
                  "velocity": float(kin.velocity[0]),
                  "acceleration": float(kin.acceleration[0])},
        "bodies": {}, "points": {}, "sliders": {}, "joints": {},
        "conventions": CONVENTIONS,
    }
    for b, body in enumerate(mech.bodies):
        if b == topo.ground:
            continue
        ang = math.degrees(kin.theta[0, b])
        out["bodies"][body.name] = {"angle_deg": 180.0 - (180.0 - ang) % 360.0,
                                    "omega": float(kin.omega[0, b]),
                                    "alpha": float(kin.alpha[0, b])}
        for pn in body.points:
            p, v, a = kin.point(body.name, pn)
            out["points"][f"{body.name}.{pn}"] = {
                "position": p[0].tolist(), "velocity": v[0].tolist(),
                "acceleration": a[0].tolist()}
    for j in topo.prismatic:
        jn = topo.joint_names[j]
        s, v, a = kin.slider(jn)
        out["sliders"][jn] = {"s": float(s[0]), "v": float(v[0]), "a": float(a[0])}
    if frc is not None:
        for jt in mech.joints:
            d = {"body_a": jt.body_a, "body_b": jt.body_b,
                 "force": frc.joint_force[jt.name][0].tolist(),
                 "magnitude": float(np.hypot(*frc.joint_force[jt.name][0]))}
            if isinstance(jt, Prismatic):
                d["normal"] = float(frc.normal[jt.name][0])
                d["moment"] = float(frc.moment[jt.name][0])
            out["joints"][jt.name] = d
        out["drive"] = {("torque" if rev else "force"): float(frc.effort[0]),
                        "power": float(frc.power[0]),
                        "power_balance_residual": float(frc.power_residual[0])}
    else:
        out["drive"] = None
        out["forces_note"] = "no masses in the description: forces not computed"
    out["jacobian_condition"] = float(kin.condition[0])
    out["transmission_deg"] = {k: float(v[0]) for k, v in kin.transmission.items()}
    return out


def _print_tables(res: dict, units=None) -> None:
    """The tables of a solution ``res`` already in ``units`` (:mod:`reports.figures.display_units`:
    :func:`~reports.figures.display_units.convert_result`), units stated in every header."""
    from rich.console import Console
    from rich.table import Table

    u = units or DisplayUnits()
    lu, vu, au, an, sp = (u.unit(k) for k in ("length", "velocity", "acceleration", "angle",
                                              "omega"))
    con = Console()
    if con.width < 150:  # keep the tables whole when piped or in a narrow terminal
        con = Console(width=150)
    inp = res["input"]
    head = (f"[bold]{res['case']}[/]  input {inp['joint']} = "
            + (f"{text(inp['angle_deg'])} {an}, omega = {text(inp['velocity'])} {sp}, "
               f"alpha = {text(inp['acceleration'])} rad/s^2" if "angle_deg" in inp else
               f"{text(inp['s'])} {lu}, v = {text(inp['velocity'])} {vu}, "
               f"a = {text(inp['acceleration'])} {au}"))
    con.print(head)
    con.print(u.header(), markup=False)
    t = Table(title="Links: position, velocity, acceleration")
    for c in ("link", f"theta ({an})", f"omega ({sp})", "alpha (rad/s^2)"):
        t.add_column(c, justify="right")
    for n, d in res["bodies"].items():
        # angles to a fixed 1e-6 deg; rates at their own scale (a nano-scale linkage's
        # omega is not 0.000000)
        t.add_row(n, text(d["angle_deg"], ".6f"), text(d["omega"], ".7g"),
                  text(d["alpha"], ".7g"))
    con.print(t)
    t = Table(title="Points (world frame)")
    for c in ("point", f"x ({lu})", f"y ({lu})", f"vx ({vu})", f"vy ({vu})", f"|v| ({vu})",
              f"ax ({au})", f"ay ({au})", f"|a| ({au})"):
        t.add_column(c, justify="right")
    for n, d in res["points"].items():
        p, v, a = d["position"], d["velocity"], d["acceleration"]
        t.add_row(n, text(p[0], ".9g"), text(p[1], ".9g"), text(v[0]), text(v[1]),
                  text(math.hypot(*v)), text(a[0]), text(a[1]), text(math.hypot(*a)))
    con.print(t)
    if res["sliders"]:
        t = Table(title="Sliders")
        for c in ("joint", f"s ({lu})", f"s' ({vu})", f"s'' ({au})"):
            t.add_column(c, justify="right")
        for n, d in res["sliders"].items():
            t.add_row(n, text(d["s"], ".9g"), text(d["v"]), text(d["a"]))
        con.print(t)
    if res["drive"] is not None:
        t = Table(title="Joint forces (by body_a on body_b, world axes)")
        for c in ("joint", "by -> on", "fx (N)", "fy (N)", "|F| (N)", "moment (N m)"):
            t.add_column(c, justify="right")
        for n, d in res["joints"].items():
            t.add_row(n, f"{d['body_a']} -> {d['body_b']}", text(d["force"][0]),
                      text(d["force"][1]), text(d["magnitude"]),
                      text(d["moment"]) if "moment" in d else "")
        con.print(t)
        dr = res["drive"]
        eff = (f"drive torque T = {text(dr['torque'])} N m" if "torque" in dr
               else f"drive force F = {text(dr['force'])} N")
        con.print(f"{eff}, input power P = {text(dr['power'])} W "
                  f"(power-balance residual {dr['power_balance_residual']:.2g} W)")
    else:
        con.print("[dim]no masses in the description: forces not computed[/]")


def cmd_solve(args) -> int:
    units = DisplayUnits.parse(getattr(args, "units", None))
    res = convert_result(_result_dict(*_solve_one(args)), units)  # display units at the edge
    if args.json:
        print(json.dumps(res, indent=2, allow_nan=False))
    else:
        _print_tables(res, units)
    return 0


def cmd_sweep(args) -> int:
    parquet = getattr(args, "parquet", None)
    if parquet == "-":
        raise opt.UsageError("argument --parquet: '-' is not accepted: a Parquet file is "
                             "written with its index at the end; give a file name")
    mech = load_case(args.case)
    # written block by block: a large CSV, and Parquet always
    streamed = bool(parquet) or (bool(args.csv) and args.points > STREAM_POINTS)
    opt.check_sweep_points(args.points, len(mech.bodies) + len(mech.joints), streamed)
    lk = Linkage(mech, branch_rule=args.branch_rule)
    kw = {"velocity": args.omega}
    if args.range is not None:
        rev = isinstance(mech.driver_joint, Revolute)
        opt.check_input_range(args.range, rev)  # capped like --angle / --value
        if not (np.all(np.isfinite(args.range)) and args.range[1] > args.range[0]):
            raise LinkageError(f"option --range: {args.range[0]} {args.range[1]} must be two "
                               "finite numbers, the second larger")
        kw["input_range"] = tuple(math.radians(v) if rev else v for v in args.range)
    elif isinstance(mech.driver_joint, Revolute):
        kw["start"] = 0.0  # the table and the events run from 0 to 360 deg
    units = DisplayUnits.parse(getattr(args, "units", None))
    rev_ = isinstance(mech.driver_joint, Revolute)
    out = parquet or (getattr(args, "stdout", sys.stdout) if args.csv == "-" else args.csv)
    r = sweep_csv(lk, args.points, out, convert=lambda f: convert_frame(f, units, rev_),
                  parquet=bool(parquet), **kw) if streamed else lk.sweep(args.points, **kw)
    if args.csv and not streamed:  # display units at the edge, round-off noise shown as 0
        table = convert_frame(r.frame, units, isinstance(mech.driver_joint, Revolute))
        write_csv(table, args.csv, getattr(args, "stdout", sys.stdout))
    print(f"{mech.name}: {r.kinematics.n} points, "
          + ("full cycle" if r.full_cycle else "the range asked for" if args.range
             else "feasible range only")
          + (f", {r.grashof}" if r.grashof else ""))
    say = _paragraph_printer()
    if args.csv or parquet:
        say(f"table {units.header()}; the events and summary below in SI, angles in deg")
    else:
        say(f"no table written: --csv FILE writes the {r.kinematics.n}-point table (--csv - "
            "to standard output), --parquet FILE as Parquet"
            + ("; --units applies to that table" if getattr(args, "units", None) else "")
            + "; the events and summary below are in SI, angles in deg")
    for n in r.notes:
        say(f"note: {n}")
    _print_events(r, say)
    for line in r.summary.lines():
        say(line)
    if r.summary.power_balance is not None:  # over the regular samples
        print(f"power balance error {r.summary.power_balance:.2g} (relative)")
    for written in (args.csv, parquet):
        if written and written != "-":
            print(f"wrote {written}")
    return 0


def _print_events(r, say) -> None:
    """The sweep's events under a header with the input's unit, one event a line, its
    detail wrapped under it (left-aligned: pandas' right-aligned table ran to 130+
    columns); each input as the summary shows positions
    (:meth:`analytic.summary.Summary.shown_input`: on the table's range, round-off as 0)."""
    if not len(r.events):
        return
    u = r.summary.unit
    heads = ("kind", "where", f"input ({u})")
    w = max(len(heads[0]), *(len(str(k)) for k in r.events["kind"]))
    ww = max(len(heads[1]), *(len(str(x)) for x in r.events["where"]))
    print(f"events ({len(r.events)}):")
    print(f"{heads[0]:<{w}} {heads[1]:<{ww}} {heads[2]:>11}  detail")
    for e in r.events.itertuples(index=False):
        x = r.summary.shown_input(float(e.input))
        say(f"{e.kind:<{w}} {e.where:<{ww}} {x:11.6f}  {e.detail}")


def _paragraph_printer():
    """``say(text)``: print ``text`` wrapped to the terminal's width (60 to 120
    columns), continuation lines indented."""
    width = max(60, min(shutil.get_terminal_size((100, 24)).columns, 120))

    def say(text: str) -> None:
        print(textwrap.fill(text, width, subsequent_indent="    ", break_on_hyphens=False))
    return say


#: Every command: name -> (the module whose ``register(sub)`` adds it, its line in
#: ``xval --help``), one line per command.  Only the module of the command that runs is
#: imported (``xval --help`` imports none of them).

def register(sub) -> None:
    """Add ``solve`` and ``sweep`` to ``xval``'s subparsers."""
    s = sub.add_parser("solve", help="solve one configuration")
    s.add_argument("case", help="built-in case name or TOML file")
    s.add_argument("--angle", type=opt.angle_deg, help="input angle, deg (revolute driver)")
    s.add_argument("--value", type=opt.length_m, help="input displacement, m (prismatic driver)")
    s.add_argument("--omega", type=opt.rate, help="input velocity, rad/s (or m/s)")
    s.add_argument("--alpha", type=opt.accel, help="input acceleration, rad/s^2 (or m/s^2)")
    s.add_argument("--json", action="store_true", help="print one JSON object (SI)")
    s.add_argument("--units", type=opt.units_option, help=opt.UNITS_HELP)
    s.set_defaults(func=cmd_solve)
    s = sub.add_parser("sweep", help="full-cycle table")
    s.add_argument("case", help="built-in case name or TOML file")
    s.add_argument("--points", type=opt.sweep_points, default=360,
                   help=f"sweep points, 2 to {opt.MAX_SWEEP_POINTS}")
    table = s.add_mutually_exclusive_group()
    table.add_argument("--csv", type=opt.output_file,
                       help="write the table to this CSV file ('-': standard output, the "
                            "summary then goes to standard error)")
    table.add_argument("--parquet", type=opt.output_file, metavar="FILE",
                       help="write the table to this Parquet file instead (the same "
                            "columns and numbers, written block by block; for large sweeps)")
    s.add_argument("--omega", type=opt.rate,
                   help="input velocity, rad/s (or m/s); default the description's")
    s.add_argument("--range", type=float, nargs=2, metavar=("FROM", "TO"),
                   help="sweep from FROM to TO, deg (or m), instead of the full cycle "
                        "(default: 0 to 360 deg, or the feasible range)")
    s.add_argument("--branch-rule", choices=("continuous", "hold", "switch"),
                   default="continuous",
                   help="branch taken at a change point: the one whose velocity is "
                        "continuous (default), or hold / switch the dyad signs")
    s.add_argument("--units", type=opt.units_option, help=opt.UNITS_HELP + " (each CSV column "
                   "names its unit: 'crank.omega [rpm]')")
    s.set_defaults(func=cmd_sweep)


