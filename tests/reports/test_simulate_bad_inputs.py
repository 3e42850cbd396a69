"""``xval simulate`` on bad free-motion input: every case is one line on standard error,
``xval: error: ...``, naming the file (or the option) and the key, body or joint at fault,
exit status 2, no traceback (issue 20, item 8).

The cases are new beside those of ``test_simulate_cmd.py`` (which keeps its own); each
is written to ``tmp_path`` from a built-in description and an edit, so the table says
exactly what is wrong.  The expected text is the part of the message a user needs (the
element and the value), not the whole sentence.
"""

from __future__ import annotations

import re

import pytest

from analytic.cases import case_path

from .cli_run import run
from .free_inputs import MOTION, seed_under_gravity

#: The seed slider-crank released from 30 deg (its crank massless, as in the notes).
SLIDER_MOTION = '\n[motion]\njoint = "A"\nvalue = 30.0\nrate = 0.0\nduration = 1.0\n'
SHORT = ("--duration", "0.05")


def four_bar() -> str:
    return seed_under_gravity() + MOTION


def slider_crank() -> str:
    return case_path("seed-slider-crank").read_text() + SLIDER_MOTION


def edit(old: str, new: str, base=four_bar):
    def f() -> str:
        text = base()
        assert old in text, old
        return text.replace(old, new, 1)
    return f


def prepend(line: str, old: str, base=four_bar):
    """``line`` at the top of the file (a top-level key), ``old`` removed."""
    def f() -> str:
        text = base()
        assert old in text, old
        return line + "\n" + text.replace(old, "", 1)
    return f


def piston_only() -> str:
    """The slider-crank with its rod massless too: only the piston has mass, and it
    stands still at the dead centre, where M(q) = 0 (the load of 500 N drives it there)."""
    text = slider_crank().replace("mass = 3.0", "mass = 0.0").replace("inertia = 0.1",
                                                                     "inertia = 0.0")
    return text.replace('rate = 0.0\nduration = 1.0', 'rate = -5.0\nduration = 1.0')


_DAMPER = '[[dampers]]\njoint = "O4"\ncoefficient = 0.01'
_TABLE = "[[0.0, 0.0], [1.0, 0.3]]"
_START = '[motion]\njoint = "O2"\nvalue = 60.0'

#: (id, description, extra arguments, what the line must say).
BAD = [
    # -- inertia: M(q) = 0 somewhere, the bodies named
    ("massless-all", lambda: re.sub(r"inertia = [0-9.e-]+", "inertia = 0.0",
                                    re.sub(r"mass = [0-9.]+", "mass = 0.0", four_bar())),
     SHORT, r"no inertia in the moving coordinate at joint 'O2' = 60 deg.*is 0.*"
            r"no moving body has mass: \['crank', 'coupler', 'rocker'\]"),
    ("inertia-zero-at-dead-centre", piston_only, (),
     r"no inertia in the moving coordinate at joint 'A' = .* deg \(t = .* s\).*"
     r"bodies with mass \['piston'\] stand still there, massless bodies: \['crank', 'rod'\]"),
    ("mass-missing", edit("mass = 0.6\ncom = [150, 0]\ninertia = 4.5e-3", "com = [150, 0]"),
     SHORT, r"needs the mass and inertia of every moving body; missing for \['coupler'\]"),
    # -- force elements joining one body to itself, negative or non-finite constants
    ("damper-one-body", edit(_DAMPER, '[[dampers]]\nbodies = ["rocker", "rocker"]\n'
                                      'points = ["O4", "B"]\ncoefficient = 0.01'),
     SHORT, r"damper 0: attached to body 'rocker' at both ends"),
    ("torsional-stiffness-negative", edit("[[dampers]]", '[[springs]]\njoint = "O4"\n'
                                          'stiffness = -2.0\nfree_angle = 0.0\n\n[[dampers]]'),
     SHORT, r"spring 1: stiffness must be >= 0 .*got -2"),
    ("point-damper-negative", edit(_DAMPER, '[[dampers]]\nbodies = ["rocker", "ground"]\n'
                                            'points = ["B", "O2"]\ncoefficient = -0.5'),
     SHORT, r"damper 0: coefficient must be >= 0 .*got -0.5"),
    ("stiffness-inf", edit("stiffness = 30.0", "stiffness = inf"),
     SHORT, r"spring 0: stiffness must be a finite number, got inf"),
    ("free-length-negative", edit("free_length = 250.0", "free_length = -250.0"),
     SHORT, r"spring 0: free_length must be >= 0 m, got -0.25"),
    ("spring-free-length-missing", edit("free_length = 250.0\n", ""),
     SHORT, r"spring 0: missing key 'free_length'"),
    ("spring-joint-and-bodies", edit("stiffness = 30.0", 'stiffness = 30.0\njoint = "O4"'),
     SHORT, r"spring 0: give either joint = name or bodies/points, not both"),
    ("spring-unknown-joint", edit("[[dampers]]", '[[springs]]\njoint = "Z"\nstiffness = 2.0\n'
                                                 '\n[[dampers]]'),
     SHORT, r"spring 1: unknown joint 'Z'; joints are \['O2', 'A', 'B', 'O4'\]"),
    ("spring-unknown-key", edit("stiffness = 30.0", "stiffness = 30.0\nstifness = 3.0"),
     SHORT, r"spring 0: unknown keys \['stifness'\]"),
    ("damper-unknown-body", edit(_DAMPER, '[[dampers]]\nbodies = ["rocker", "moon"]\n'
                                          'points = ["B", "O2"]\ncoefficient = 0.5'),
     SHORT, r"damper 0: unknown body 'moon'; bodies are \['ground', 'crank', 'coupler', "
            r"'rocker'\]"),
    ("damper-with-stiffness", edit("coefficient = 0.01", "coefficient = 0.01\nstiffness = 3.0"),
     SHORT, r"damper 0: unknown keys \['stiffness'\]"),
    ("slider-spring-free-angle", edit(SLIDER_MOTION, SLIDER_MOTION + '\n[[springs]]\njoint = '
                                      '"slide"\nstiffness = 10.0\nfree_angle = 3.0\n',
                                      slider_crank),
     SHORT, r"spring 0: a prismatic joint's spring has free_length, not free_angle"),
    ("springs-not-an-array", prepend("springs = 3", '[[springs]]\nbodies = ["coupler", '
                                     '"ground"]\npoints = ["B", "O2"]\nstiffness = 30.0\n'
                                     'free_length = 250.0\n'),
     SHORT, r"springs must be an array of tables \[\[springs\]\], got an integer"),
    # -- motors: tables that do not cover the run, efforts not finite or out of range
    ("table-starts-late", edit(_TABLE, "[[0.1, 0.0], [1.0, 0.3]]"),
     SHORT, r"motor 0: the table covers t = 0.1 to 1 s; it must cover the run, 0 to 1 s"),
    ("table-one-row", edit(_TABLE, "[[0.0, 0.3]]"),
     SHORT, r"motor 0: table has 1 row\(s\): a motor table needs at least 2 rows"),
    ("table-effort-nan", edit(_TABLE, "[[0.0, nan], [1.0, 0.3]]"),
     SHORT, r"motor 0: table row 0 effort must be a finite number, got nan"),
    ("table-shorter-than-duration-option", four_bar, ("--duration", "2"),
     r"motor 0: the table covers t = 0 to 1 s; it must cover the run, 0 to 2 s"),
    ("effort-nan", edit(f"table = {_TABLE}", "effort = nan"),
     SHORT, r"motor 0: effort must be a finite number, got nan"),
    ("effort-too-large", edit(f"table = {_TABLE}", "effort = 1e13"),
     SHORT, r"motor 0: effort = 1e\+13 is out of range: the accepted range is \|effort\| <= "
            r"1e\+12"),
    ("motor-unknown-key", edit('joint = "O2"\ntable', 'joint = "O2"\nspeed = 2\ntable'),
     SHORT, r"motor 0: unknown keys \['speed'\]"),
    # -- the initial state
    ("value-inf", edit("value = 60.0\nrate", "value = inf\nrate"),
     SHORT, r"\[motion\]: value must be a finite number, got inf"),
    ("value-not-a-number", edit("value = 60.0\nrate", 'value = "sixty"\nrate'),
     SHORT, r"\[motion\]: value must be a finite number, got 'sixty'"),
    ("value-missing", edit("value = 60.0\nrate", "rate"),
     SHORT, r"\[motion\]: missing key 'value'"),
    ("rate-nan", edit("rate = 0.0\nduration", "rate = nan\nduration"),
     SHORT, r"\[motion\]: rate must be a finite number, got nan"),
    ("rate-too-large", edit("rate = 0.0\nduration", "rate = 1e30\nduration"),
     SHORT, r"\[motion\]: rate = 1e\+30 rad/s is out of range"),
    ("rate-unit-unknown", edit("rate = 0.0\nduration", 'rate = 0.0\nrate_unit = "furlong"\n'
                                                       'duration'),
     SHORT, r"\[motion\]: rate_unit 'furlong' is not a unit"),
    ("motion-joint-empty", edit('[motion]\njoint = "O2"', '[motion]\njoint = ""'),
     SHORT, r"\[motion\]: joint must be a non-empty string"),
    ("motion-not-a-table", prepend("motion = 3", '[motion]\njoint = "O2"\nvalue = 60.0\n'
                                   'rate = 0.0\nduration = 1.0\n'),
     SHORT, r"\[motion\]: expected a table, got an integer"),
    ("start-unreachable-rocker", edit(_START, '[motion]\njoint = "O4"\nvalue = 170.0'),
     SHORT, r"\[motion\]: the initial state cannot be reached: the loops cannot close at "
            r"joint 'O4' = 170 deg; the feasible range\(s\) of joint 'O4': \[108.21 deg"),
    ("start-unreachable-coupler-angle", edit(_START, '[motion]\njoint = "B"\nvalue = 0.0'),
     SHORT, r"\[motion\]: the initial state cannot be reached: the loops cannot close at "
            r"joint 'B' = 0 deg"),
    ("start-unreachable-slider", edit(SLIDER_MOTION, SLIDER_MOTION.replace(
        'joint = "A"\nvalue = 30.0', 'joint = "slide"\nvalue = 50.0'), slider_crank),
     SHORT, r"\[motion\]: the initial state cannot be reached: the loops cannot close at "
            r"joint 'slide' = 0.5 m; the feasible range\(s\) of joint 'slide': \[0.1 m, 0.3 m\]"),
    # -- duration and samples beyond their stated limits
    ("duration-negative", edit("duration = 1.0", "duration = -1.0"),
     SHORT, r"\[motion\]: duration = -1 s is out of range: the accepted range is "
     r"0 < duration <= 10000 s"),
    ("duration-zero", edit("duration = 1.0", "duration = 0.0"),
     SHORT, r"\[motion\]: duration = 0 s is out of range: the accepted range is "
     r"0 < duration <= 10000 s"),
    ("duration-nan", edit("duration = 1.0", "duration = nan"),
     (), r"\[motion\]: duration must be a finite number, got nan"),
    ("duration-missing", edit("duration = 1.0\n", ""),
     SHORT, r"\[motion\]: missing key 'duration'"),
    ("samples-one", edit("duration = 1.0", "duration = 1.0\nsamples = 1"),
     SHORT, r"\[motion\]: samples = 1 is out of range: the accepted range is 2 to 1000000"),
    ("samples-not-integer", edit("duration = 1.0", "duration = 1.0\nsamples = 10.5"),
     SHORT, r"\[motion\]: samples must be an integer, got 10.5"),
    ("option-duration-too-long", four_bar, ("--duration", "1e5"),
     r"argument --duration: 100000 is out of range: the accepted range is 1e-06 to 10000 s"),
    ("option-duration-inf", four_bar, ("--duration", "inf"),
     r"argument --duration: inf is not a finite number"),
    ("option-samples-too-many", four_bar, ("--samples", "2000000"),
     r"argument --samples: 2000000 is out of range: the accepted range is 2 to 1000000"),
    ("option-samples-not-integer", four_bar, ("--samples", "many"),
     r"argument --samples: 'many' is not an integer"),
    ("option-wall-limit-zero", four_bar, ("--engine", "mujoco", "--wall-limit", "0"),
     r"argument --wall-limit: 0 is out of range: the accepted range is above 0 and at most "
     r"86400 s"),
    ("option-wall-limit-inf", four_bar, ("--engine", "mujoco", "--wall-limit", "inf"),
     r"argument --wall-limit: inf is not a finite number"),
]


@pytest.mark.parametrize("name, text, argv, message", BAD, ids=[b[0] for b in BAD])
def test_bad_free_motion_input(tmp_path, capsys, name, text, argv, message):
    f = tmp_path / f"{name}.toml"
    f.write_text(text())
    code, out = run("simulate", str(f), *argv)
    err = capsys.readouterr().err
    assert code == 2, (out, err)
    assert err.startswith("xval: error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err + out
    assert not out.strip(), out  # nothing tabulated before the refusal
    if not name.startswith("option-"):
        assert str(f) in err, err  # the file is named (an option's error names the option)
    assert re.search(message, err), err


def test_at_least_15_cases():
    """Issue 20's Must show: at least 15 new bad inputs."""
    assert len(BAD) >= 15 and len({b[0] for b in BAD}) == len(BAD)


@pytest.mark.parametrize("base", [four_bar, slider_crank])
def test_the_base_descriptions_run(tmp_path, base):
    """The edits above break a description that is otherwise valid."""
    f = tmp_path / "base.toml"
    f.write_text(base())
    code, out = run("simulate", str(f), *SHORT, "--samples", "3")
    assert code == 0 and "work-energy balance" in out, out
