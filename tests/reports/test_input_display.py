"""One input convention everywhere (issue 18, "What to build" 7).

The verdict table (``xval compare``'s printed table), the error figure's panel title
(drawn by ``xval plot``'s own figure code) and the JUnit file of one run must name the
same worst input, and a failed run's input is shown in its own unit (a slider's 0.1 m
is 0.1 m, not 5.73 "m" from a degree conversion).
"""

from __future__ import annotations

import math
import re
import types
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from analytic import Linkage, load_case
from analytic.input_display import (
    InputConvention,
    convention_of,
    display_input,
    format_input,
    input_text,
)

from .cli_run import run

#: six-bar's mujoco run: its worst error sits in the second turn, 400 deg along the
#: motion, which the figure once titled "at 400" while the table said 40.
CASE, ENGINE = "six-bar", "mujoco"
#: A step 20x the recommended one: the verdict fails (link.alpha ~1e-3 of peak), so the
#: JUnit file carries a failure message naming the worst input.
TIMESTEP = 0.005
NUMBER = r"(-?[0-9.]+(?:e[-+]?[0-9]+)?)"


def test_wrap_and_units_from_independent_values():
    full = InputConvention(True, True)
    assert display_input(math.radians(495.0), full) == pytest.approx(135.0, abs=1e-9)
    assert display_input(2 * math.pi * (1 - 1e-17), full) == 0.0   # 360 - 1 ulp
    assert display_input(math.radians(-40.0), InputConvention(True, False)) == \
        pytest.approx(-40.0)
    assert display_input(0.1, InputConvention(False)) == 0.1
    assert format_input(0.1, "m") == "0.1 m"
    assert input_text(math.radians(390.0), full) == "30 deg"
    assert input_text(float("nan"), full) == "" and input_text(None, full) == ""
    assert convention_of(Linkage(load_case("seed-four-bar"))).full_turn
    assert not convention_of(Linkage(load_case("hibbeler-16-30"))).revolute


def test_failed_slider_run_is_shown_in_metres():
    """report_tables once turned a slider-driven run that failed at 0.1 m into
    'at input 5.73 m' (degrees of 0.1 rad)."""
    from reports.report.tables import failed_at, summary_table, verdict_table
    slider, four_bar = Linkage(load_case("hibbeler-16-30")), Linkage(load_case("seed-four-bar"))
    r = types.SimpleNamespace(ok=False, fail_value=0.1, reason="diverged",
                              mechanism=slider.mech, linkage=slider, settings_text="")
    assert failed_at(r) == 0.1
    crank = types.SimpleNamespace(ok=False, fail_value=math.radians(390.0),
                                  mechanism=four_bar.mech, linkage=four_bar)
    assert failed_at(crank) == pytest.approx(30.0)
    import reports.comparison.compare as cmp
    orig = cmp.comparison_frame
    cmp.comparison_frame = lambda run_, comps: orig(run_, [])  # no quantities: the row only
    try:
        r.case, r.engine = "hibbeler-16-30", "mujoco"
        v = verdict_table([{"run": r, "comparisons": [], "case": "hibbeler-16-30",
                            "engine": "mujoco"}])
    finally:
        cmp.comparison_frame = orig
    s = summary_table(v, {"hibbeler-16-30": "m"})
    assert s["at (input)"].iloc[0] == "0.1 m"


def _title_input(title: str) -> str:
    m = re.search(r" at " + NUMBER + r" (deg|m)\b", title)
    assert m, f"no input in the panel title {title!r}"
    return m.group(1)


def test_table_figure_and_junit_name_the_same_worst_input(tmp_path):
    from reports.cli import plot as plot_cmd
    from reports.comparison.runs import settings_for
    from reports.figures import plots
    junit = tmp_path / "j.xml"
    code, out = run("compare", CASE, "--engine", ENGINE, "--timestep", str(TIMESTEP),
                    "--junit", str(junit))
    assert code == 1, out
    # the verdict table: the row of the largest normalised error
    rows = [ln.split() for ln in out.splitlines()
            if re.match(r"^\s*\S+\.(alpha|a|force|effort|normal|moment)\s", ln)
            and "[engine]" not in ln]
    assert rows, out
    worst = max(rows, key=lambda r: float(r[3]))
    table_at = worst[4]
    # the figure: xval plot's own error panel, its title as drawn
    settings = settings_for([ENGINE], options={"--timestep": ("timestep", TIMESTEP)})
    _, err, _, _ = plot_cmd.case_figures(load_case(CASE), ["alpha"], [ENGINE], settings)
    fig, ax = plots.plt.subplots()
    plots.draw_error_axes(ax, err, ENGINE, err.panels[ENGINE])
    title = ax.get_title()
    plots.plt.close(fig)
    assert worst[0] in title, (title, worst)
    fig_at = _title_input(title)
    # JUnit: the testcase's failure message or its properties name the worst input
    tc = ET.parse(junit).getroot().find(".//testcase")
    text = ET.tostring(tc, encoding="unicode")
    fail = tc.find("failure")
    assert fail is not None, text
    m = re.search(rf"{re.escape(worst[0])}: error [^ ]+ of peak at {NUMBER} deg",
                  fail.get("message", ""))
    assert m, fail.get("message")
    junit_at = m.group(1)
    assert table_at == fig_at == junit_at, (table_at, fig_at, junit_at)
    assert 0.0 <= float(table_at) < 360.0
    # and the figure's own axis places the worst error at that input
    p = err.panels[ENGINE]
    assert np.isclose(p["worst"][2], float(table_at), atol=1e-6)


def test_engine_failure_reason_uses_the_same_convention():
    """An engine's failure reason names the driver value as the verdict row does: a
    run that stopped 390 deg along the motion said '390 deg' there and '30 deg' in the
    table."""
    from sim_models import compile_linkage
    from sim_models.runs.engine_run import fmt_value
    assert fmt_value(compile_linkage(load_case("seed-four-bar")), math.radians(390.0)) \
        == "30 deg"
    assert fmt_value(compile_linkage(load_case("hibbeler-16-30")), 0.1) == "0.1 m"
