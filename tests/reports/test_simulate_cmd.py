"""``xval simulate``: bad free-motion input gets one line naming the file and the element,
status 2; a good run prints its table and events, status 0."""

from __future__ import annotations

import math
import re

import pytest

from tests.reports.cli_run import run
from tests.reports.free_inputs import MOTION
from tests.reports.free_inputs import seed_under_gravity as _seed


def edit(old: str, new: str):
    def f(text: str) -> str:
        assert old in text, old
        return text.replace(old, new, 1)
    return f


BAD = [
    ("spring-one-body", edit('bodies = ["coupler", "ground"]\npoints = ["B", "O2"]',
                             'bodies = ["coupler", "coupler"]\npoints = ["A", "B"]'),
     r"spring 0: attached to body 'coupler' at both ends"),
    ("negative-stiffness", edit("stiffness = 30.0", "stiffness = -30.0"),
     r"spring 0: stiffness must be >= 0"),
    ("negative-damping", edit("coefficient = 0.01", "coefficient = -0.01"),
     r"damper 0: coefficient must be >= 0"),
    ("table-not-increasing", edit("[[0.0, 0.0], [1.0, 0.3]]",
                                  "[[0.0, 0.0], [0.5, 1.0], [0.5, 2.0], [1.0, 0.3]]"),
     r"motor 0: table times must be strictly increasing: row 2"),
    ("table-ends-early", edit("[[0.0, 0.0], [1.0, 0.3]]", "[[0.0, 0.0], [0.5, 0.3]]"),
     r"motor 0: the table covers t = 0 to 0.5 s; it must cover the run, 0 to 1 s"),
    ("table-not-pairs", edit("[[0.0, 0.0], [1.0, 0.3]]", "[0.0, 1.0]"),
     r"motor 0: table must be an array of \[time s, effort\] pairs"),
    ("motor-effort-and-table", edit('table = [[0.0, 0.0], [1.0, 0.3]]',
                                    'table = [[0.0, 0.0], [1.0, 0.3]]\neffort = 1.0'),
     r"motor 0: a motor needs exactly one of effort"),
    ("duration-huge", edit("duration = 1.0", "duration = 1e5"),
     r"\[motion\]: duration = 100000 s is out of range"),
    ("duration-zero", edit("duration = 1.0", "duration = 0.0"),
     r"\[motion\]: duration = 0 s is out of range: the accepted range is 0 < duration"),
    ("samples-huge", edit("duration = 1.0", "duration = 1.0\nsamples = 2000000"),
     r"\[motion\]: samples = 2000000 is out of range"),
    ("spring-unknown-body", edit('["coupler", "ground"]', '["nope", "ground"]'),
     r"spring 0: unknown body 'nope'"),
    ("spring-unknown-point", edit('points = ["B", "O2"]', 'points = ["Z", "O2"]'),
     r"spring 0: body 'coupler' has no point 'Z'"),
    ("motion-unknown-joint", edit('[motion]\njoint = "O2"', '[motion]\njoint = "Q"'),
     r"\[motion\]: unknown joint 'Q'"),
    ("motor-unknown-joint", edit('joint = "O2"\ntable', 'joint = "X9"\ntable'),
     r"motor 0: unknown joint 'X9'"),
    ("motion-unknown-key", edit("rate = 0.0", "rate = 0.0\nspeed = 3.0"),
     r"\[motion\]: unknown keys \['speed'\]"),
    ("torsional-free-length", edit('joint = "O4"\ncoefficient = 0.01',
                                   'joint = "O4"\ncoefficient = 0.01\n\n[[springs]]\n'
                                   'joint = "O4"\nstiffness = 1.0\nfree_length = 3.0'),
     r"spring 1: a revolute joint's spring has free_angle"),
    ("unreachable-start", edit('[motion]\njoint = "O2"\nvalue = 60.0',
                                   '[motion]\njoint = "O4"\nvalue = 170.0'),
     r"(cannot|not) .*assembl|loops cannot close|no assembly"),
]


@pytest.mark.parametrize("name, change, message", BAD, ids=[b[0] for b in BAD])
def test_bad_free_motion_input_one_line_status_2(tmp_path, capsys, name, change, message):
    f = tmp_path / f"{name}.toml"
    f.write_text(change(_seed() + MOTION))
    code, out = run("simulate", str(f), "--duration", "0.05")
    err = capsys.readouterr().err
    assert code == 2, (out, err)
    assert err.count("\n") == 1 and err.startswith("xval: error: "), err
    assert re.search(message, err), err


def test_springs_without_motion(tmp_path, capsys):
    f = tmp_path / "nomotion.toml"
    f.write_text(_seed() + MOTION[MOTION.index("[[springs]]"):])
    code, _ = run("simulate", str(f))
    err = capsys.readouterr().err
    assert code == 2 and "act in free motion only" in err and err.count("\n") == 1


def test_no_motion_table_in_a_file(tmp_path, capsys):
    """A user's file without [motion] is not guessed at: one line, status 2."""
    f = tmp_path / "driven.toml"
    f.write_text(_seed())
    code, _ = run("simulate", str(f))
    err = capsys.readouterr().err
    assert code == 2 and "no [motion] table" in err and err.count("\n") == 1


def test_builtin_case_without_motion_is_released_as_the_report_does():
    """``xval simulate seed-four-bar`` (no [motion]) integrates the report's released
    seed four-bar: the driver's joint O2 at its reference 60 deg, at rest, under
    9.81 m/s^2, and says so; the trajectory starts there with KE 0."""
    import json

    from reports.comparison.free_cases import free_case
    code, text = run("simulate", "seed-four-bar", "--duration", "0.1", "--json")
    out = json.loads(text)
    assert code == 0 and out["case"] == free_case("seed-four-bar").name
    rel = out["released"]
    assert rel["joint"] == "O2" and rel["rate"] == 0.0 and rel["duration_s"] == 0.1
    assert rel["value"] == pytest.approx(math.radians(60.0), rel=1e-15)
    assert rel["gravity_m_s2"] == [0.0, -9.81]
    smp = out["samples"]
    assert smp["O2_rad"][0] == pytest.approx(math.radians(60.0), rel=1e-12)
    assert smp["kinetic_J"][0] == 0.0
    code, text = run("simulate", "seed-four-bar", "--duration", "0.1", "--samples", "3")
    assert code == 0 and text.startswith("seed-four-bar has no [motion] table: released")
    assert "at its driver's reference value 60 deg, at rest, under 9.81 m/s^2 in -y, " \
           "0.1 s" in text


def test_builtin_case_released_in_an_engine():
    import json
    code, text = run("simulate", "seed-four-bar", "--engine", "mujoco", "--duration",
                     "0.05", "--samples", "11", "--json")
    out = json.loads(text)
    assert code == 0 and out["released"]["joint"] == "O2"
    assert out["verdicts"][0]["engine"] == "mujoco" and out["verdicts"][0]["verdict"] == "pass"
    code, text = run("simulate", "seed-four-bar", "--engine", "mujoco", "--duration",
                     "0.05", "--samples", "11")
    assert code == 0 and text.splitlines()[0].startswith("seed-four-bar has no [motion]")
    assert "== seed-four-bar-released / mujoco (free motion, 0.05 s): PASS" in text


@pytest.mark.parametrize("case", ["hibbeler-16-121", "hibbeler-16-30", "hibbeler-16-31",
                                  "hibbeler-two-inclines"])
@pytest.mark.parametrize("engine", [[], ["--engine", "all"]])
def test_massless_builtin_case_cannot_be_released(capsys, case, engine):
    code, out = run("simulate", case, *engine)
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert f"case {case!r} cannot be released under gravity: no moving body has mass" in err


def test_massless_linkage_has_no_inertia(tmp_path, capsys):
    text = re.sub(r"mass = [0-9.]+", "mass = 0.0", _seed() + MOTION)
    text = re.sub(r"inertia = [0-9.e-]+", "inertia = 0.0", text)
    f = tmp_path / "massless.toml"
    f.write_text(text)
    code, _ = run("simulate", str(f), "--duration", "0.05")
    err = capsys.readouterr().err
    assert code == 2 and "no inertia in the moving coordinate" in err, err


@pytest.mark.parametrize("argv, message", [
    (["--duration", "0"], r"argument --duration: 0 is out of range"),
    (["--samples", "1"], r"argument --samples: 1 is out of range"),
    (["--duration", "nan"], r"argument --duration: nan is not a finite number"),
    (["--json", "--csv", "-"], r"--json and --csv - both write to standard output"),
])
def test_bad_options(capsys, argv, message):
    code, _ = run("simulate", "iftomm-a01-pendulum", *argv)
    err = capsys.readouterr().err
    assert code == 2 and re.search(message, err) and err.count("\n") == 1, err


def test_simulate_prints_table_and_events(tmp_path, capsys):
    csv = tmp_path / "out.csv"
    code, out = run("simulate", "iftomm-a01-pendulum", "--duration", "1.3", "--samples", "5",
                    "--csv", str(csv))
    assert code == 0
    assert "work-energy balance" in out and "turn" in out
    assert csv.read_text().count("\n") == 6  # header + 5 samples


def _crash(*_a, **_k):
    raise IndexError("too many indices for array")


def test_engine_all_one_crash_is_a_failed_verdict_and_a_summary_closes(monkeypatch):
    """``simulate --engine all``: one engine's exception ended the whole command; and 99
    lines of verdicts ended without a summary.  Now the crashed engine is a FAIL with its
    one-line cause, every other engine's verdict is printed, and one line closes the
    output with the counts and the exit status."""
    from sim_models.engines.pybullet.free import PybulletFreeSession
    monkeypatch.setattr(PybulletFreeSession, "advance", _crash)
    monkeypatch.setattr("reports.cli.simulate_engines.free_engine_names",
                        lambda: ("mujoco", "pybullet"))
    code, out = run("simulate", "iftomm-a01-pendulum", "--duration", "0.2", "--samples", "11",
                    "--engine", "all")
    assert code == 1
    assert "/ mujoco (free motion, 0.2 s): PASS" in out
    assert "/ pybullet (free motion, 0.2 s): FAIL" in out
    assert "engine crashed: IndexError: too many indices for array" in out
    last = out.strip().splitlines()[-1]
    assert last == ("simulate iftomm-a01-pendulum: 1 of 2 engines pass, 1 failed (pybullet); "
                    "exit status 1")


def test_simulate_labels_and_exits_as_the_report_does(monkeypatch):
    """The report calls PyBullet's released seed four-bar over 1 s a known engine limit
    and exits 0; ``simulate`` exited 1 on the same run.  Both now use one rule
    (reports.comparison.free_limits.label)."""
    monkeypatch.setattr("reports.cli.simulate_engines.free_engine_names",
                        lambda: ("mujoco", "pybullet"))
    code, out = run("simulate", "seed-four-bar", "--duration", "1", "--samples", "101",
                    "--engine", "all")
    assert "/ pybullet (free motion, 1 s): KNOWN LIMIT" in out, out
    assert "known engine limit (reports/comparison/free_limits.py" in out
    assert out.strip().splitlines()[-1] == (
        "simulate seed-four-bar-released: 1 of 2 engines pass, 1 known engine limit "
        "(pybullet; not counted); exit status 0")
    assert code == 0


def test_sampling_stops_at_the_wall_limit_with_one_line(capsys):
    """Issue 30's shortfall: ``--samples 1000000`` (the top of the range) sampled for
    minutes past ``--wall-limit``.  A 0.05 s run integrates in ~0.1 s, and its 1e6
    samples take 8 s on the shared 2-core machine: the limit of 1 s now ends the sampling
    with the integration's message form (file, limit, samples done of N), status 2."""
    code, out = run("simulate", "seed-four-bar", "--duration", "0.05", "--samples",
                    "1000000", "--wall-limit", "1")
    err = capsys.readouterr().err
    assert code == 2 and out == "", (out, err)
    assert err.count("\n") == 1 and err.startswith("xval: error: "), err
    assert re.search(r"seed-four-bar\.toml: mechanism 'seed-four-bar-released': sampling the "
                     r"exact trajectory reached the wall-clock limit of 1 s at [\d,]+ of "
                     r"1,000,000 samples .*raise --wall-limit or lower --samples", err), err


def test_motor_table_without_rows_is_refused_not_run_as_no_motor(tmp_path, capsys):
    """``table = []`` ran as no motor at all; one line naming the file, the motor and the
    key now, status 2 (one row, as before, the same)."""
    for rows, n in (("[]", 0), ("[[0.0, 0.3]]", 1)):
        f = tmp_path / f"rows{n}.toml"
        f.write_text(edit("[[0.0, 0.0], [1.0, 0.3]]", rows)(_seed() + MOTION))
        code, _ = run("simulate", str(f), "--duration", "0.05")
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1, err
        assert f"rows{n}.toml: motor 0: table has {n} row(s): a motor table needs at least " \
               "2 rows" in err, err


def test_samples_range_shrinks_with_the_joints_at_every_door(tmp_path, capsys):
    """A 121-joint chain (A02) at 1e5 samples held 1.1 GB (at 1e6: ~11 GB, ~35 GB as
    JSON); its table's values are capped (MAX_SAMPLE_VALUES), the same range from the
    option and from the file, one line each, status 2; the four-bar keeps 1e6."""
    from analytic import load_case
    from analytic.cases import case_path
    from analytic.motion_spec import MAX_SAMPLE_VALUES, MAX_SAMPLES, max_samples
    top = MAX_SAMPLE_VALUES // (3 * 121 + 9)
    rng = rf"the accepted range is 2 to {top} for 121 joints \(372 columns a sample"
    code, _ = run("simulate", "iftomm-a02-n-four-bar", "--samples", str(top + 1))
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert re.search(rf"argument --samples: {top + 1} is out of range: {rng}", err), err
    f = tmp_path / "a02.toml"
    f.write_text(case_path("iftomm-a02-n-four-bar").read_text().replace(
        "samples = 401", f"samples = {top + 1}"))
    code, _ = run("simulate", str(f))
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert re.search(rf"a02.toml: \[motion\]: samples = {top + 1} is out of range: {rng}",
                     err), err
    assert max_samples(load_case("seed-four-bar")) == MAX_SAMPLES
