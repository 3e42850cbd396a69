"""The console verdict of ``xval report``: fits 100 columns, two significant figures,
one line of counts per engine and the smallest margin."""

from __future__ import annotations

import math

import pandas as pd

from reports.report.console import WIDTH, counts_line, sig2, verdict_table


def _summary():
    rows = []
    for i, case in enumerate(["seed-four-bar", "a-very-long-user-case-name-that-goes-on-and-on"]):
        for e, err in (("mujoco", 1.365519e-08), ("pybullet", 8.5e-4), ("exudyn", 2.0e-5)):
            rows.append({"case": case, "engine": e, "verdict": "pass",
                         "worst quantity": "crank.alpha", "worst error / peak": err * (i + 1),
                         "at (deg or m)": 145.0, "at (input)": "145 deg", "tolerance": 1e-3,
                         "note": ""})
    rows[-1].update(verdict="FAIL", note="diverged at 12 deg: loop gap 2e-3 of size " * 3,
                    **{"worst error / peak": math.inf})
    return pd.DataFrame(rows)


def test_two_significant_figures():
    assert [sig2(v) for v in (1.365519e-08, 8.5e-4, 1e-3, 0.0123, 42.0, math.inf)] == \
        ["1.4e-8", "8.5e-4", "1e-3", "0.012", "42", "inf"]


def test_table_fits_the_width_and_has_no_nan():
    lines = verdict_table(_summary())
    assert len(lines) == 7
    assert all(len(ln) <= WIDTH for ln in lines), max(map(len, lines))
    assert not any("NaN" in ln or "nan" in ln for ln in lines)
    assert "1.4e-8" in lines[1]


def test_counts_line():
    s = _summary()
    assert counts_line(s).startswith("5 of 6 pass (mujoco 2/2, pybullet 2/2, exudyn 1/2); ")
    ok = s.iloc[:3]
    assert counts_line(ok) == ("3 of 3 pass (mujoco 1/1, pybullet 1/1, exudyn 1/1); "
                               "smallest margin: seed-four-bar pybullet crank.alpha 8.5e-4 "
                               "of 1e-3")
