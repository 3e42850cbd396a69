"""``xval sweep``'s options and wording (issue 18, What was seen 9): ``--range`` takes the
values ``--angle`` (or ``--value``) takes, and the summary names each stroke once."""

from __future__ import annotations

import pytest

from reports.cli import main


@pytest.mark.parametrize("case, lo, hi, message", [
    ("seed-four-bar", "0", "1e300", "argument --range: 1e+300 is out of range"),
    ("seed-four-bar", "inf", "10", "argument --range: inf is not a finite number"),
    ("seed-four-bar", "0", "nan", "argument --range: nan is not a finite number"),
    ("hibbeler-16-30", "0", "1e9", "argument --range: 1e+09 is out of range"),
])
def test_range_is_capped_like_angle(capsys, tmp_path, case, lo, hi, message):
    out = tmp_path / "o.csv"
    assert main(["sweep", case, "--points", "36", "--range", lo, hi, "--csv", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("xval: error: ") and message in err, err
    assert not out.exists()


def test_range_at_the_cap_is_accepted(capsys):
    assert main(["sweep", "seed-four-bar", "--points", "4", "--range", "-359999", "359999"]) == 0


def test_summary_names_each_stroke_once(capsys):
    assert main(["sweep", "seed-four-bar"]) == 0
    out = capsys.readouterr().out
    assert "swing of rocker: 47.6432 deg" in out and "rocker rocker" not in out
    assert main(["sweep", "quick-return"]) == 0
    out = capsys.readouterr().out
    assert "stroke of slider ram: 0.5 m" in out and "slider ram: stroke" not in out
