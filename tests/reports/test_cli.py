"""The xval command line: JSON contents, tables, CSV sweep, and errors as one line + exit 2."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from analytic import case_names
from reports.cli.xval import main


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_cases_lists_every_builtin(capsys):
    code, out, _ = run(capsys, "cases")
    assert code == 0
    for name in ("seed-slider-crank", "seed-four-bar", "hibbeler-two-inclines", "hibbeler-16-121",
                 "hibbeler-16-30", "hibbeler-16-31", "offset-slider-crank",
                 "inverted-slider-crank", "quick-return", "six-bar"):
        assert name in out
    assert len(case_names()) == 10


def test_solve_json_s4(capsys):
    """REFERENCE S4 and the ENGINE_NOTES forces through the JSON interface (SI)."""
    code, out, _ = run(capsys, "solve", "seed-four-bar", "--angle", "60", "--omega", "15",
                       "--json")
    assert code == 0
    d = json.loads(out)
    assert d["bodies"]["coupler"]["angle_deg"] == pytest.approx(29.379, abs=5e-4)
    assert d["bodies"]["rocker"]["alpha"] == pytest.approx(95.5036, abs=5e-5)
    assert d["joints"]["B"]["force"] == pytest.approx([3.8305, 1.1213], abs=5e-5)
    assert d["drive"]["torque"] == pytest.approx(0.67334, abs=5e-6)
    assert d["drive"]["power"] == pytest.approx(0.67334 * 15, abs=1e-4)


def test_solve_json_sliders_s1(capsys):
    code, out, _ = run(capsys, "solve", "seed-slider-crank", "--angle", "30", "--json")
    d = json.loads(out)
    assert d["sliders"]["slide"]["a"] == pytest.approx(-4600.18, abs=5e-3)
    assert d["drive"]["torque"] == pytest.approx(476.56, abs=5e-3)


def test_solve_tables(capsys):
    code, out, _ = run(capsys, "solve", "seed-slider-crank", "--angle", "30")
    assert code == 0
    assert "8262.364" in out and "476.558" in out and "rod -> piston" in out


def test_solve_kinematics_only_case(capsys):
    code, out, _ = run(capsys, "solve", "hibbeler-16-30", "--value", "0", "--json")
    d = json.loads(out)
    assert d["drive"] is None and d["bodies"]["linkAB"]["alpha"] == pytest.approx(-95.0)


def test_sweep_csv(capsys, tmp_path):
    f = tmp_path / "sc.csv"
    code, out, _ = run(capsys, "sweep", "seed-slider-crank", "--points", "72", "--csv", str(f))
    assert code == 0
    df = pd.read_csv(f)
    assert len(df) == 72
    for col in ("input [deg]", "rod.alpha [rad/s^2]", "slide.a [m/s^2]", "C.fx [N]",
                "drive.torque [N m]", "drive.power [W]", "jacobian_condition [-]",
                "transmission.C [deg]", "singular"):
        assert col in df.columns
    # dead centres of a centred slider-crank at 0 and 180 deg (closed form)
    assert "slider velocity = 0" in out and "180" in out


@pytest.mark.parametrize("argv, message", [
    (("solve", "no-such-case"), "no built-in case 'no-such-case'"),
    (("solve", "hibbeler-16-30", "--value", "0.6"), "cannot close at driver 'guide' = 0.6 m"),
    (("solve", "hibbeler-16-30", "--angle", "10"), "give --value"),
    (("solve", "seed-four-bar", "--value", "0.1"), "give --angle"),
])
def test_errors_are_one_line_and_exit_2(capsys, argv, message):
    code, out, err = run(capsys, *argv)
    assert code == 2
    assert message in err and "Traceback" not in err
    assert err.count("\n") == 1


def test_malformed_file_error(capsys, tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("name = \n")
    code, _, err = run(capsys, "solve", str(p))
    assert code == 2 and "bad.toml" in err and "malformed TOML" in err


def test_compare_json_instantaneous(capsys):
    """MuJoCo instantaneous mode on the S4 four-bar within 1e-4 of peak (issue 3)."""
    code, out, _ = run(capsys, "compare", "seed-four-bar", "--engine", "mujoco", "--mode",
                       "instantaneous", "--samples", "12", "--json")
    d = json.loads(out)
    assert code == 0 and d[0]["verdict"] == "pass"
    q = {c["quantity"]: c for c in d[0]["comparisons"]}
    assert q["rocker.alpha"]["normalised"] <= 1e-4 and q["B.force"]["passed"]


def test_compare_table_and_failing_exit_code(capsys):
    code, out, _ = run(capsys, "compare", "seed-slider-crank", "--engine", "mujoco",
                       "--timestep", "5e-3", "--samples", "12")
    # RK4 at 5 ms is too coarse for a 200 rad/s crank (6 steps a revolution): the
    # verdict fails and the command says so with exit status 1
    assert code == 1 and "FAIL" in out


def test_compare_pybullet_has_no_instantaneous_mode(capsys):
    code, _, err = run(capsys, "compare", "seed-four-bar", "--engine", "pybullet", "--mode",
                       "instantaneous")
    assert code == 2 and "no instantaneous mode" in err and "mujoco" in err


def test_models_writes_every_case(capsys, tmp_path):
    code, out, _ = run(capsys, "models", "--out", str(tmp_path))
    assert code == 0
    assert len(list(tmp_path.glob("*.xml"))) == len(case_names())
    assert len(list(tmp_path.glob("*.urdf"))) == len(case_names())


def test_solve_tables_print_a_nano_linkage_at_its_scale(capsys):
    """A four-bar with nanometre links (shared/bugs/nano-four-bar.toml): every point's x
    and y, and every rate, print at their own scale, never as a false 0.000000; the
    velocity and acceleration columns name their units."""
    from pathlib import Path

    from analytic import Linkage, load_mechanism
    f = Path(__file__).parents[1] / "data" / "bugs" / "nano-four-bar.toml"
    code, out, _ = run(capsys, "solve", str(f), "--angle", "77")
    assert code == 0
    for head in ("vx (m/s)", "vy (m/s)", "ax (m/s^2)", "ay (m/s^2)"):
        assert head in out
    kin = Linkage(load_mechanism(f)).kinematics(np.radians(77.0))
    rows = {ln.split("│")[1].strip(): ln.split("│")[2:-1] for ln in out.splitlines()
            if ln.count("│") == 10}
    coupler_b = [float(c) for c in rows["coupler.B"]]
    x, y = kin.point("coupler", "B")[0][0]  # position of the solver, m
    assert coupler_b[0] == pytest.approx(x, rel=1e-5) and x != 0
    assert coupler_b[1] == pytest.approx(y, rel=1e-5) and y != 0


@pytest.mark.parametrize("case", ["near-toggle-four-bar", "parallelogram-four-bar"])
def test_every_name_the_report_prints_resolves(capsys, case):
    """The report's hard cases are cases like the others: `xval cases` lists them and
    `xval solve` takes their names (it said "no built-in case" before)."""
    code, out, _ = run(capsys, "cases")
    assert code == 0 and case in out
    code, out, err = run(capsys, "solve", case, "--json")
    assert code == 0, err
    assert json.loads(out)["case"] == case
