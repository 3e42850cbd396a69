"""Every error a user can cause ends in one line on standard error, naming the file, key,
body, joint, option or input value, with exit status 2 (issue 8, "What to build" 5, 8, 9).

Each row is one distinct bad input: a file (written from the seed four-bar with one
change) or a command line.  The test runs ``reports.cli.xval.main`` in-process and asserts
the exit status, that standard error is exactly one line matching the row's message
class, that it holds no traceback, and that nothing was written to standard output.
A few rows that need a real pipe run ``xval`` in a subprocess.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from analytic.cases import case_path
from reports.cli.xval import main

SEED = case_path("seed-four-bar").read_text()
HARD = Path(__file__).resolve().parents[2] / "analytic" / "cases" / "hard"
# the seed four-bar at 1e-8 scale (a 4 nm linkage; the file is in mm)
NANOMETRE = SEED
for _k in ("400", "100", "300", "250", "310", "230", "50", "150", "125"):
    NANOMETRE = NANOMETRE.replace(f"[{_k}, ", f"[{_k}e-8, ").replace(f", {_k}]", f", {_k}e-8]")
NANOMETRE = NANOMETRE.replace("inertia = 1.6666666666666667e-4", "inertia = 1.67e-20").replace(
    "inertia = 4.5e-3", "inertia = 4.5e-19").replace("inertia = 2.6041666666666665e-3",
                                                      "inertia = 2.6e-19")
# ../shared/bugs/loops-not-a-cycle.toml: the seed four-bar with a two-joint "loop"
LOOPS_NOT_A_CYCLE = 'loops = [["O2", "A"]]\n' + SEED


def edit(old: str, new: str, count: int = 1):
    """A file mutation: replace ``old`` by ``new`` in the seed four-bar (must match)."""
    def mutate(text: str) -> str:
        assert old in text, f"mutation target {old!r} not in the seed file"
        return text.replace(old, new, count)
    return mutate


def text(body: str):
    return lambda _: body


# (id, file mutation or raw bytes, message regex); every file row runs `xval solve FILE`.
FILE_ROWS = [
    ("utf16", SEED.encode("utf-16"), r"m\.toml: the file is UTF-16 text; TOML files must be UTF-8"),
    ("binary", bytes(range(256)) * 4,
     r"m\.toml: not a UTF-8 text file \(byte 0x80 at offset 128\)"),
    ("nul-byte", b"name = \"x\"\n\x00\n", r"m\.toml: not a text file \(a NUL byte"),
    ("latin1", "name = \"caf\xe9\"\n".encode("latin-1"), r"not a UTF-8 text file \(byte 0xe9"),
    ("malformed", text("name = \n"), r"m\.toml: malformed TOML: .*line 1"),
    ("units-array", edit('[units]\nlength = "mm"', 'units = ["mm"]'),
     r"m\.toml: \[units\]: expected a table, got an array"),
    ("units-length-array", edit('length = "mm"', 'length = ["mm"]'),
     r"\[units\]: unknown length unit \['mm'\]"),
    ("units-unknown", edit('length = "mm"', 'length = "furlong"'),
     r"\[units\]: unknown length unit 'furlong'"),
    ("hint-points-array", edit('points = { "coupler.B" = [310, 230] }', 'points = [[310, 230]]'),
     r"\[assembly\]: points must be a table, got an array"),
    ("hint-angles-array", edit('points = { "coupler.B" = [310, 230] }', 'angles = [10]'),
     r"\[assembly\]: angles must be a table, got an array"),
    ("hint-not-pair", edit('"coupler.B" = [310, 230]', '"coupler.B" = 310'),
     r"\[assembly\]: hint 'coupler\.B' must be a pair"),
    ("hint-unknown-point", edit('"coupler.B" = [310, 230]', '"coupler.Z" = [310, 230]'),
     r"assembly: assembly hint names unknown point 'coupler\.Z'"),
    ("hint-huge", edit('"coupler.B" = [310, 230]', '"coupler.B" = [310, 1e300]'),
     r"\[assembly\]: hint 'coupler\.B' = 1e\+300 mm is out of range: .*<= 1e\+07 mm"),
    ("hint-angle-nan", edit('points = { "coupler.B" = [310, 230] }', 'angles = { rocker = nan }'),
     r"\[assembly\]: hint 'rocker' must be a finite number"),
    ("mass-1e308", edit("mass = 0.6", "mass = 1e308"),
     r"body 'coupler': mass = 1e\+308 kg is out of range: the accepted range is 0 to 1e\+09 kg"),
    ("mass-negative", edit("mass = 0.6", "mass = -0.6"),
     r"body 'coupler': mass = -0\.6 kg is out of range"),
    ("mass-nan", edit("mass = 0.6", "mass = nan"), r"body 'coupler': mass must be a finite number"),
    ("mass-string", edit("mass = 0.6", 'mass = "0.6"'),
     r"body 'coupler': mass must be a finite number, got '0\.6'"),
    ("inertia-huge", edit("inertia = 4.5e-3", "inertia = 1e300"),
     r"body 'coupler': inertia = 1e\+300 kg m\^2 is out of range"),
    ("inertia-zero", edit("inertia = 4.5e-3", "inertia = 0"),
     r"body 'coupler'.*inertia about the centre of mass must be > 0"),
    ("inertia-without-mass", edit("mass = 0.6\n", ""),
     r"body 'coupler'.*inertia given without a mass"),
    ("velocity-1e200", edit("velocity = 15.0", "velocity = 1e200"),
     r"\[driver\]: velocity = 1e\+200 rad/s is out of range: .*\|velocity\| <= 1e\+06 rad/s"),
    ("velocity-inf", edit("velocity = 15.0", "velocity = inf"),
     r"\[driver\]: velocity must be a finite number, got inf"),
    ("acceleration-huge", edit("acceleration = 0.0", "acceleration = 1e300"),
     r"\[driver\]: acceleration = 1e\+300 rad/s\^2 is out of range"),
    ("driver-value-1e308", edit("value = 60.0", "value = 1e308"),
     r"\[driver\]: value = 1e\+308 deg is out of range: .*<= 360000 deg"),
    ("driver-value-string", edit("value = 60.0", 'value = "sixty"'),
     r"\[driver\]: value must be a finite number, got 'sixty'"),
    ("driver-missing-velocity", edit("velocity = 15.0", ""), r"\[driver\]: missing key 'velocity'"),
    ("driver-not-a-joint", edit('joint = "O2"', 'joint = "Z9"'),
     r"\[driver\]: driver joint 'Z9' is not a joint"),
    ("driver-as-array", edit("[driver]\njoint", "driver = 1\n[drivr]\njoint"),
     r"unknown keys \['drivr'\]"),
    ("point-1e300", edit("B = [300, 0]", "B = [1e300, 0]"),
     r"body 'coupler': point 'B' = 1e\+300 mm is out of range"),
    ("point-1e20-mm", edit("B = [300, 0]", "B = [1e20, 0]"),
     r"body 'coupler': point 'B' = 1e\+20 mm is out of range: .*<= 1e\+07 mm"),
    ("point-not-pair", edit("B = [250, 0]", "B = [250]"), r"body 'rocker'.*point 'B'.*pair"),
    ("com-huge", edit("com = [150, 0]", "com = [1e30, 0]"), r"body 'coupler': com = 1e\+30 mm"),
    ("gravity-huge", edit("gravity = [0.0, 0.0]", "gravity = [0.0, -1e10]"),
     r"gravity = -1e\+10 m/s\^2 is out of range"),
    ("gravity-not-pair", edit("gravity = [0.0, 0.0]", "gravity = -9.81"),
     r"gravity must be a pair"),
    ("load-force-huge", lambda t: t + '\n[[loads]]\nbody = "rocker"\nforce = [1e300, 0]\n',
     r"load 0: force = 1e\+300 N is out of range"),
    ("load-torque-nan", lambda t: t + '\n[[loads]]\nbody = "rocker"\ntorque = nan\n',
     r"load 0: torque must be a finite number"),
    ("loads-as-table", lambda t: t + '\n[loads]\nbody = "rocker"\n',
     r"loads must be an array of tables \[\[loads\]\], got a table"),
    ("load-unknown-body", lambda t: t + '\n[[loads]]\nbody = "rokker"\n',
     r"load 0 on body 'rokker': unknown body 'rokker'"),
    ("joint-name-integer", edit('name = "A"', "name = 7"),
     r"joint 7: name must be a non-empty string"),
    ("joint-body-integer", edit('bodies = ["crank", "coupler"]', 'bodies = ["crank", 3]'),
     r"joint 'A': bodies\[1\] must be a non-empty string, got 3"),
    ("joints-not-array", lambda t: 'joints = "O2 A B O4"\n' + t[:t.index("[[joints]]")]
     + t[t.index("[driver]"):], r"joints must be an array of tables \[\[joints\]\]"),
    ("joint-missing-type", edit('type = "revolute"\nbodies = ["crank"', 'bodies = ["crank"'),
     r"joint 'A': missing key 'type'"),
    ("joint-unknown-type", edit('type = "revolute"\nbodies = ["crank"',
                                'type = "cylindrical"\nbodies = ["crank"'),
     r"joint 'A': unknown joint type 'cylindrical'"),
    ("joint-to-itself", edit('bodies = ["crank", "coupler"]', 'bodies = ["crank", "crank"]'),
     r"joint 'A': .*joins body 'crank' to itself|joint 'A': body 'crank' has no point 'A'"),
    ("joint-unknown-point", edit('points = ["A", "A"]', 'points = ["A", "Q"]'),
     r"joint 'A': body 'coupler' has no point 'Q'"),
    ("body-unknown-key", edit("mass = 0.6", "mas = 0.6"),
     r"body 'coupler': unknown keys \['mas'\]"),
    ("top-unknown-key", lambda t: "colour = 1\n" + t, r"unknown keys \['colour'\]"),
    ("name-integer", edit('name = "seed-four-bar"', "name = 4"), r"name must be a string"),
    ("bodies-empty", lambda t: "bodies = {}\n" + t[:t.index("[bodies.")]
     + t[t.index("[[joints]]"):],
     r"\[bodies\] must be a non-empty table"),
    ("prismatic-direction-huge", lambda t: t.replace(
        '[[joints]]\nname = "O4"\ntype = "revolute"\nbodies = ["ground", "rocker"]\n'
        'points = ["O4", "O4"]',
        '[[joints]]\nname = "O4"\ntype = "prismatic"\nguide = "ground"\norigin = "O4"\n'
        'direction = 1e308\nslider = "rocker"\npoint = "O4"'),
     r"joint 'O4': direction = 1e\+308 deg is out of range"),
    ("zero-length-link", edit("B = [300, 0]", "B = [1e-8, 0]"),
     r"body 'coupler': joints 'A' and 'B' are at the same point \(zero link length\)"),
    ("size-below-picometre", lambda t: t.replace('length = "mm"', 'length = "mm"').replace(
        "[400, 0]", "[4e-10, 0]").replace("[100, 0]", "[1e-10, 0]").replace(
        "[300, 0]", "[3e-10, 0]").replace("[250, 0]", "[2.5e-10, 0]"),
     r"the mechanism's size .* is 4e-13 m; it must be at least 1e-12 m"),
    ("gruebler", lambda t: t[:t.rindex("[[joints]]")] + t[t.index("[driver]"):],
     r"3 degrees of freedom by Gruebler's count"),
    ("loops-not-a-list", lambda t: 'loops = "O2 A B O4"\n' + t,
     r"loops must be a list of lists of joint names"),
    ("loops-two-joints", lambda t: 'loops = [["O2", "A"]]\n' + t,
     r"loops entry 1 \['O2', 'A'\]: not a closed cycle of distinct bodies: 2 joints"),
    ("loops-unknown-joint", lambda t: 'loops = [["O2", "A", "X", "O4"]]\n' + t,
     r"loops entry 1 .*: unknown joint 'X'"),
    ("loops-repeated-joint", lambda t: 'loops = [["O2", "A", "A", "O4"]]\n' + t,
     r"loops entry 1 .*: not a closed cycle of distinct bodies: joints \['A'\] appear more"),
    ("loops-skips-a-body", lambda t: 'loops = [["O2", "B", "A", "O4"]]\n' + t,
     r"loops entry 1 .*: not a closed cycle .*joints 'O2' and 'B' do not share exactly one body"),
    ("loops-open", lambda t: 'loops = [["O2", "A", "B"]]\n' + t,
     r"loops entry 1 .*: not a closed cycle .*last joint 'B' .* share no body"),
    ("loops-too-many", lambda t: 'loops = [["O2", "A", "B", "O4"], ["O2", "A", "B", "O4"]]\n' + t,
     r"loops: 2 loops given but the joint graph has 1 independent loops"),
    ("loop-name-integer", lambda t: 'loops = [["O2", "A", 3, "O4"]]\n' + t,
     r"loops entry 1: joint name must be a non-empty string, got 3"),
]


@pytest.mark.parametrize("mutation, message", [r[1:] for r in FILE_ROWS],
                         ids=[r[0] for r in FILE_ROWS])
def test_bad_file(capsys, tmp_path, mutation, message):
    p = tmp_path / "m.toml"
    if isinstance(mutation, bytes):
        p.write_bytes(mutation)
    else:
        bad = mutation(SEED)
        assert bad != SEED
        p.write_text(bad)
    assert_one_line_error(capsys, ["solve", str(p)], message, where=str(p))


# (id, argv, message regex, status): command lines, in-process.  "{tmp}" is a temporary
# folder, "{file}" a file in it, "{ro}" a folder that cannot be written.
ARGV_ROWS = [
    ("no-command", [], r"the following arguments are required: COMMAND"),
    ("unknown-command", ["frobnicate"], r"argument COMMAND: invalid choice: 'frobnicate'"),
    ("solve-no-case", ["solve"], r"the following arguments are required: case"),
    ("unknown-case", ["solve", "no-such-case"], r"no built-in case 'no-such-case'"),
    ("missing-file", ["solve", "{tmp}/nope.toml"], r"nope\.toml: cannot read file: No such file"),
    ("directory-as-file", ["solve", "{tmp}/dir.toml"],
     r"dir\.toml: cannot read file: Is a directory"),
    ("unknown-option", ["solve", "seed-four-bar", "--speed", "3"],
     r"unrecognized arguments: --speed 3"),
    ("omega-nan", ["solve", "seed-four-bar", "--omega", "nan"],
     r"argument --omega: nan is not a finite number"),
    ("omega-inf", ["solve", "seed-four-bar", "--omega", "inf"],
     r"argument --omega: inf is not a finite number"),
    ("omega-minus-inf", ["solve", "seed-four-bar", "--omega=-inf"],
     r"argument --omega: -inf is not a finite number"),
    ("omega-1e200", ["solve", "seed-four-bar", "--omega", "1e200"],
     r"argument --omega: 1e\+200 is out of range: the accepted range is \|x\| <= 1e\+06 rad/s"),
    ("omega-word", ["solve", "seed-four-bar", "--omega", "fast"],
     r"argument --omega: 'fast' is not a number"),
    ("alpha-nan", ["solve", "seed-four-bar", "--alpha", "nan"],
     r"argument --alpha: nan is not a finite number"),
    ("alpha-1e13", ["solve", "seed-four-bar", "--alpha", "1e13"],
     r"argument --alpha: 1e\+13 is out of range: .*<= 1e\+12 rad/s\^2"),
    ("angle-1e308", ["solve", "seed-four-bar", "--angle", "1e308"],
     r"argument --angle: 1e\+308 is out of range: .*<= 360000 deg"),
    ("angle-nan", ["solve", "seed-four-bar", "--angle", "nan"],
     r"argument --angle: nan is not a finite number"),
    ("value-nan", ["solve", "hibbeler-16-30", "--value", "nan"],
     r"argument --value: nan is not a finite number"),
    ("value-1e9", ["solve", "hibbeler-16-30", "--value", "1e9"],
     r"argument --value: 1e\+09 is out of range: .*<= 10000 m"),
    ("angle-on-prismatic", ["solve", "hibbeler-16-30", "--angle", "10"], r"give --value"),
    ("value-on-revolute", ["solve", "seed-four-bar", "--value", "0.1"], r"give --angle"),
    ("cannot-close", ["solve", "hibbeler-16-30", "--value", "0.6"],
     r"cannot close at driver 'guide' = 0\.6 m; feasible input range"),
    ("singular", ["solve", str(HARD / "parallelogram-four-bar.toml"), "--angle", "0"],
     r"singular configuration .* at driver 'O2' = 0 deg"),
    ("points-0", ["sweep", "seed-four-bar", "--points", "0"],
     r"argument --points: 0 is out of range: the accepted range is 2 to 1000000"),
    ("points-1", ["sweep", "seed-four-bar", "--points", "1"],
     r"argument --points: 1 is out of range"),
    ("points-negative", ["sweep", "seed-four-bar", "--points", "-1"],
     r"argument --points: -1 is out of range"),
    ("points-1e9", ["sweep", "seed-four-bar", "--points", "1000000000"],
     r"argument --points: 1000000000 is out of range: the accepted range is 2 to 1000000"),
    ("points-float", ["sweep", "seed-four-bar", "--points", "3.5"],
     r"argument --points: '3\.5' is not an integer"),
    ("csv-folder-under-a-file", ["sweep", "seed-four-bar", "--csv", "{loops}/nodir/f.csv"],
     r"argument --csv: cannot create folder '.*nodir': Not a directory"),
    ("csv-is-folder", ["sweep", "seed-four-bar", "--csv", "{tmp}"],
     r"argument --csv: '.*' is a folder; give a file name"),
    ("csv-read-only-folder", ["sweep", "seed-four-bar", "--csv", "{ro}/f.csv"],
     r"argument --csv: cannot write a file in folder '.*ro'"),
    ("loops-not-a-cycle-sweep", ["sweep", "{loops}"],
     r"loops-not-a-cycle\.toml: loops entry 1 \['O2', 'A'\]: not a closed cycle"),
    ("compare-samples-0", ["compare", "seed-four-bar", "--samples", "0"],
     r"argument --samples: 0 is out of range: the accepted range is 2 to 3600"),
    ("compare-samples-huge", ["compare", "seed-four-bar", "--samples", "100000"],
     r"argument --samples: 100000 is out of range"),
    ("compare-timestep-nan", ["compare", "seed-four-bar", "--timestep", "nan"],
     r"argument --timestep: nan is not a finite number"),
    ("compare-timestep-negative", ["compare", "seed-four-bar", "--timestep", "-1"],
     r"argument --timestep: -1 is out of range: the accepted range is 1e-06 to 0\.1 s"),
    ("compare-timestep-0", ["compare", "seed-four-bar", "--timestep", "0"],
     r"argument --timestep: 0 is out of range"),
    ("compare-revolutions-0", ["compare", "seed-four-bar", "--revolutions", "0"],
     r"argument --revolutions: 0 is out of range: the accepted range is 1 to 1000"),
    ("compare-engine-unknown", ["compare", "seed-four-bar", "--engine", "gazebo"],
     r"argument --engine: invalid choice: 'gazebo'"),
    ("compare-mode-unknown", ["compare", "seed-four-bar", "--mode", "fast"],
     r"argument --mode: invalid choice: 'fast'"),
    ("compare-nanometre-linkage", ["compare", "{tiny}", "--engine", "mujoco"],
     r"mechanism 'seed-four-bar' \(size 4e-09 m\): MuJoCo cannot compile its model"),
    ("report-workers-negative", ["report", "--workers", "-1"],
     r"argument --workers: -1 is out of range: the accepted range is 1 to 64"),
    ("report-workers-0", ["report", "--workers", "0"], r"argument --workers: 0 is out of range"),
    ("report-out-read-only", ["report", "--out", "{ro}"],
     r"argument --out: cannot write files in folder '.*ro'"),
    ("report-out-under-read-only", ["report", "--out", "{ro}/sub"],
     r"argument --out: cannot create folder '.*ro/sub'"),
    ("report-out-is-file", ["report", "--out", "{file}"],
     r"argument --out: '.*f\.txt' exists and is not a folder"),
    ("report-dask-malformed", ["report", "--dask", "nonsense"],
     r"argument --dask: 'nonsense' is not a scheduler address; expected HOST:PORT"),
    ("models-out-read-only", ["models", "--out", "{ro}"],
     r"argument --out: cannot write files in folder '.*ro'"),
    ("models-out-is-file", ["models", "--out", "{file}"],
     r"argument --out: '.*f\.txt' exists and is not a folder"),
    ("report-cases-missing-file", ["report", "--cases", "sub/none.toml"],
     r"argument --cases: no such file 'sub/none\.toml'"),
    ("report-cases-unknown", ["report", "--cases", "four-bar"],
     r"argument --cases: no built-in case 'four-bar'"),
]


@pytest.mark.parametrize("argv, message", [r[1:] for r in ARGV_ROWS],
                         ids=[r[0] for r in ARGV_ROWS])
def test_bad_command_line(capsys, tmp_path, read_only_dir, argv, message):
    (tmp_path / "dir.toml").mkdir()
    (tmp_path / "f.txt").write_text("x")
    (tmp_path / "loops-not-a-cycle.toml").write_text(LOOPS_NOT_A_CYCLE)
    (tmp_path / "tiny.toml").write_text(NANOMETRE)
    subs = {"{tmp}": str(tmp_path), "{file}": str(tmp_path / "f.txt"),
            "{loops}": str(tmp_path / "loops-not-a-cycle.toml"),
            "{tiny}": str(tmp_path / "tiny.toml")}
    if any("{ro}" in a for a in argv):
        subs["{ro}"] = str(read_only_dir())
    argv = [_sub(a, subs) for a in argv]
    assert_one_line_error(capsys, argv, message)


def test_enough_distinct_bad_inputs():
    """Issue 8 asks for at least 60 distinct bad inputs."""
    ids = [r[0] for r in FILE_ROWS] + [r[0] for r in ARGV_ROWS]
    assert len(set(ids)) == len(ids) >= 60


# ----------------------------------------------------------------------------- helpers
def _sub(a: str, subs: dict) -> str:
    for k, v in subs.items():
        a = a.replace(k, v)
    return a


def assert_one_line_error(capsys, argv, message, status=2, where=None):
    code = main(argv)
    cap = capsys.readouterr()
    err = cap.err
    assert code == status, (code, err)
    assert "Traceback" not in err
    assert err.endswith("\n") and err.count("\n") == 1, f"not one line: {err!r}"
    assert err.startswith("xval: error: "), err
    assert re.search(message, err), f"{message!r} not in {err!r}"
    if where is not None:
        assert where in err, "the error names the file"
    assert cap.out == "", "nothing on standard output"


@pytest.fixture
def read_only_dir(tmp_path):
    """A folder nobody may write into: mode 555, and for root (who ignores modes) the
    immutable attribute.  Skips where neither works."""
    made = []

    def make() -> Path:
        d = tmp_path / "ro"
        d.mkdir()
        d.chmod(0o555)
        made.append(d)
        if _writable(d) and shutil.which("chattr"):
            subprocess.run(["chattr", "+i", str(d)], capture_output=True)
        if _writable(d):
            pytest.skip("cannot make a read-only folder here (root without chattr)")
        return d

    yield make
    for d in made:
        if shutil.which("chattr"):
            subprocess.run(["chattr", "-i", str(d)], capture_output=True)
        d.chmod(0o755)


def _writable(d: Path) -> bool:
    try:
        (d / ".probe").write_text("")
    except OSError:
        return False
    (d / ".probe").unlink()
    return True


# ----------------------------------------------------------------------------- through a pipe
def _xval(cmd: str, cwd=None) -> subprocess.CompletedProcess:
    """``cmd`` in bash with xval from this interpreter; PIPESTATUS of the first command
    is printed last on standard output."""
    xval = f"{sys.executable} -m reports.cli.xval"
    script = cmd.replace("xval", xval) + '; echo "rc=${PIPESTATUS[0]}"'
    return subprocess.run(["bash", "-c", script], capture_output=True, text=True,
                          cwd=cwd or os.getcwd(), timeout=120)


@pytest.mark.parametrize("cmd", [
    "xval sweep six-bar --points 20000 | true",
    "xval sweep seed-four-bar --points 20000 --csv - | true",
    "xval solve quick-return --json | true",
    "xval sweep seed-four-bar --points 300000 --csv - | true",  # streamed in blocks
])
def test_closed_pipe_ends_quietly(cmd):
    """The reader exits before xval writes: no BrokenPipeError, status 141 (SIGPIPE's)."""
    r = _xval(cmd)
    assert r.stderr == "", r.stderr
    assert r.stdout.strip().endswith("rc=141")


def test_pipe_into_head_keeps_the_first_lines():
    r = _xval("xval sweep seed-four-bar --points 50000 --csv - | head -2")
    assert r.stderr == "", r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith("input [deg],") and len(lines) == 3  # two CSV lines, then rc
    assert lines[-1] in ("rc=141", "rc=0")


def test_csv_to_standard_output(capsys):
    """``--csv -`` writes the table to standard output and the summary to standard error
    (no file named '-')."""
    code = main(["sweep", "seed-slider-crank", "--points", "12", "--csv", "-"])
    cap = capsys.readouterr()
    assert code == 0 and not Path("-").exists()
    rows = cap.out.splitlines()
    assert rows[0].startswith("input [deg],") and len(rows) == 13
    assert "seed-slider-crank: 12 points" in cap.err


def test_one_line_error_through_the_console_script(tmp_path):
    """The same one line and status 2 from a real process (no interpreter noise)."""
    p = tmp_path / "u.toml"
    p.write_bytes("name = 'x'\n".encode("utf-16"))
    r = _xval(f"xval solve {p}")
    assert r.stderr.count("\n") == 1 and "UTF-16" in r.stderr
    assert r.stdout.strip() == "rc=2"


# ----------------------------------------------------------------------------- report names
NASTY = "a|b*c_d<e>[f](g)`h`#1. &amp; ~i~ \\j"


def test_report_markdown_shows_names_literally(tmp_path):
    """A case name with Markdown's special characters renders as itself in report.md,
    as it does in index.html (rendered here by CommonMark with tables)."""
    import html as _html

    import pandas as pd
    from markdown_it import MarkdownIt

    from reports.report.build import Document
    doc = Document(tmp_path)
    doc.h(2, NASTY)
    doc.p(NASTY)
    doc.p("1. not a list: " + NASTY)
    doc.table(pd.DataFrame({"case": [NASTY], "x": [1.5]}), "t", caption=NASTY)
    rendered = MarkdownIt("commonmark").enable("table").render(doc.markdown("t"))
    literal = _html.escape(NASTY, quote=False)
    assert f"<h3>{literal}</h3>" in rendered
    assert f"<p>{literal}</p>" in rendered and "<ol" not in rendered
    assert f"<td>{literal}</td>" in rendered and "<td>1.5</td>" in rendered
    assert f"<em>{literal}</em>" in rendered  # the caption, in italics as before


def test_report_image_of_a_case_given_as_a_path(tmp_path):
    """--cases sub/f.toml: the case's figures are written under a file-safe name."""
    from reports.report.build import Document
    doc = Document(tmp_path)
    doc.image(b"\x89PNG", "sub/f.toml-angle", "sub/f.toml: angle")
    md = doc.markdown("t")
    rel = next(line for line in md.splitlines() if line.startswith("![")).split("](")[1][:-1]
    assert (tmp_path / rel).is_file() and "/" not in rel[len("img/"):]
