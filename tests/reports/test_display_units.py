"""Display units (``--units``) of solve and sweep, rpm in a file, and no printed noise.

Expected values: the SI output of the same command converted here by the definitions
(1 m = 1000 mm, 1 rpm = 2 pi / 60 rad/s, 1 in = 25.4 mm), never by the module under test.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from analytic import load_case
from reports.cli.xval import main

from .cli_run import run

CASES = Path(__file__).resolve().parents[2] / "analytic" / "cases"
#: The conversion is one multiplication: agreement to a few ulps.
REL = 1e-13


def solve_json(*argv) -> dict:
    code, out = run("solve", *argv, "--json")
    assert code == 0
    return json.loads(out)


def test_solve_mm_deg_rpm_matches_si():
    si = solve_json("seed-four-bar")
    mm = solve_json("seed-four-bar", "--units", "mm,deg,rpm")
    rpm = 60.0 / (2.0 * math.pi)
    assert mm["units"] == {"length": "mm", "angle": "deg", "angular_speed": "rpm",
                           "note": mm["units"]["note"]}
    assert mm["input"]["velocity"] == pytest.approx(15.0 * rpm, rel=REL)
    for b, d in si["bodies"].items():
        assert mm["bodies"][b]["angle_deg"] == pytest.approx(d["angle_deg"], rel=REL)
        assert mm["bodies"][b]["omega"] == pytest.approx(d["omega"] * rpm, rel=REL)
        assert mm["bodies"][b]["alpha"] == pytest.approx(d["alpha"], rel=REL)
    for p, d in si["points"].items():
        for key in ("position", "velocity", "acceleration"):
            got = np.array(mm["points"][p][key])
            # noise (|x| < 1e-12 of the largest) is shown as 0 in both
            np.testing.assert_allclose(got, 1000.0 * np.array(d[key]), rtol=REL,
                                       atol=1e-9 * 1000.0 * max(
                                           np.abs(v[key]).max() for v in si["points"].values()))
    for j, d in si["joints"].items():
        np.testing.assert_allclose(mm["joints"][j]["force"], d["force"], rtol=REL)
    assert mm["drive"]["torque"] == pytest.approx(si["drive"]["torque"], rel=REL)


def test_solve_tables_state_units_and_convert():
    _, si = run("solve", "seed-four-bar")
    code, out = run("solve", "seed-four-bar", "--units", "in,rad,rpm")
    assert code == 0
    assert "units: lengths in, angles rad, angular speeds rpm" in out
    assert "x (in)" in out and "theta (rad)" in out and "omega (rpm)" in out
    # crank.A at 60 deg of the 100 mm crank: (50, 86.60254) mm
    row = next(line for line in out.splitlines() if "crank.A" in line)
    nums = [float(x) for x in re.findall(r"-?\d+\.\d+(?:e[-+]?\d+)?", row)]
    assert nums[0] == pytest.approx(50.0 / 25.4, abs=1e-6)
    assert nums[1] == pytest.approx(100.0 * math.sin(math.radians(60)) / 25.4, abs=1e-6)
    crank = next(line for line in out.splitlines() if line.strip("│ ").startswith("crank "))
    assert float(crank.split("│")[2]) == pytest.approx(math.pi / 3, abs=1e-6)


@pytest.mark.parametrize("case", ["seed-four-bar", "seed-slider-crank"])
def test_no_negative_zero_or_noise_printed(case):
    for angle in ("0", "90", "180"):
        _, out = run("solve", case, "--angle", angle)
        body = out.split("power-balance residual")[0]
        assert not re.search(r"(?<![\w.])-0(\.0*)?(?![\d.e])", body), body
        assert not re.search(r"-?\d\.\d+e-1[2-9]", body), body  # e.g. -3.3e-16


def test_sweep_csv_units(tmp_path):
    si, conv = tmp_path / "si.csv", tmp_path / "mm.csv"
    assert run("sweep", "seed-slider-crank", "--points", "12", "--csv", str(si))[0] == 0
    code, out = run("sweep", "seed-slider-crank", "--points", "12", "--csv", str(conv),
                    "--units", "mm,rad,rpm")
    assert code == 0 and "table units: lengths mm, angles rad" in out
    a, b = pd.read_csv(si), pd.read_csv(conv)
    # the input in rad is the value solved at: radians of the printed degrees, exactly
    np.testing.assert_array_equal(b["input [rad]"], np.radians(a["input [deg]"]))
    np.testing.assert_allclose(b["crank.omega [rpm]"],
                               a["crank.omega [rad/s]"] * 60 / (2 * math.pi), rtol=REL)
    np.testing.assert_allclose(b["slide.s [mm]"], 1000 * a["slide.s [m]"], rtol=REL)
    # the piston's y stays on the line: 0 (never round-off) in both
    assert (b["piston.C.y [mm]"] == 0).all() and (a["piston.C.y [m]"] == 0).all()
    assert not (np.signbit(b.select_dtypes("number").to_numpy())
                & (b.select_dtypes("number").to_numpy() == 0)).any()


@pytest.mark.parametrize("unit,factor", [("rpm", 2 * math.pi / 60), ("deg/s", math.pi / 180),
                                         ("rad/s", 1.0)])
def test_toml_velocity_unit(tmp_path, unit, factor):
    text = (CASES / "seed-four-bar.toml").read_text()
    text = re.sub(r"(\[driver\][^\[]*?)velocity = [^\n]*",
                  lambda m: f'{m.group(1)}velocity = 1500\nvelocity_unit = "{unit}"', text,
                  count=1, flags=re.S)
    f = tmp_path / "m.toml"
    f.write_text(text)
    assert load_case(str(f)).driver.velocity == pytest.approx(1500 * factor, rel=1e-15)


def test_toml_bad_velocity_unit_is_one_line(tmp_path, capsys):
    text = (CASES / "seed-four-bar.toml").read_text().replace(
        "[driver]", '[driver]\nvelocity_unit = "rps"')
    f = tmp_path / "m.toml"
    f.write_text(text)
    assert main(["solve", str(f)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "velocity_unit 'rps'" in err and "[driver]" in err


def test_bad_units_option_is_one_line(capsys):
    assert main(["solve", "seed-four-bar", "--units", "mm,cm"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "two length units" in err
