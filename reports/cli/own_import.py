"""``xval import MODEL.xml|MODEL.urdf [--driver JOINT] [--keyframe NAME] [--close
LINK_A:x,y,z=LINK_B:x,y,z] --out FILE.toml``: a user's own MJCF or URDF model read
through MuJoCo's compiler (:func:`sim_models.own.import_model`), checked to be a planar
one-degree-of-freedom linkage, and written as the description of its exact reference,
with the table mapping the model's elements to the description's (printed, and kept in
the file's header)."""

from __future__ import annotations

import sys

from analytic.errors import OutputError
from analytic.motion_spec import MAX_DURATION
from reports.cli import options as opt
from reports.cli.own_options import add_own_options
from reports.cli.paths import check_outputs
from reports.comparison.free_cases import MIN_DURATION
from sim_models.own import DEFAULT_DURATION, import_model, imported_toml, table_text


def own_closes(args) -> tuple:
    """``--close`` as :class:`sim_models.own.Close` objects."""
    from sim_models.own import Close
    return tuple(Close(*c) for c in (getattr(args, "close", None) or ()))


def cmd_import(args) -> int:
    check_outputs([("--out", args.out)], [("the model file", args.model)])
    imp = import_model(args.model, args.driver, args.keyframe, args.duration,
                       own_closes(args))
    text = imported_toml(imp)
    if args.out == "-":
        args.stdout.write(text)
        return 0
    try:
        with open(args.out, "w", encoding="utf-8") as fh:
            fh.write(text)
    except OSError as e:
        raise OutputError(f"cannot write {args.out!r}: {e.strerror or e}") from None
    m = imp.mechanism
    print(f"{args.model} ({imp.compiled.config}): {len(m.moving_bodies)} moving bodies, "
          f"{len(m.joints)} joints, driver {m.driver.joint!r}")
    print(table_text(imp))
    for line in imp.notes:
        print(f"note: {line}")
    for line in imp.not_modelled:
        print(f"not modelled: {line}")
    print(f"wrote {args.out}")
    return 0


def register(sub) -> None:
    """Add ``import`` to ``xval``'s subparsers."""
    s = sub.add_parser("import", help="read your own MJCF model and write its description")
    s.add_argument("model", help="the MJCF (.xml) or URDF (.urdf) file, read by "
                   "MuJoCo's compiler")
    add_own_options(s, "")
    s.add_argument("--duration", type=opt.finite_float(MAX_DURATION, "s", lo=MIN_DURATION),
                   default=DEFAULT_DURATION,
                   help=f"free motion's duration in [motion], s (default {DEFAULT_DURATION:g})")
    s.add_argument("--out", type=opt.output_file, required=True,
                   help="the description to write (TOML), or - for standard output")
    s.set_defaults(func=cmd_import)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(1)
