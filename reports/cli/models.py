"""``xval models [CASE|FILE] [--out DIR]``: the MJCF/URDF files of one case, or of every
built-in case (:func:`sim_models.builders.model_files.write_models`)."""

from __future__ import annotations

from reports.cli import options as opt
from sim_models.builders.model_files import MODELS_DIR, write_models


def cmd_models(args) -> int:
    if args.case and not args.out:
        raise opt.UsageError("xval models CASE_OR_FILE needs --out DIR (the default folder, "
                             "sim_models/models, holds the built-in cases' committed files)")
    paths = write_models(args.out or MODELS_DIR, [args.case] if args.case else None)
    print(f"wrote {len(paths)} files to {args.out or MODELS_DIR}")
    for p in paths:
        if p.suffix == ".xml":
            print(f"view it turning: python -m mujoco.viewer --mjcf={p}  (or xval view "
                  f"{args.case or p.stem}; keyframe 'assembled' is the prescribed start)")
            break
    return 0


def register(sub) -> None:
    """Add ``models`` to ``xval``'s subparsers."""
    s = sub.add_parser("models", help="write the MJCF/URDF files of one case or file, or of "
                       "every built-in case")
    s.add_argument("case", nargs="?", type=opt.case_or_file,
                   help="built-in case name or TOML file (default: every built-in case)")
    s.add_argument("--out", type=opt.output_dir, help="directory (default sim_models/models)")
    s.set_defaults(func=cmd_models)
