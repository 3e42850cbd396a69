"""``xval explain CASE|FILE [--angle DEG | --value M] [--format md|html|tex] [--out F]``:
the worked solution of one configuration in the course notes' method and notation.

See :mod:`reports.explain.doc` for the contents and :mod:`reports.explain.render`
for the formats.  Bad input is one line and status 2, as for every ``xval`` command.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

from analytic import LinkageError, load_case
from analytic.mechanism import Revolute
from reports.cli import options as opt
from reports.explain.doc import explain
from reports.explain.render import render


def register(sub) -> None:
    """Add the ``explain`` subcommand to ``xval``'s subparsers."""
    s = sub.add_parser("explain", help="worked solution of one configuration, in the "
                                       "notes' method")
    s.add_argument("case", help="built-in case name or TOML file")
    g = s.add_mutually_exclusive_group()
    g.add_argument("--angle", type=opt.angle_deg, help="input angle, deg (revolute driver)")
    g.add_argument("--value", type=opt.length_m,
                   help="input displacement, m (prismatic driver)")
    s.add_argument("--format", choices=("md", "html", "tex"), default="md",
                   help="Markdown (default), HTML with MathML, or LaTeX")
    s.add_argument("--out", type=opt.output_file,
                   help="write to this file (Markdown figures go beside it as SVG); "
                        "default standard output")
    s.set_defaults(func=cmd_explain)


def input_value(mech, angle: float | None, value: float | None) -> float | None:
    """The driver value (rad or m) from ``--angle``/``--value``, checked against the
    driver's joint type."""
    rev = isinstance(mech.driver_joint, Revolute)
    if angle is not None:
        if not rev:
            raise LinkageError(f"case {mech.name!r} is driven by prismatic joint "
                               f"{mech.driver.joint!r}: give --value (m), not --angle")
        return math.radians(angle)
    if value is not None:
        if rev:
            raise LinkageError(f"case {mech.name!r} is driven by revolute joint "
                               f"{mech.driver.joint!r}: give --angle (deg), not --value")
        return value
    return None


def cmd_explain(args) -> int:
    mech = load_case(args.case)
    doc = explain(mech, input_value(mech, args.angle, args.value))
    out = Path(args.out) if args.out not in (None, "-") else None
    text = render(doc, args.format, out)
    if out is None:
        getattr(args, "stdout", sys.stdout).write(text + "\n")
        return 0
    try:
        out.write_text(text + "\n", encoding="utf-8")
    except OSError as e:
        raise LinkageError(f"--out {str(out)!r}: cannot write: {e.strerror}") from None
    print(f"wrote {out}")
    return 0
