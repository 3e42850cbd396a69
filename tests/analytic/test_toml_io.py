"""The TOML format: round trip to the Python description, units, and bad files."""

from __future__ import annotations

import math

import pytest

from analytic import DescriptionError, Linkage, load_mechanism
from analytic.cases import case_path

GOOD = '''
name = "fb"
[units]
length = "mm"
[bodies.ground]
points = { O2 = [0, 0], O4 = [400, 0] }
[bodies.crank]
points = { O2 = [0, 0], A = [100, 0] }
mass = 0.2
com = [50, 0]
inertia = 1.6666666666666667e-4
[bodies.coupler]
points = { A = [0, 0], B = [300, 0] }
[bodies.rocker]
points = { O4 = [0, 0], B = [250, 0] }
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
[assembly]
points = { "coupler.B" = [310, 230] }
'''


def write(tmp_path, text, name="m.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_units_converted_at_the_edge(tmp_path):
    m = load_mechanism(write(tmp_path, GOOD))
    assert m.body("rocker").points["B"] == pytest.approx((0.25, 0.0))
    assert m.body("crank").com == pytest.approx((0.05, 0.0))
    assert m.driver.value == pytest.approx(math.radians(60))
    assert m.assembly.points["coupler.B"] == pytest.approx((0.31, 0.23))
    inch = load_mechanism(case_path("hibbeler-16-121"))
    assert inch.body("crank").points["B"] == pytest.approx((7 * 0.0254, 0.0))


def test_same_mechanism_in_other_units(tmp_path):
    """The file in cm gives the same solution as in mm (alpha4 of S4 = 95.5036)."""
    cm = GOOD.replace('"mm"', '"cm"')
    for a, b in (("400", "40"), ("100", "10"), ("300", "30"), ("250", "25"),
                 ("[50, 0]", "[5, 0]"), ("[310, 230]", "[31, 23]")):
        cm = cm.replace(a, b)
    k1 = Linkage(load_mechanism(write(tmp_path, GOOD, "a.toml"))).kinematics()
    k2 = Linkage(load_mechanism(write(tmp_path, cm, "b.toml"))).kinematics()
    assert k1.alpha[0, 3] == pytest.approx(k2.alpha[0, 3], rel=1e-13)
    assert k1.alpha[0, 3] == pytest.approx(95.5036, abs=5e-5)


@pytest.mark.parametrize("mutate, message", [
    (lambda t: t.replace('type = "revolute"\nbodies = ["crank"',
                         'type = "revolute\nbodies = ["crank"'), r"malformed TOML.*line"),
    (lambda t: t.replace("mass = 0.2", "mas = 0.2"), r"body 'crank'.*unknown keys \['mas'\]"),
    (lambda t: t.replace('length = "mm"', 'length = "furlong"'), r"unknown length unit"),
    (lambda t: t.replace('type = "revolute"\nbodies = ["rocker"',
                         'type = "cylindrical"\nbodies = ["rocker"'),
     r"joint 'B'.*unknown joint type 'cylindrical'"),
    (lambda t: t.replace("value = 60.0", 'value = "sixty"'), r"\[driver\].*value.*finite number"),
    (lambda t: t.replace("O4 = [0, 0], B = [250, 0]", "O4 = [0, 0], B = [250]"),
     r"body 'rocker'.*point 'B'.*pair"),
    (lambda t: t.replace('joint = "O2"', 'joint = "Z9"'), r"driver joint 'Z9' is not a joint"),
    (lambda t: t.replace("[driver]", "[drivr]"), r"unknown keys \['drivr'\]"),
    (lambda t: t.replace("velocity = 15.0", "velocity = nan"), r"velocity.*finite"),
])
def test_malformed_files(tmp_path, mutate, message):
    bad = mutate(GOOD)
    assert bad != GOOD, "the mutation must change the file"
    p = write(tmp_path, bad)
    with pytest.raises(DescriptionError, match=message) as e:
        load_mechanism(p)
    assert str(p) in str(e.value), "the error names the file"


def test_missing_file(tmp_path):
    with pytest.raises(DescriptionError, match="cannot read file"):
        load_mechanism(tmp_path / "nope.toml")


@pytest.mark.parametrize("case", ["seed-four-bar", "quick-return", "hibbeler-16-121",
                                  "inverted-slider-crank"])
def test_written_toml_reads_back_the_same_mechanism(tmp_path, case):
    """mechanism_to_toml -> load_mechanism gives the same solution (lengths, masses and
    rates are written with repr, so they read back bit for bit)."""
    from analytic import load_case
    from analytic.toml_io import mechanism_to_toml
    m = load_case(case)
    p = write(tmp_path, mechanism_to_toml(m))
    k1, k2 = Linkage(m).kinematics(), Linkage(load_mechanism(p)).kinematics()
    assert k2.theta == pytest.approx(k1.theta, abs=1e-15)
    assert k2.alpha == pytest.approx(k1.alpha, rel=1e-12)


def test_range_errors_in_the_files_units(tmp_path):
    """A length out of range is reported in the file's unit, with the accepted range."""
    p = write(tmp_path, GOOD.replace("B = [300, 0]", "B = [2e7, 0]"))
    with pytest.raises(DescriptionError, match=r"body 'coupler': point 'B' = 2e\+07 mm is out "
                                               r"of range: .*<= 1e\+07 mm"):
        load_mechanism(p)


def test_utf8_byte_order_mark_is_accepted(tmp_path):
    p = tmp_path / "bom.toml"
    p.write_bytes(b"\xef\xbb\xbf" + GOOD.encode())
    assert load_mechanism(p).name == "fb"
