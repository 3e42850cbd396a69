"""Put a report run's headline figures into the documentation (between marker comments).

    python scripts/readme_figures.py reports/out/<timestamp>

A maintainer script, run from a checkout (with linkage-xval installed in it, ``pip
install -e .``): it edits this checkout's ``docs/``, so it is not part
of the installed package (``pyproject.toml`` installs ``analytic``, ``sim_models`` and
``reports`` only).

Rewrites the block between ``<!-- verdict:start -->`` / ``<!-- verdict:end -->`` (the
headline verdict, ``docs/explanation/engine-findings.md``) and between
``<!-- cheapest:start -->`` / ``<!-- cheapest:end -->`` (the cheapest settings,
``docs/explanation/speed.md``) from the run's CSV files and copies its speed-against-error
plot to ``docs/``; nothing is typed in by hand.
"""

from __future__ import annotations

import re
import shutil
import sys
from pathlib import Path

import pandas as pd

from analytic.input_display import input_number

#: The checkout: the folder above ``scripts/``.
ROOT = Path(__file__).resolve().parents[1]
PLOT = "pareto-seed-slider-crank.png"
#: The page each marked block lives on.
PAGES = {"verdict": ROOT / "docs" / "explanation" / "engine-findings.md",
         "cheapest": ROOT / "docs" / "explanation" / "speed.md"}


def verdict_block(run: Path) -> str:
    s = pd.read_csv(run / "verdict_summary.csv")
    meta = pd.read_csv(run / "run_metadata.csv").set_index("key")["value"]
    lines = [f"Full report run of {meta['date']} ({meta['cpu']}, {meta['cores']} cores, "
             + "".join(f"{e} {meta[e]}, " for e in ("mujoco", "pybullet", "exudyn")
                       if e in meta.index)
             + f"{meta.get('samples', 36)} samples per revolution; "
             f"{meta['wall_seconds']} s):", "",
             "| case | engine | verdict | worst quantity | worst error / peak | at |",
             "|---|---|---|---|---|---|"]
    for _, r in s.iterrows():
        # the verdict's "at" is already in the one input convention (deg in [0, 360)
        # for a full turn: analytic.input_display); shown with the same digits
        at = input_number(float(r["at (deg or m)"]))
        lines.append(f"| {r.case} | {r.engine} | {r.verdict} | {r['worst quantity']} | "
                     f"{r['worst error / peak']:.2g} | {at} |")
    return "\n".join(lines)


def cheapest_block(run: Path) -> str:
    lines = ["| case | engine | tolerance | cheapest setting | steps/rev run | ms per revolution "
             "| error |", "|---|---|---|---|---|---|---|"]
    for f in sorted(run.glob("cheapest_*.csv")):
        for _, r in pd.read_csv(f).iterrows():
            ms = f"{r.seconds_per_rev * 1e3:.2g}" if pd.notna(r.seconds_per_rev) else ""
            err = f"{r.error:.2g}" if pd.notna(r.error) else ""
            spr = f"{r.steps_per_rev:.0f}" if pd.notna(r.steps_per_rev) else ""
            lines.append(f"| {r.case} | {r.engine} | {r.tolerance:g} | {r.label} | {spr} | "
                         f"{ms} | {err} |")
    return "\n".join(lines)


def replace_block(text: str, name: str, body: str, where: str = "the page") -> str:
    pat = re.compile(rf"(<!-- {name}:start -->\n).*?(<!-- {name}:end -->)", re.S)
    if not pat.search(text):
        raise SystemExit(f"{where} has no {name} markers")
    return pat.sub(lambda m: m.group(1) + body + "\n" + m.group(2), text)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        raise SystemExit(__doc__)
    run = Path(argv[0])
    blocks = {"verdict": verdict_block(run), "cheapest": cheapest_block(run)}
    for name, page in PAGES.items():
        page.write_text(replace_block(page.read_text(), name, blocks[name],
                                      str(page.relative_to(ROOT))))
    shutil.copy(run / "img" / PLOT, ROOT / "docs" / PLOT)
    print(f"{', '.join(str(p.relative_to(ROOT)) for p in PAGES.values())} updated from {run}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
