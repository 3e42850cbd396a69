"""``xval view CASE|FILE``: MuJoCo's viewer on the harness's own session of a linkage.

The model, its drive (armature and ``qfrc_applied``) and its loads are exactly those of
the verdict runs (:func:`sim_models.builders.viewer_model.run_viewer`); it starts at the analytic
assembled state with the prescribed rate.  Without a display it says so in one line
(status 2) and names the file route: ``xval models CASE --out DIR`` then
``python -m mujoco.viewer --mjcf=DIR/CASE.xml`` on a machine with one.
"""

from __future__ import annotations

from analytic import load_case
from reports.cli import options as opt
from reports.cli.plot import NoDisplay, has_display
from sim_models.builders.viewer_model import run_viewer, viewer_unavailable


def cmd_view(args) -> int:
    mech = load_case(args.case)  # a bad case or file is reported before the display
    ok, why = has_display()
    if ok:
        why = viewer_unavailable()
        ok = why is None
    if not ok:
        raise NoDisplay(f"xval view: {why}, so MuJoCo's viewer cannot open; write the "
                        f"model with 'xval models {args.case} --out DIR' and open "
                        "DIR/<name>.xml with 'python -m mujoco.viewer --mjcf=...' where "
                        "there is a display")
    print(run_viewer(mech, seconds=args.seconds))
    return 0


def register(sub) -> None:
    s = sub.add_parser("view", help="MuJoCo's viewer on the linkage, driven as the harness "
                       "drives it (needs a display)")
    s.add_argument("case", type=opt.case_or_file, help="built-in case name or TOML file")
    s.add_argument("--seconds", type=opt.finite_float(1e6, "s", lo=0.0),
                   help="stop after this much simulated time (default: when the window "
                        "closes)")
    s.set_defaults(func=cmd_view)
