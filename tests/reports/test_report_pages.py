"""The report's pages (issue 35): angles plotted in the tables' range, a first screen that
names the prescribed and free runs that did not pass with their reasons, and case pages
linked relative to the page, their figures files, not inline data."""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pandas as pd
import pytest

from analytic import Linkage, load_case
from analytic.sweep import to_frame
from reports.comparison.compare import FAIL, PASS
from reports.figures.case_figures import curve_figures
from reports.report import first_screen
from reports.report.console import sig2
from reports.report.document import Document
from reports.report.free_section import verdict_frame
from reports.studies import free_studies as FS
from sim_models import compile_linkage
from sim_models.runs.driven import run


@pytest.fixture(autouse=True)
def _headless(monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "disable")


@pytest.mark.parametrize("case", ["hibbeler-16-121", "hibbeler-16-31"])
def test_accelerating_crank_angle_in_the_tables_range(case):
    """An accelerating crank's verdict turn is its second (the run's inputs are one turn
    on): its angle figure must read as the tables do, the body angle starting in
    (-180, 180] deg (``xval solve``'s ``angle_deg``) and the crank's angle equal to the
    input on the axis (0 to 360 deg), not 360 to 720."""
    tree = compile_linkage(load_case(case))
    r = run(tree, "mujoco", None, revolutions=2, samples=36)
    assert r.ok
    assert np.nanmax(np.degrees(r.values)) > 360  # the sampled turn is the second one
    (fig,) = [f for f in curve_figures(case, {"mujoco": r}, tree.linkage) if f.name == "angle"]
    # the table's angle of each body at the line's first input, by the analytic solver
    lk = Linkage(load_case(case))
    first = to_frame(lk, lk.kinematics(np.radians([fig.curves[0].x[0]])), None).iloc[0]
    for c in fig.curves:
        y = np.asarray(c.y, float)
        assert -180 < y[0] <= 180, (c.label, y[0])
        assert y[0] == pytest.approx(first[f"{c.label}.angle_deg"], abs=1e-6), c.label
        x, my, _ = c.markers["mujoco"]
        assert np.nanmax(np.abs(my)) < 540, c.label  # within the turn the line spans
    crank = next(c for c in fig.curves if c.label == "crank")
    assert np.allclose(crank.y, crank.x, atol=1e-6)  # the crank's angle is the input
    assert 0 <= np.min(crank.y) and np.max(crank.y) <= 360 + 1e-6


def _summary(rows):
    cols = ["case", "engine", "verdict", "worst quantity", "worst error / peak",
            "at (deg or m)", "at (input)", "tolerance", "precision", "note"]
    return pd.DataFrame(rows, columns=cols)


@pytest.fixture(scope="module")
def free_runs():
    """A real short free run of A01 in MuJoCo (passes) and the same row made a failure:
    one pass and one FAIL, plus a case whose task died (not run)."""
    res = FS.case_task("iftomm-a01-pendulum", 0.5, 20, engines=["mujoco"])
    assert not res["errors"], res["errors"]
    bad = dict(res, case="iftomm-a01-copy",
               rows=[dataclasses.replace(res["rows"][0], case="iftomm-a01-copy",
                                         passed=False)],
               verdicts=[dataclasses.replace(res["verdicts"][0], case="iftomm-a01-copy")])
    # keyed by its task's name, not the case's own (as seed-four-bar runs released as
    # seed-four-bar-released)
    return {"cases": {"iftomm-a01-pendulum": res, "a01-task": bad}, "grid": [],
            "errors": ["iftomm-a03-andrews / pybullet: task failed: RuntimeError: boom"]}


def test_first_screen_lists_free_runs_and_failures_with_reasons(tmp_path, free_runs):
    summary = _summary([
        ("seed-four-bar", "mujoco", PASS, "B.force", 2e-6, 10.0, "10 deg", 1e-3, "float64", ""),
        ("seed-four-bar", "pybullet", FAIL, "O4.force", 3e-3, 20.0, "20 deg", 1e-3, "float64",
         ""),
        ("six-bar", "mujoco_warp", "precision limit (float32)", "link.alpha", 1.5e-3, 0.0,
         "0 deg", 1e-3, "float32", "link.alpha 0.0015 of peak is over the tolerance but "
         "within the engine's float32 floor 0.002")])
    vt = verdict_frame(free_runs)
    doc = Document(tmp_path)
    first_screen.lead(doc, summary, vt, free_runs, 2, ["mujoco", "pybullet", "mujoco_warp"])
    doc.h(1, "Verdict")
    page = doc.html("t")
    lead = page[page.index("<div class='lead'>"):page.index("<h2")]
    text = re.sub(r"<[^>]+>", "", lead)
    assert "3 of 6 runs FAIL" in text
    # the free runs: a line of their own with their counts, and rows in the figure
    assert "Free motion (3 cases" in text and "1 of 3 pass" in text
    # every run that did not pass, with why
    assert "prescribed seed-four-bar / pybullet: O4.force 3e-3 of peak over the " \
           "tolerance 1e-3 at 20 deg" in text
    assert "precision limit (float32) prescribed six-bar / mujoco_warp: link.alpha" in text
    w = free_runs["cases"]["a01-task"]["verdicts"][0].worst
    ratio = w.normalised / w.tolerance
    assert re.search(r"FAIL free iftomm-a01-copy / mujoco \(0\.5 s\): \S+ "
                     + re.escape(sig2(ratio)) + " x its tolerance", text), text
    assert "FAIL free iftomm-a03-andrews / pybullet: not run: " in text and "boom" in text
    assert "pass free iftomm-a01-pendulum" not in text  # a pass is counted, not listed
    # one figure, loaded with the page, that exists
    imgs = re.findall(r"<img[^>]*>", lead)
    assert len(imgs) == 1 and "loading" not in imgs[0]
    assert (tmp_path / "img" / "overview.png").stat().st_size > 5000
    cells = {(c.row, c.engine): c for c in first_screen.free_cells(vt, free_runs)}
    assert cells["iftomm-a01-pendulum (free)", "mujoco"].status == "pass"
    assert cells["iftomm-a01-copy (free)", "mujoco"].status == "FAIL"
    assert math.isclose(cells["iftomm-a01-copy (free)", "mujoco"].ratio, ratio)
    assert cells["iftomm-a03-andrews (free)", "pybullet"].status == "not run"


def test_pages_are_relative_unique_and_in_place_in_markdown(tmp_path):
    """A sub-page: its own file under cases/ (two names with one file stem get two
    files), links and figures relative to it, a cut table linking the whole CSV; the
    Markdown holds it in place, one heading level down, its figure from img/."""
    doc = Document(tmp_path)
    doc.h(1, "Cases")
    a = doc.page("a/b", "A", "a/b", "- first")
    b = doc.page("a_b", "B", "a_b")
    assert (a.page_path, b.page_path) == ("cases/a_b.html", "cases/a_b-2.html")
    a.h(1, "a/b")
    a.table(pd.DataFrame({"x": [1.0]}), "whole_table", "cut", whole="whole_table")
    a.image(b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x10\0\0\0\x08", "fig", "a figure")
    doc.write_html("t")
    page = (tmp_path / "cases" / "a_b.html").read_text()
    assert "src='../img/fig.png'" in page and "loading='lazy'" in page
    assert "width='16' height='8'" in page
    assert "href='../whole_table.csv'" in page and "href='../index.html'" in page
    assert not (tmp_path / "whole_table.csv").exists()  # linked, not written again
    index = (tmp_path / "index.html").read_text()
    assert "href='cases/a_b.html'" in index and "href='cases/a_b-2.html'" in index
    md = doc.markdown("t")
    assert "## Cases" in md and "### a/b" in md and "![a figure](img/fig.png)" in md
    assert md.index("## Cases") < md.index("### a/b")


def test_free_case_pages_hold_their_own_rows(tmp_path, free_runs):
    """Each free case's page is named after its rows' case and shows those rows and its
    figures; its line in the section says how many pass and which did not."""
    from reports.report.free_section import section
    doc = Document(tmp_path)
    section(doc, free_runs, quick=True)
    doc.write_html("t")
    index = (tmp_path / "index.html").read_text()
    assert ("<a href='cases/free-iftomm-a01-copy.html'>iftomm-a01-copy (free)</a> "
            "- 0/1 pass (mujoco FAIL)") in index
    assert "<a href='cases/free-iftomm-a01-pendulum.html'>iftomm-a01-pendulum (free)</a> " \
           "- 1/1 pass<" in index
    page = (tmp_path / "cases" / "free-iftomm-a01-copy.html").read_text()
    assert page.count("<tr>") == 2 and "iftomm-a01-copy" in page and "FAIL" in page
    assert page.count("<img") == 3 and "href='../free_verdicts.csv'" in page


def test_known_limit_text_has_no_markdown_markup(tmp_path, free_runs):
    """The free section's known-limit paragraph (shown only when a run is at a listed
    limit) and the first screen's line for it carry no raw Markdown into the HTML
    (the paragraph said `xval report` before)."""
    from html.parser import HTMLParser

    from reports.report.free_section import section
    res = free_runs["cases"]["iftomm-a01-pendulum"]
    row = dataclasses.replace(res["rows"][0], case="seed-four-bar-released",
                              engine="pybullet", duration=1.0, passed=False,
                              worst_error=3.5e-2)
    free = {"cases": {"seed-four-bar": dict(res, rows=[row])}, "grid": [], "errors": []}
    vt = verdict_frame(free)
    assert list(vt["verdict"]) == ["known limit"]
    doc = Document(tmp_path)
    first_screen.lead(doc, _summary([]), vt, free, 0, ["pybullet"])
    section(doc, free, quick=True)

    class Text(HTMLParser):
        def __init__(self):
            super().__init__()
            self.chunks, self.skip = [], False

        def handle_starttag(self, tag, attrs):
            self.skip = tag == "style"

        def handle_endtag(self, tag):
            self.skip = False

        def handle_data(self, data):
            if not self.skip:
                self.chunks.append(data)

    t = Text()
    t.feed(doc.html("t"))
    text = "".join(t.chunks)
    assert "A 'known limit' is a case" in text and "known limit" in text
    assert "free seed-four-bar-released / pybullet (1 s)" in text
    assert "`" not in text and "**" not in text
