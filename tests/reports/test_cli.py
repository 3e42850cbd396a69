"""The xval command line: JSON contents, tables, CSV sweep, and errors as one line + exit 2."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from analytic import case_names
from reports.cli import main


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
    for col in ("input", "rod.alpha", "slide.a", "C.fx", "drive.torque", "drive.power",
                "jacobian_condition", "transmission_deg.C"):
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
