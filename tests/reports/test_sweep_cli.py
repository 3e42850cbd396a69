"""``xval sweep``'s options and wording (issue 18, What was seen 9): ``--range`` takes the
values ``--angle`` (or ``--value``) takes, and the summary names each stroke once."""

from __future__ import annotations

import pytest

from reports.cli.xval import main


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


#: the Parquet table (streamed, the kernel block by block) and the CSV (in memory) solve
#: the same rows, possibly by the two paths (kernel, numpy), which agree to 1e-13 of
#: peak (tests/analytic/test_fused.py's AGREEMENT); the CSV prints every double exactly
PARQUET_AGREEMENT = 1e-13


def test_parquet_holds_the_csv_table(capsys, tmp_path):
    """``--parquet F``: the table of ``--csv``, the same columns, inputs and cells."""
    import numpy as np
    import pandas as pd
    import pyarrow.parquet as pq
    csv, par = tmp_path / "t.csv", tmp_path / "t.parquet"
    assert main(["sweep", "seed-four-bar", "--points", "500", "--csv", str(csv)]) == 0
    out_csv = capsys.readouterr().out
    assert main(["sweep", "seed-four-bar", "--points", "500", "--parquet", str(par)]) == 0
    out_par = capsys.readouterr().out
    a, b = pd.read_csv(csv), pq.read_table(par).to_pandas()
    assert list(b.columns) == list(a.columns) and len(b) == len(a) == 500
    np.testing.assert_array_equal(b.iloc[:, 0], a.iloc[:, 0])  # the inputs, exactly
    x, y = a.to_numpy(float), b.to_numpy(float)
    np.testing.assert_array_equal(x == 0, y == 0)
    scale = np.max(np.abs(x), axis=0)
    assert np.all(np.abs(x - y) <= PARQUET_AGREEMENT * np.maximum(scale, 1e-300))
    # the same events and summary, the file named
    assert out_par.replace(str(par), "F") == out_csv.replace(str(csv), "F")


def test_parquet_to_standard_output_is_refused(capsys, tmp_path):
    assert main(["sweep", "seed-four-bar", "--points", "36", "--parquet", "-"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("xval: error: argument --parquet"), err
