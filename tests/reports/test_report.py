"""The validation report: written whole even when an engine fails, and its HTML is sound."""

from __future__ import annotations

import base64
import io
import os
from html.parser import HTMLParser

import pandas as pd
import pytest

from reports.report.build import ReportConfig, build_report


class _Images(HTMLParser):
    def __init__(self):
        super().__init__()
        self.srcs, self.tables = [], 0

    def handle_starttag(self, tag, attrs):
        if tag == "img":
            self.srcs.append(dict(attrs)["src"])
        if tag == "table":
            self.tables += 1


@pytest.fixture(scope="module")
def report_dir(tmp_path_factory):
    """A small real report: one case, MuJoCo made to diverge (Euler with a 5 ms step and a
    stiff loop), PyBullet at its recommended settings; no studies."""
    out = tmp_path_factory.mktemp("report")
    cfg = ReportConfig(out=out, quick=True, cases=("seed-slider-crank",), samples=12,
                       studies=False, workers=2,
                       settings={"mujoco": {"integrator": "Euler", "timestep": 5e-3,
                                            "solref": (-1e8, -2e4)}})
    build_report(cfg)
    return out


def test_outputs_exist(report_dir):
    for name in ("index.html", "report.md", "verdicts.csv", "verdict_summary.csv",
                 "seed_comparison.csv", "run_metadata.csv", "instantaneous_floors.csv"):
        assert (report_dir / name).is_file(), name


def test_diverging_engine_is_a_failed_row(report_dir):
    s = pd.read_csv(report_dir / "verdict_summary.csv")
    mj = s[s.engine == "mujoco"].iloc[0]
    pb = s[s.engine == "pybullet"].iloc[0]
    assert mj.verdict == "FAIL" and "diverged" in mj.note
    assert pb.verdict == "pass"


def test_html_images_decode(report_dir):
    from PIL import Image
    p = _Images()
    p.feed((report_dir / "index.html").read_text())
    assert p.tables >= 4 and len(p.srcs) >= 5
    for src in p.srcs:
        assert src.startswith("data:image/png;base64,")
        img = Image.open(io.BytesIO(base64.b64decode(src.split(",", 1)[1])))
        img.verify()
        assert img.size[0] > 100


def test_markdown_links_its_images(report_dir):
    md = (report_dir / "report.md").read_text()
    for line in md.splitlines():
        if line.startswith("!["):
            rel = line.rsplit("](", 1)[1].rstrip(")")
            assert (report_dir / rel).is_file(), rel


def test_missing_engine_still_reports(tmp_path, monkeypatch):
    """An engine that cannot be imported becomes a failed row, not a crash."""
    import reports.report.build as rep

    real = rep.engine_task

    def fake(case, engine, overrides, revolutions, samples, mode="run"):
        if engine == "pybullet":
            import sim_models.engines.pybullet.driven as pbs
            monkeypatch.setattr(pbs, "_require_pybullet", lambda: (_ for _ in ()).throw(
                pbs.SimModelError("PyBullet is not installed (test)")))
        return real(case, engine, overrides, revolutions, samples, mode)

    monkeypatch.setattr(rep, "engine_task", fake)
    cfg = ReportConfig(out=tmp_path, quick=True, cases=("seed-four-bar",), samples=8,
                       studies=False, engines=("pybullet",), workers=1)
    from concurrent.futures import ThreadPoolExecutor
    monkeypatch.setattr(rep, "make_executor", lambda cfg: ThreadPoolExecutor(1))
    build_report(cfg)
    s = pd.read_csv(tmp_path / "verdict_summary.csv")
    assert s.iloc[0].verdict == "FAIL" and "not installed" in s.iloc[0].note


@pytest.mark.slow
def test_dask_local_cluster(tmp_path):
    """--dask SCHEDULER_ADDRESS: the same tasks on a Dask distributed cluster."""
    distributed = pytest.importorskip("distributed")
    # the dashboard on a port the system picks (None meant Dask's fixed 8787, taken by a
    # second test process under pytest -n, or another project's cluster)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster:
        cfg = ReportConfig(out=tmp_path, quick=True, cases=("seed-four-bar",), samples=8,
                           studies=False, engines=("mujoco",), dask=cluster.scheduler_address)
        build_report(cfg)
    s = pd.read_csv(tmp_path / "verdict_summary.csv")
    assert s.iloc[0].verdict == "pass"
    meta = pd.read_csv(tmp_path / "run_metadata.csv").set_index("key")["value"]
    assert meta["executor"].startswith("dask tcp://")


#: After load, the page reports its own height and width and how many of its images the
#: browser decoded (``naturalWidth > 0``) into a <pre id="probe"> read from --dump-dom.
_PROBE = ("<script>window.addEventListener('load',()=>{const im=[...document.images];"
          "const p=document.createElement('pre');p.id='probe';p.textContent=JSON.stringify("
          "{h:document.documentElement.scrollHeight,w:document.documentElement.scrollWidth,"
          "n:im.length,bad:im.filter(i=>!(i.complete&&i.naturalWidth>0)).length});"
          "document.body.appendChild(p);});</script>")


def _chromium():
    import shutil
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        if os.environ.get("CI"):  # .ci/run installs it: under CI a missing browser is a failure
            pytest.fail("CI=true but no Chromium: .ci/run should have installed it")
        pytest.skip("no Chromium on this machine (apt-get install chromium)")
    return exe


def _chromium_args(exe, tmp_path, *more):
    return [exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
            "--no-first-run", "--disable-background-networking",
            "--disable-component-update", "--disable-sync",
            f"--user-data-dir={tmp_path / 'profile'}", "--window-size=1200,1600", *more]


def test_html_renders_in_headless_chromium(report_dir, tmp_path):
    """Debian's Chromium renders the page: the screenshot is not blank, the browser
    decodes every image, and the page is as tall as its contents make plausible."""
    import json
    import re
    import subprocess
    exe = _chromium()
    shot = tmp_path / "page.png"
    subprocess.run(_chromium_args(exe, tmp_path, f"--screenshot={shot}",
                                  (report_dir / "index.html").as_uri()),
                   check=True, timeout=120, capture_output=True)
    from PIL import Image
    img = Image.open(shot)
    assert img.size == (1200, 1600)
    # not a blank page: the tables and plots put many distinct colours on it
    assert len(img.convert("RGB").getcolors(maxcolors=1 << 20) or []) > 50
    # the browser's own view: every image decoded, the page's height
    html_text = (report_dir / "index.html").read_text()
    probe = tmp_path / "probe.html"
    probe.write_text(html_text.replace("</body>", _PROBE + "</body>"))
    dom = subprocess.run(_chromium_args(exe, tmp_path, "--virtual-time-budget=15000",
                                        "--dump-dom", probe.as_uri()),
                         check=True, timeout=120, capture_output=True, text=True).stdout
    m = re.search(r'<pre id="probe">([^<]*)</pre>', dom)
    assert m, "the page's load handler never ran"
    got = json.loads(m.group(1))
    p = _Images()
    p.feed(html_text)
    assert got["n"] == len(p.srcs) >= 5 and got["bad"] == 0, got
    # plausible height: more than a screen, less than every image and table at 900 px
    assert 1600 < got["h"] < 900 * (len(p.srcs) + p.tables) + 4000, got
    assert got["w"] <= 1200, got  # nothing wider than the window
