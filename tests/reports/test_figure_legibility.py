"""Figures legible when zoomed (issue 18, "What was seen" 9): 150 dpi, legend text of at
least 9 pt, linkage drawings whose ground pivots are the ground's revolute joints and
whose coinciding poses stay visible, labels that do not overlap, zeros on a log axis
said on the figure."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

from analytic import Linkage, load_case
from reports.figures import plots
from reports.figures.case_figures import linkage_figure

#: The brief's floor for legend text at the page's width (pt).
MIN_LEGEND_PT = 9.0


@pytest.fixture
def keep_figure(monkeypatch):
    """plots._png hands back the matplotlib figure instead of PNG bytes."""
    got = []

    def grab(fig, tight=True):
        got.append(fig)
        return b""
    monkeypatch.setattr(plots, "_png", grab)
    yield got
    for f in got:
        plots.plt.close(f)


def test_png_is_150_dpi():
    png = linkage_figure("seed-four-bar", Linkage(load_case("seed-four-bar")))
    dpi = Image.open(io.BytesIO(png)).info["dpi"]
    assert dpi[0] == pytest.approx(150, abs=0.1)


def _legend_sizes(fig) -> list[float]:
    out = []
    for ax in fig.axes:
        leg = ax.get_legend()
        if leg is not None:
            out += [t.get_fontsize() for t in leg.get_texts()]
    out += [t.get_fontsize() for leg in fig.legends for t in leg.get_texts()]
    return out


def test_quick_return_drawing(keep_figure):
    """Ground pivots at O2 and O4 only (the ram line's origin is no pivot); the 90 deg
    pose, which coincides with the 270 deg one along the rocker, is drawn wider than it,
    so it shows; the labels' boxes do not overlap; legend text >= 9 pt."""
    lk = Linkage(load_case("quick-return"))
    plots.draw_linkage(lk, np.radians([0.0, 90.0, 180.0, 270.0]))
    fig = keep_figure[0]
    ax = fig.axes[0]
    piv = [ln for ln in ax.get_lines() if ln.get_marker() == "^"]
    assert len(piv) == 1
    xy = np.column_stack(piv[0].get_data())
    g = lk.mech.body(lk.mech.ground).points
    want = {tuple(np.round(g[p], 9)) for p in ("O2", "O4")} if "O2" in g else None
    assert len(xy) == 2
    if want is not None:
        assert {tuple(np.round(p, 9)) for p in xy} == want
    widths = sorted({round(ln.get_linewidth(), 3) for ln in ax.get_lines()
                     if ln.get_marker() in ("None", "", None) and ln.get_linestyle() != "None"
                     and ln.get_linewidth() > 1.0})
    assert len(widths) >= 4  # one width per input: the earlier wider
    r = fig.canvas.get_renderer()
    boxes = [t.get_window_extent(r) for t in ax.texts if t.get_visible() and t.get_text()]
    over = [(a, b) for i, a in enumerate(boxes) for b in boxes[i + 1:] if a.overlaps(b)]
    assert not over
    assert min(_legend_sizes(fig)) >= MIN_LEGEND_PT


def test_declutter_separates_labels():
    fig, ax = plots.plt.subplots(figsize=(4, 3))
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ts = [ax.annotate(f"label {k}", (0.5, 0.5), xytext=(0, 0), textcoords="offset points",
                      fontsize=9) for k in range(6)]
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    before = [t.get_window_extent(r) for t in ts]
    assert before[0].overlaps(before[1])  # the check can fail
    hidden = plots.declutter(ax, ts)
    shown = [t.get_window_extent(r) for t in ts if t.get_visible()]
    assert len(shown) + hidden == 6 and len(shown) >= 4
    assert not any(a.overlaps(b) for i, a in enumerate(shown) for b in shown[i + 1:])
    plots.plt.close(fig)


def test_log_floor_is_said(keep_figure):
    plots.timeseries_plot(np.arange(5.0), {"gap": np.array([0.0, 0.0, 1e-9, 2e-9, 3e-9])},
                          "t", "relative")
    ax = keep_figure[0].axes[0]
    notes = [t.get_text() for t in ax.texts]
    assert any("2 values below 1e-18 (exact zeros)" in n for n in notes), notes
    assert min(_legend_sizes(keep_figure[0])) >= MIN_LEGEND_PT
