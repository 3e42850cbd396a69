"""``xval report --quick --cases my/file.toml --out D``: the user's case, named by its
``name``, studied alone, and every file written under D."""

from __future__ import annotations

import os
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[2]


def _snapshot(*dirs: Path) -> dict:
    """Every file under ``dirs`` with its size and modification time."""
    out = {}
    for d in dirs:
        if d.is_dir():
            for p in d.rglob("*"):
                if p.is_file():
                    st = p.stat()
                    out[str(p)] = (st.st_size, st.st_mtime_ns)
    return out


@pytest.mark.slow
def test_user_case_report_writes_only_under_out(tmp_path, monkeypatch):
    from reports.cli.xval import main
    user = tmp_path / "my"
    user.mkdir()
    toml = user / "crank-rocker.toml"
    text = (ROOT / "analytic" / "cases" / "seed-four-bar.toml").read_text()
    toml.write_text(text.replace('name = "seed-four-bar"', 'name = "my-crank-rocker"', 1))
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    watched = (user, cwd, ROOT / "reports" / "out", ROOT / "sim_models" / "models",
               ROOT / "analytic" / "cases", ROOT / "docs")
    before = _snapshot(*watched)
    out = tmp_path / "D"
    assert main(["report", "--quick", "--cases", str(toml), "--out", str(out)]) == 0
    assert _snapshot(*watched) == before, "files written outside --out"
    assert os.listdir(cwd) == []
    s = pd.read_csv(out / "verdict_summary.csv")
    assert set(s["case"]) == {"my-crank-rocker"}
    md = (out / "report.md").read_text()
    assert "## my-crank-rocker" in md and str(toml) not in md
    for line in md.splitlines():
        if line.startswith("!["):
            rel = line.rsplit("](", 1)[1].rstrip(")")
            assert not rel.startswith("/") and (out / rel).is_file(), rel
    # only the requested case's work: its own speed-against-error study, no built-in ones
    names = {p.name for p in out.iterdir()}
    assert "speed_error_my-crank-rocker.csv" in names
    assert not any(n.startswith(("speed_error_seed", "hard_", "scene_economy",
                                 "seed_comparison")) for n in names), names
