"""The report's overview figure: one cell per case and engine, prescribed and free runs,
coloured by the verdict and labelled with the worst error over its tolerance.

A reader sees in one look which runs pass (green, darker the larger the margin), which
sit at a known engine limit or a float32 precision limit (amber), which fail (red) and
which did not run (grey); the number in a cell is the run's worst judged error divided
by that quantity's tolerance (below 1 passes).  Data in
(:class:`OverviewCell`, made by :mod:`reports.report.first_screen`), PNG bytes out.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass

import numpy as np

from reports.figures.plots import plt  # pyplot on the Agg backend

#: Verdict classes of a cell: its fill (a pass is shaded by its margin instead).
STATUS_COLOUR = {"limit": "#f6c26b", "FAIL": "#e05a5a", "not run": "#c8c8c8"}
#: A pass's shade: light at error / tolerance 1, dark at this ratio and below.
DARKEST_RATIO = 1e-6
#: Inches per row and per engine column (a 12 x 5 grid is ~640 px wide at 100 dpi).
ROW_IN, COL_IN = 0.27, 0.92
#: Resolution of the overview PNG (shown at its own size on the first screen).
DPI = 100


@dataclass(frozen=True)
class OverviewCell:
    """One run: its row (``case``, or ``case (free)``), engine, worst error over its
    tolerance (``ratio``, NaN: not run) and ``status``: ``pass``, ``limit``, ``FAIL``
    or ``not run``."""

    row: str
    engine: str
    ratio: float
    status: str


def ratio_text(r: float) -> str:
    """A cell's number: two significant digits, '-' when not run."""
    if not math.isfinite(r):
        return "inf" if r == math.inf else "-"
    return f"{r:.2g}"


def _cell_text(c: OverviewCell) -> str:
    """The ratio, after the verdict word where it is not a pass (a run that stopped
    has no ratio: the word alone)."""
    if c.status == "not run":
        return "not run"
    num = ratio_text(c.ratio) if math.isfinite(c.ratio) else ""
    return num if c.status == "pass" else f"{c.status} {num}".strip()


def _fill(cell: OverviewCell | None):
    if cell is None:
        return "white", "#888"
    if cell.status != "pass":
        return STATUS_COLOUR.get(cell.status, STATUS_COLOUR["not run"]), "black"
    depth = min(max(-math.log10(max(cell.ratio, 1e-300)) / -math.log10(DARKEST_RATIO), 0.0),
                1.0) if math.isfinite(cell.ratio) else 0.0
    rgba = plt.get_cmap("Greens")(0.15 + 0.7 * depth)
    return rgba, "white" if depth > 0.6 else "black"


def overview_figure(rows: list[str], engines: list[str], cells: list[OverviewCell],
                    split: int | None = None, title: str = "") -> bytes:
    """The grid: ``rows`` top to bottom, ``engines`` left to right; ``split``: the
    number of prescribed rows (a line and a label part them from the free rows)."""
    by = {(c.row, c.engine): c for c in cells}
    nr, nc = max(len(rows), 1), max(len(engines), 1)
    fig, ax = plt.subplots(figsize=(1.9 + COL_IN * nc, 0.9 + ROW_IN * nr))
    for i, row in enumerate(rows):
        for j, eng in enumerate(engines):
            c = by.get((row, eng))
            face, ink = _fill(c)
            ax.add_patch(plt.Rectangle((j, i), 1, 1, facecolor=face, edgecolor="white",
                                       lw=1.5))
            text = "" if c is None else _cell_text(c)
            ax.text(j + 0.5, i + 0.52, text, ha="center", va="center", fontsize=7.5,
                    color=ink, fontweight="bold" if c is not None and c.status == "FAIL"
                    else "normal")
    if split is not None and 0 < split < len(rows):
        ax.axhline(split, color="black", lw=1.2)
    ax.set_xlim(0, nc)
    ax.set_ylim(nr, 0)
    ax.set_xticks(np.arange(nc) + 0.5, engines, fontsize=8)
    ax.xaxis.tick_top()
    ax.set_yticks(np.arange(nr) + 0.5, rows, fontsize=8)
    ax.tick_params(length=0)
    for s in ax.spines.values():
        s.set_visible(False)
    if title:
        ax.set_title(title, fontsize=9, pad=18 if len(engines) else 6)
    ax.set_xlabel("number: worst error / its tolerance (below 1 passes); green: pass, "
                  "darker = larger margin;\namber: known or precision limit; red: FAIL; "
                  "grey: not run", fontsize=7.5, color="#444")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, bbox_inches="tight", pad_inches=0.05,
                metadata={"Software": None})
    plt.close(fig)
    return buf.getvalue()


__all__ = ["OverviewCell", "overview_figure", "ratio_text"]
