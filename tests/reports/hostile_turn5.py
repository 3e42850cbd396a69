"""The turn-5 hostile campaign's inputs and the one way each is run and classified
(shared by tests/reports/test_hostile_turn5.py and a count of outcomes by kind).

Each input is an ``xval`` command line run in-process in a scratch folder with the
files of :func:`write_files`; its outcome is one of

* ``error``: exit status 2 and exactly one line on standard error, ``xval: error: ...``;
* ``result``: exit status 0 or 1 with output (printed, or the file asked for written);
* ``traceback``: any other exception; ``hang``: still running after :data:`HANG_S`;
* ``silent``: status 0 and nothing printed or written; ``bad-error``: status 2 but not
  one line of printable text (a raw newline or escape sequence in it).
"""

from __future__ import annotations

import contextlib
import io
import os
import signal
from pathlib import Path

#: Seconds an input may run before it counts as a hang (every input is tiny: runs of
#: 0.01-0.05 s, a few samples; the slowest, an engine run with its model build, takes
#: about 2 s here).
HANG_S = 30

BASE = '''name = "fb"
ground = "ground"
gravity = [0.0, -9.81]

[units]
length = "m"

[bodies.ground]
points = { O2 = [0, 0], O4 = [0.4, 0] }

[bodies.crank]
points = { O2 = [0, 0], A = [0.1, 0] }
mass = 0.2
com = [0.05, 0]
inertia = 1.6666666666666667e-4

[bodies.coupler]
points = { A = [0, 0], B = [0.3, 0] }
mass = 0.6
com = [0.15, 0]
inertia = 4.5e-3

[bodies.rocker]
points = { O4 = [0, 0], B = [0.25, 0] }
mass = 0.5
com = [0.125, 0]
inertia = 2.6041666666666665e-3

[[joints]]
name = "O2"
type = "revolute"
bodies = ["ground", "crank"]
points = ["O2", "O2"]

[[joints]]
name = "A"
type = "revolute"
bodies = ["crank", "coupler"]
points = ["A", "A"]

[[joints]]
name = "B"
type = "revolute"
bodies = ["rocker", "coupler"]
points = ["B", "B"]

[[joints]]
name = "O4"
type = "revolute"
bodies = ["ground", "rocker"]
points = ["O4", "O4"]

[driver]
joint = "O2"
value = 60.0
velocity = 15.0
acceleration = 0.0

[assembly]
points = { "coupler.B" = [0.31, 0.23] }
'''
MOTION = '''
[motion]
joint = "O2"
value = 60.0
rate = 0.0
duration = 0.02
samples = 3
'''


def _sub(old: str, new: str) -> str:
    text = BASE + MOTION
    assert old in text, old
    return text.replace(old, new, 1)


#: file name -> content (text, or bytes for the odd files)
FILES: dict[str, str | bytes] = {
    "ok.toml": BASE + MOTION,
    "nomotion.toml": BASE,
    "empty.toml": "",
    "garbage.toml": b"\x00\xff\xfe\x89PNG\r\n\x1a\n" * 8,
    "syntax.toml": BASE + "[motion\njoint = ",
    "motion_joint.toml": _sub('joint = "O2"\nvalue = 60.0\nrate',
                              'joint = "Q9"\nvalue = 60.0\nrate'),
    "motion_value_str.toml": _sub("value = 60.0\nrate", 'value = "sixty"\nrate'),
    "motion_rate_nan.toml": _sub("rate = 0.0", "rate = nan"),
    "motion_rate_inf.toml": _sub("rate = 0.0", "rate = inf"),
    "motion_rate_huge.toml": _sub("rate = 0.0", "rate = 1e30"),
    "motion_duration_neg.toml": _sub("duration = 0.02", "duration = -1.0"),
    "motion_duration_str.toml": _sub("duration = 0.02", 'duration = "1 s"'),
    "motion_samples_one.toml": _sub("samples = 3", "samples = 1"),
    "motion_samples_float.toml": _sub("samples = 3", "samples = 2.5"),
    "motion_value_huge.toml": _sub("value = 60.0\nrate", "value = 1e300\nrate"),
    "motion_twice.toml": BASE + MOTION + MOTION,
    "name_escape.toml": _sub('name = "fb"', 'name = "fb\\u001b[31mred\\u0007"'),
    "name_unicode.toml": _sub('name = "fb"', 'name = "Viergelenk-é-✓-四節"'),
    "name_newline.toml": _sub('name = "fb"', 'name = "two\\nlines"'),
    "name_long.toml": _sub('name = "fb"', 'name = "' + "n" * 2000 + '"'),
    "gravity_huge.toml": _sub("gravity = [0.0, -9.81]", "gravity = [0.0, 1e30]"),
    "gravity_str.toml": _sub("gravity = [0.0, -9.81]", 'gravity = ["down", 0.0]'),
    "gravity_3d.toml": _sub("gravity = [0.0, -9.81]", "gravity = [0.0, -9.81, 0.0]"),
    "mass_negative.toml": _sub("mass = 0.6", "mass = -0.6"),
    "mass_str.toml": _sub("mass = 0.6", 'mass = "heavy"'),
    "inertia_nan.toml": _sub("inertia = 4.5e-3", "inertia = nan"),
    "inertia_zero.toml": _sub("inertia = 4.5e-3", "inertia = 0.0"),
    "crank_zero_length.toml": _sub("points = { O2 = [0, 0], A = [0.1, 0] }",
                                   "points = { O2 = [0, 0], A = [0.0, 0] }"),
    "coincident_ground.toml": _sub("points = { O2 = [0, 0], O4 = [0.4, 0] }",
                                   "points = { O2 = [0, 0], O4 = [0.0, 0] }"),
    "huge_geometry.toml": _sub("points = { O2 = [0, 0], O4 = [0.4, 0] }",
                               "points = { O2 = [0, 0], O4 = [4e30, 0] }"),
    "joint_dup.toml": BASE.replace('name = "A"', 'name = "O2"', 1) + MOTION,
    "joint_bad_point.toml": _sub('points = ["A", "A"]', 'points = ["A", "Z"]'),
    "joint_bad_type.toml": _sub('type = "revolute"', 'type = "spherical"'),
    "units_bad.toml": _sub('length = "m"', 'length = "furlong"'),
    "hint_far.toml": _sub('"coupler.B" = [0.31, 0.23]', '"coupler.B" = [310.0, 230.0]'),
    "spring_neg.toml": BASE + MOTION + '''
[[springs]]
bodies = ["coupler", "ground"]
points = ["B", "O4"]
stiffness = -5.0
free_length = 0.1
''',
    "spring_str.toml": BASE + MOTION + '''
[[springs]]
bodies = ["coupler", "ground"]
points = ["B", "O4"]
stiffness = "stiff"
free_length = 0.1
''',
    "spring_bad_body.toml": BASE + MOTION + '''
[[springs]]
bodies = ["coupler", "nowhere"]
points = ["B", "O4"]
stiffness = 5.0
free_length = 0.1
''',
    "spring_coincident_zero.toml": BASE + MOTION + '''
[[springs]]
bodies = ["crank", "coupler"]
points = ["A", "A"]
stiffness = 30.0
free_length = 0.0
''',
    "damper_bad_joint.toml": BASE + MOTION + '''
[[dampers]]
joint = "Q7"
coefficient = 0.1
''',
    "damper_neg.toml": BASE + MOTION + '''
[[dampers]]
joint = "O2"
coefficient = -0.1
''',
    "motor_decreasing.toml": BASE + MOTION + '''
[[motors]]
joint = "O2"
table = [[0.0, 0.0], [1.0, 0.2], [0.5, 0.1]]
''',
    "motor_duplicate_t.toml": BASE + MOTION + '''
[[motors]]
joint = "O2"
table = [[0.0, 0.0], [0.5, 0.2], [0.5, 0.4], [1.0, 0.1]]
''',
    "motor_nan.toml": BASE + MOTION + '''
[[motors]]
joint = "O2"
table = [[0.0, 0.0], [1.0, nan]]
''',
    "motor_empty.toml": BASE + MOTION + '''
[[motors]]
joint = "O2"
table = []
''',
    "motor_one_row.toml": BASE + MOTION + '''
[[motors]]
joint = "O2"
table = [[0.0, 0.1]]
''',
    "motor_ragged.toml": BASE + MOTION + '''
[[motors]]
joint = "O2"
table = [[0.0, 0.1, 7.0], [1.0]]
''',
    "load_bad_body.toml": BASE + MOTION + '''
[[loads]]
body = "nowhere"
point = "B"
force = [0.0, -5.0]
torque = 0.0
''',
    "load_huge.toml": BASE + MOTION + '''
[[loads]]
body = "rocker"
point = "B"
force = [0.0, -1e300]
torque = 0.0
''',
}


def write_files(folder: Path) -> None:
    """Every file of :data:`FILES` in ``folder``, and a sub-folder named like a file."""
    for name, content in FILES.items():
        p = folder / name
        if isinstance(content, bytes):
            p.write_bytes(content)
        else:
            p.write_text(content, encoding="utf-8")
    (folder / "folder.toml").mkdir(exist_ok=True)


#: (id, argv, expected kind: "error" or "result"); argv words are run in the scratch folder
SIM = ["simulate", "ok.toml"]
ENG = ["--engine", "mujoco", "--duration", "0.01", "--samples", "3"]
CASES: list[tuple[str, list[str], str]] = [
    # -- simulate: the exact side, options
    ("sim-ok", SIM, "result"),
    ("sim-duration-0", SIM + ["--duration", "0"], "error"),
    ("sim-duration-neg", SIM + ["--duration", "-1"], "error"),
    ("sim-duration-nan", SIM + ["--duration", "nan"], "error"),
    ("sim-duration-inf", SIM + ["--duration", "inf"], "error"),
    ("sim-duration-below-min", SIM + ["--duration", "1e-7"], "error"),
    ("sim-duration-above-max", SIM + ["--duration", "1e5"], "error"),
    ("sim-duration-word", SIM + ["--duration", "1s"], "error"),
    ("sim-duration-min", SIM + ["--duration", "1e-6"], "result"),
    ("sim-samples-1", SIM + ["--samples", "1"], "error"),
    ("sim-samples-0", SIM + ["--samples", "0"], "error"),
    ("sim-samples-neg", SIM + ["--samples", "-5"], "error"),
    ("sim-samples-float", SIM + ["--samples", "2.5"], "error"),
    ("sim-samples-huge", SIM + ["--samples", "99999999999"], "error"),
    ("sim-samples-2", SIM + ["--samples", "2"], "result"),
    ("sim-json-and-csv-stdout", SIM + ["--json", "--csv", "-"], "error"),
    ("sim-json", SIM + ["--json"], "result"),
    ("sim-csv-stdout", SIM + ["--csv", "-"], "result"),
    ("sim-csv-file", SIM + ["--csv", "out.csv"], "result"),
    # the documented output rule: a missing folder of an output file is made
    ("sim-csv-into-missing-folder", SIM + ["--csv", "no/such/dir/out.csv"], "result"),
    ("sim-csv-is-folder", SIM + ["--csv", "folder.toml"], "error"),
    ("sim-set-without-engine", SIM + ["--set", "timestep=1e-3"], "error"),
    ("sim-builtin-released", ["simulate", "seed-four-bar", "--duration", "0.01",
                              "--samples", "3"], "result"),
    ("sim-builtin-massless", ["simulate", "hibbeler-16-30"], "error"),
    # -- simulate: odd files
    ("sim-missing-file", ["simulate", "missing.toml"], "error"),
    ("sim-empty-file", ["simulate", "empty.toml"], "error"),
    ("sim-garbage-file", ["simulate", "garbage.toml"], "error"),
    ("sim-folder-as-file", ["simulate", "folder.toml"], "error"),
    ("sim-syntax-error", ["simulate", "syntax.toml"], "error"),
    ("sim-no-motion-file", ["simulate", "nomotion.toml"], "error"),
    ("sim-motion-twice", ["simulate", "motion_twice.toml"], "error"),
    ("sim-motion-joint-unknown", ["simulate", "motion_joint.toml"], "error"),
    ("sim-motion-value-str", ["simulate", "motion_value_str.toml"], "error"),
    ("sim-motion-rate-nan", ["simulate", "motion_rate_nan.toml"], "error"),
    ("sim-motion-rate-inf", ["simulate", "motion_rate_inf.toml"], "error"),
    ("sim-motion-rate-huge", ["simulate", "motion_rate_huge.toml"], "error"),
    ("sim-motion-duration-neg", ["simulate", "motion_duration_neg.toml"], "error"),
    ("sim-motion-duration-str", ["simulate", "motion_duration_str.toml"], "error"),
    ("sim-motion-samples-1", ["simulate", "motion_samples_one.toml"], "error"),
    ("sim-motion-samples-float", ["simulate", "motion_samples_float.toml"], "error"),
    ("sim-motion-value-huge", ["simulate", "motion_value_huge.toml"], "error"),
    ("sim-name-escape", ["simulate", "name_escape.toml"], "error"),
    ("sim-name-unicode", ["simulate", "name_unicode.toml"], "result"),
    ("sim-name-newline", ["simulate", "name_newline.toml"], "error"),
    ("sim-name-long", ["simulate", "name_long.toml"], "result"),
    ("sim-gravity-huge", ["simulate", "gravity_huge.toml"], "error"),
    ("sim-gravity-str", ["simulate", "gravity_str.toml"], "error"),
    ("sim-gravity-3d", ["simulate", "gravity_3d.toml"], "error"),
    ("sim-mass-negative", ["simulate", "mass_negative.toml"], "error"),
    ("sim-mass-str", ["simulate", "mass_str.toml"], "error"),
    ("sim-inertia-nan", ["simulate", "inertia_nan.toml"], "error"),
    ("sim-inertia-zero", ["simulate", "inertia_zero.toml"], "error"),
    ("sim-crank-zero-length", ["simulate", "crank_zero_length.toml"], "error"),
    # crank and rocker on one ground pin: a valid mechanism (a triangle of links)
    ("sim-coincident-ground-pins", ["simulate", "coincident_ground.toml"], "result"),
    ("sim-huge-geometry", ["simulate", "huge_geometry.toml"], "error"),
    ("sim-duplicate-joint", ["simulate", "joint_dup.toml"], "error"),
    ("sim-joint-bad-point", ["simulate", "joint_bad_point.toml"], "error"),
    ("sim-joint-bad-type", ["simulate", "joint_bad_type.toml"], "error"),
    ("sim-units-bad", ["simulate", "units_bad.toml"], "error"),
    ("sim-hint-far", ["simulate", "hint_far.toml"], "error"),
    ("sim-spring-negative", ["simulate", "spring_neg.toml"], "error"),
    ("sim-spring-str", ["simulate", "spring_str.toml"], "error"),
    ("sim-spring-bad-body", ["simulate", "spring_bad_body.toml"], "error"),
    ("sim-damper-bad-joint", ["simulate", "damper_bad_joint.toml"], "error"),
    ("sim-damper-negative", ["simulate", "damper_neg.toml"], "error"),
    ("sim-motor-decreasing", ["simulate", "motor_decreasing.toml"], "error"),
    ("sim-motor-duplicate-time", ["simulate", "motor_duplicate_t.toml"], "error"),
    ("sim-motor-nan", ["simulate", "motor_nan.toml"], "error"),
    ("sim-motor-empty", ["simulate", "motor_empty.toml"], "error"),
    ("sim-motor-ragged", ["simulate", "motor_ragged.toml"], "error"),
    ("sim-load-bad-body", ["simulate", "load_bad_body.toml"], "error"),
    ("sim-load-huge", ["simulate", "load_huge.toml"], "error"),
    # -- simulate --engine
    ("eng-bogus", SIM + ["--engine", "bogus"], "error"),
    ("eng-mujoco", SIM + ENG, "result"),
    ("eng-set-timestep-0", SIM + ENG + ["--set", "timestep=0"], "error"),
    ("eng-set-timestep-nan", SIM + ENG + ["--set", "timestep=nan"], "error"),
    ("eng-set-newline", SIM + ENG + ["--set", "integrator=RK4\nx"], "error"),
    ("eng-set-key-newline", SIM + ENG + ["--set", "time\nstep=1e-3"], "error"),
    ("eng-set-escape", SIM + ENG + ["--set", "integrator=\x1b[2J"], "error"),
    ("eng-set-empty", SIM + ENG + ["--set", "="], "error"),
    ("eng-set-no-equals", SIM + ENG + ["--set", "timestep"], "error"),
    ("eng-set-unknown-key", SIM + ENG + ["--set", "mujoco.warp_speed=9"], "error"),
    ("eng-set-other-engine", SIM + ENG + ["--set", "pybullet.erp=0.5"], "error"),
    ("eng-integrator-lower", SIM + ENG + ["--integrator", "rk4"], "result"),
    ("eng-integrator-bogus", SIM + ENG + ["--integrator", "leapfrog"], "error"),
    ("eng-set-integrator-upper", SIM + ENG + ["--set", "integrator=EULER"], "result"),
    ("eng-wall-limit-0", SIM + ENG + ["--wall-limit", "0"], "error"),
    ("eng-wall-limit-nan", SIM + ENG + ["--wall-limit", "nan"], "error"),
    ("eng-wall-limit-huge", SIM + ENG + ["--wall-limit", "1e9"], "error"),
    ("eng-timestep-tiny", SIM + ENG + ["--timestep", "1e-9"], "error"),
    ("eng-samples-closer-than-a-step", SIM + ["--engine", "mujoco", "--duration", "1e-6"],
     "error"),
    ("eng-tiny-run-two-samples", SIM + ["--engine", "mujoco", "--duration", "1e-6",
                                        "--samples", "2"], "result"),
    ("eng-junit-is-input", SIM + ENG + ["--junit", "ok.toml"], "error"),
    ("eng-csv-stdout", SIM + ENG + ["--csv", "-"], "error"),
    # -- plot / animate --free
    ("plot-free-builtin", ["plot", "seed-four-bar", "--free", "--duration", "0.01",
                           "--samples", "3", "--out", "p.png"], "result"),
    ("plot-free-file", ["plot", "ok.toml", "--free", "--out", "q.png"], "result"),
    ("plot-free-massless", ["plot", "hibbeler-16-30", "--free", "--out", "r.png"], "error"),
    ("plot-free-no-motion-file", ["plot", "nomotion.toml", "--free", "--out", "s.png"],
     "error"),
    ("plot-free-samples-1", ["plot", "ok.toml", "--free", "--samples", "1"], "error"),
    ("plot-free-samples-huge", ["plot", "ok.toml", "--free", "--samples", "1e9"], "error"),
    ("plot-free-what-bogus", ["plot", "ok.toml", "--free", "--what", "colour"], "error"),
    ("plot-free-engine", ["plot", "ok.toml", "--free", "--engine", "mujoco"], "error"),
    ("plot-free-out-txt", ["plot", "ok.toml", "--free", "--out", "p.txt"], "error"),
    ("plot-free-duration-nan", ["plot", "ok.toml", "--free", "--duration", "nan"], "error"),
    ("plot-driven-duration", ["plot", "seed-four-bar", "--driven", "--duration", "1"],
     "error"),
    ("plot-free-and-driven", ["plot", "ok.toml", "--free", "--driven"], "error"),
    ("animate-free-builtin", ["animate", "seed-four-bar", "--free", "--duration", "0.01",
                              "--frames", "36", "--out", "a.gif"], "result"),
    ("animate-free-frames-0", ["animate", "ok.toml", "--free", "--frames", "0",
                               "--out", "b.gif"], "error"),
    ("animate-free-out-txt", ["animate", "ok.toml", "--free", "--out", "b.txt"], "error"),
    ("animate-no-out", ["animate", "ok.toml", "--free"], "error"),
    # -- sweep
    ("sweep-ok", ["sweep", "seed-four-bar", "--points", "36"], "result"),
    ("sweep-points-1", ["sweep", "seed-four-bar", "--points", "1"], "error"),
    ("sweep-points-0", ["sweep", "seed-four-bar", "--points", "0"], "error"),
    ("sweep-points-2", ["sweep", "seed-four-bar", "--points", "2"], "result"),
    ("sweep-points-huge", ["sweep", "seed-four-bar", "--points", "1000000000000"], "error"),
    ("sweep-range-empty", ["sweep", "seed-four-bar", "--range", "10", "10"], "error"),
    ("sweep-range-reversed", ["sweep", "seed-four-bar", "--range", "20", "10"], "error"),
    ("sweep-range-nan", ["sweep", "seed-four-bar", "--range", "nan", "10"], "error"),
    ("sweep-range-huge", ["sweep", "seed-four-bar", "--range", "0", "1e9"], "error"),
    ("sweep-csv-is-input", ["sweep", "ok.toml", "--csv", "ok.toml"], "error"),
    ("sweep-csv-and-parquet", ["sweep", "seed-four-bar", "--csv", "x.csv", "--parquet",
                               "x.parquet"], "error"),
    ("sweep-parquet-stdout", ["sweep", "seed-four-bar", "--parquet", "-"], "error"),
    ("sweep-omega-nan", ["sweep", "seed-four-bar", "--omega", "nan"], "error"),
    ("sweep-omega-huge", ["sweep", "seed-four-bar", "--omega", "1e30"], "error"),
    ("sweep-branch-rule-bogus", ["sweep", "seed-four-bar", "--branch-rule", "maybe"],
     "error"),
    ("sweep-free-file", ["sweep", "ok.toml", "--points", "12"], "result"),
    ("sweep-empty-file", ["sweep", "empty.toml"], "error"),
    # -- solve, explain
    ("solve-angle-nan", ["solve", "seed-four-bar", "--angle", "nan"], "error"),
    ("solve-angle-huge", ["solve", "seed-four-bar", "--angle", "1e30"], "error"),
    ("solve-value-on-revolute", ["solve", "seed-four-bar", "--value", "0.1"], "error"),
    ("solve-name-newline", ["solve", "see\nd"], "error"),
    ("solve-name-escape", ["solve", "seed\x1b[31m"], "error"),
    ("solve-name-empty", ["solve", ""], "error"),
    ("solve-unicode-file", ["solve", "name_unicode.toml", "--angle", "60"], "result"),
    ("explain-ok", ["explain", "seed-four-bar", "--angle", "30"], "result"),
    ("explain-angle-inf", ["explain", "seed-four-bar", "--angle", "inf"], "error"),
    ("explain-format-bogus", ["explain", "seed-four-bar", "--format", "docx"], "error"),
    ("explain-out-is-input", ["explain", "ok.toml", "--out", "ok.toml"], "error"),
    # -- compare
    ("compare-revolutions-0", ["compare", "seed-four-bar", "--engine", "mujoco",
                               "--revolutions", "0"], "error"),
    ("compare-samples-1", ["compare", "seed-four-bar", "--engine", "mujoco",
                           "--samples", "1"], "error"),
    ("compare-integrator-upper", ["compare", "seed-four-bar", "--engine", "mujoco",
                                  "--integrator", "EULER", "--revolutions", "1",
                                  "--samples", "8"], "result"),
    ("compare-set-integrator-lower", ["compare", "seed-four-bar", "--engine", "mujoco",
                                      "--set", "mujoco.integrator=rk4", "--revolutions", "1",
                                      "--samples", "8"], "result"),
    ("compare-set-tab", ["compare", "seed-four-bar", "--engine", "mujoco",
                         "--set", "timestep=\t1e-3\t"], "result"),
    # -- the command table
    ("help", ["--help"], "result"),
    ("cases", ["cases"], "result"),
    ("no-command", [], "error"),
    ("bogus-command", ["fly"], "error"),
]


class _Hang(Exception):
    pass


def _alarm(signum, frame):
    raise _Hang


def classify(argv: list[str], folder: Path) -> tuple[str, str, str]:
    """``(kind, stdout, stderr)`` of ``xval ARGV`` run in-process in ``folder``."""
    from reports.cli.xval import main
    out, err = io.StringIO(), io.StringIO()
    before = {p.name for p in folder.iterdir()}
    cwd = os.getcwd()
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(HANG_S)
    try:
        os.chdir(folder)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(list(argv))
            except SystemExit as e:  # --help
                code = e.code
    except _Hang:
        return "hang", out.getvalue(), err.getvalue()
    except Exception as e:  # noqa: BLE001 - a traceback is what is counted
        return "traceback", out.getvalue(), f"{type(e).__name__}: {e}"
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
        os.chdir(cwd)
    o, e = out.getvalue(), err.getvalue()
    written = {p.name for p in folder.iterdir()} - before
    if code == 2:
        lines = e.strip("\n").split("\n")
        one = len(lines) == 1 and lines[0].startswith("xval: error: ") and \
            not any(ord(ch) < 32 or ord(ch) == 127 for ch in lines[0])
        return ("error" if one else "bad-error"), o, e
    if code in (0, 1) and (o.strip() or written):
        return "result", o, e
    return ("silent" if code in (0, 1, None) else f"status {code}"), o, e


#: The Python API's free door (:func:`reports.comparison.free_cases.release_and_judge`,
#: what ``xval simulate --engine`` and the plugin's ``assert_free_agrees`` run): (id,
#: keyword arguments, expected kind), the seed four-bar released in MuJoCo.
API_CASES: list[tuple[str, dict, str]] = [
    ("api-ok", dict(duration=0.02, samples=4), "result"),
    ("api-samples-0", dict(duration=0.02, samples=0), "error"),
    ("api-samples-neg", dict(duration=0.02, samples=-3), "error"),
    ("api-samples-float", dict(duration=0.02, samples=2.5), "error"),
    ("api-duration-nan", dict(duration=float("nan"), samples=4), "error"),
    ("api-duration-neg", dict(duration=-1.0, samples=4), "error"),
    ("api-samples-closer-than-a-step", dict(duration=1e-6, samples=200), "error"),
    ("api-settings-lower-case", dict(duration=0.02, samples=4,
                                     settings={"integrator": "rk4"}), "result"),
    ("api-settings-bogus", dict(duration=0.02, samples=4, settings={"integrator": "bogus"}),
     "error"),
    ("api-settings-timestep-0", dict(duration=0.02, samples=4, settings={"timestep": 0}),
     "error"),
    ("api-settings-unknown", dict(duration=0.02, samples=4, settings={"warp": 1}), "error"),
]


def classify_api(kwargs: dict) -> tuple[str, str]:
    """``(kind, message)`` of one API call: ``error`` a typed one-line
    :class:`analytic.errors.LinkageError`, ``result`` a verdict judged at more than one
    sample, ``silent`` a verdict judged at t = 0 only, ``traceback`` anything else."""
    from analytic import load_case
    from analytic.errors import LinkageError
    from reports.comparison.free_cases import release_and_judge
    try:
        _, v = release_and_judge(load_case("seed-four-bar"), "mujoco", **kwargs)
    except LinkageError as e:
        return ("error" if "\n" not in str(e) else "bad-error"), str(e)
    except Exception as e:  # noqa: BLE001 - a traceback is what is counted
        return "traceback", f"{type(e).__name__}: {e}"
    return ("result" if len(v.times) > 1 else "silent"), f"passed={v.passed}"
