"""Precision-limit verdicts: an error over the tolerance but within the engine's arithmetic
floor reads "precision limit (float32)" and does not fail; above the floor it fails; a
float64 engine claims no floor.

The runs are synthetic: a MuJoCo run of the seed four-bar (float64, errors near 1e-8 of
peak) with one body's alpha moved at one sample by a chosen multiple of the float32
floor there, computed here from its definition (``4 u32 steps condition``,
:mod:`sim_models.runs.precision`) with the condition number from the analytic linkage.  The
settings are MuJoCo's, or a subclass that declares float32, so only the declared
arithmetic differs: nothing engine-specific enters the comparison.
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest

from analytic import load_case
from analytic.input_display import convention_of, display_input
from reports.comparison.compare import compare_run, verdict, verdict_word
from reports.comparison.runs import Verdict
from reports.regression.ci_formats import from_compare, junit_xml, markdown_summary
from reports.report.tables import accepted, summary_table, verdict_table
from sim_models import compile_linkage, run
from sim_models.builders.mjcf import MujocoSettings
from sim_models.runs.precision import FLOAT32, FLOAT64

#: float32's unit round-off and the floor's growth per step (the module's definition,
#: restated: a change of either must be a deliberate one that edits this test too).
U32 = 2.0 ** -24
GROWTH = 4.0
LIMIT = "precision limit (float32)"


@dataclasses.dataclass(frozen=True)
class Float32Mujoco(MujocoSettings):
    """MuJoCo's settings declaring float32 arithmetic (only the declaration differs)."""

    arithmetic: ClassVar = FLOAT32


@pytest.fixture(scope="module")
def base():
    tree = compile_linkage(load_case("seed-four-bar"))
    r = run(tree, "mujoco", MujocoSettings(), revolutions=2, samples=12)
    assert r.ok
    return tree, r


def _moved(base, factor: float, settings, ok: bool = True):
    """The base run with the coupler's alpha moved at sample 5 by ``factor`` x the
    float32 floor there (times its peak), its settings replaced; ``(run, floor, at)``."""
    tree, r = base
    b = r.body_names.index("coupler")
    kin = tree.linkage.kinematics(r.values, velocity=r.driver_velocity,
                                  acceleration=r.driver_acceleration)
    k = 5
    floor = GROWTH * U32 * r.steps * float(kin.condition[k])
    peak = float(np.max(np.abs(kin.alpha[:, b])))
    alpha = r.alpha.copy()
    alpha[k, b] = kin.alpha[k, b] + factor * floor * peak
    at = float(display_input(r.values, convention_of(tree.linkage))[k])
    return dataclasses.replace(r, alpha=alpha, settings=settings, ok=ok,
                               reason=None if ok else "stopped"), floor, at


def _coupler(comps):
    return next(c for c in comps if c.quantity == "coupler.alpha")


def test_within_the_float32_floor_reads_precision_limit_and_does_not_fail(base):
    tree, _ = base
    r, floor, at = _moved(base, 0.5, Float32Mujoco())
    comps = compare_run(r, tolerance=0.1 * floor)
    c = _coupler(comps)
    assert not c.passed and c.at == pytest.approx(at)
    assert c.floor == pytest.approx(floor, rel=1e-9)
    assert c.limited and c.status == LIMIT and c.as_json()["verdict"] == LIMIT
    assert verdict(comps) and verdict_word(comps) == LIMIT
    # the report's summary and exit status
    summary = summary_table(verdict_table([{"case": r.case, "engine": "mujoco", "run": r,
                                            "comparisons": comps}]))
    assert summary["verdict"].iloc[0] == LIMIT and accepted(summary).all()
    assert "floor" in summary["note"].iloc[0]
    # JUnit: a passing testcase that says what it is; Markdown: the word, not a failure
    v = Verdict(tree, r, tuple(comps))
    cases = from_compare(r.case, [v], revolute=True)
    assert cases[0].status == "limit" and cases[0].kind == LIMIT
    xml = junit_xml("xval compare", cases)
    root = ET.fromstring(xml)
    tc = root.find(".//testcase")
    assert tc.find("failure") is None and tc.find("error") is None
    assert tc.find("system-out").text.startswith(LIMIT + ": coupler.alpha")
    assert root.get("failures") == "0"
    xmlschema = pytest.importorskip("xmlschema")  # still the schema CI systems read
    xmlschema.XMLSchema(str(Path(__file__).with_name("junit.xsd"))).validate(xml)
    md = markdown_summary("xval compare", cases)
    assert LIMIT in md and "FAIL" not in md


def test_above_the_float32_floor_fails(base):
    tree, _ = base
    r, floor, _ = _moved(base, 2.0, Float32Mujoco())
    comps = compare_run(r, tolerance=0.1 * floor)
    c = _coupler(comps)
    assert not c.limited and c.status == "FAIL"
    assert not verdict(comps) and verdict_word(comps) == "FAIL"
    summary = summary_table(verdict_table([{"case": r.case, "engine": "mujoco", "run": r,
                                            "comparisons": comps}]))
    assert summary["verdict"].iloc[0] == "FAIL" and not accepted(summary).any()
    cases = from_compare(r.case, [Verdict(tree, r, tuple(comps))], revolute=True)
    assert cases[0].status == "fail"


def test_float64_claims_no_floor(base):
    """The same error with float64 settings: a failure (u64 claims nothing)."""
    tree, _ = base
    r, floor, _ = _moved(base, 0.5, MujocoSettings())
    c = _coupler(compare_run(r, tolerance=0.1 * floor))
    assert c.floor == 0.0 and c.precision == "float64" and c.status == "FAIL"


def test_a_stopped_run_claims_no_floor(base):
    tree, _ = base
    r, floor, _ = _moved(base, 0.5, Float32Mujoco(), ok=False)
    comps = compare_run(r, tolerance=0.1 * floor)
    assert _coupler(comps).floor == 0.0
    assert verdict_word(comps, run_ok=False) == "FAIL"


def test_floor_definition():
    """Linear in steps and condition; one solve uses the solve constant; float64 and a
    non-finite condition give none."""
    assert FLOAT32.floor(1000, 2.0) == pytest.approx(GROWTH * U32 * 1000 * 2.0)
    assert FLOAT32.floor(2000, 2.0) == pytest.approx(2 * FLOAT32.floor(1000, 2.0))
    assert FLOAT32.floor(0, 1.0) == pytest.approx(FLOAT32.solve_growth * U32)
    assert FLOAT64.floor(10 ** 6, 10.0) == 0.0
    assert FLOAT32.floor(1000, float("inf")) == 0.0
    assert FLOAT32.floor(1000, float("nan")) == 0.0
