"""``xval report``'s run: the options into a :class:`reports.report.ReportConfig`,
progress by phase, the console verdict and the wall time (registered with the engine
commands in :mod:`reports.cli_engines`; the report itself is :mod:`reports.report`).
"""

from __future__ import annotations

import datetime as _dt
import time
from pathlib import Path

import pandas as pd
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from . import report
from .console import print_verdict
from .report_tables import accepted


def run(args) -> int:
    """``xval report`` entry point: progress by phase, the console verdict, wall time."""
    t0 = time.perf_counter()
    stamp = _dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    out = Path(args.out) if args.out else report.DEFAULT_OUT / stamp
    cfg = report.ReportConfig(out=out, quick=args.quick, cases=tuple(args.cases or ()),
                              samples=36 if args.quick else 72, workers=args.workers,
                              dask=args.dask)
    console = Console(width=100)
    with Progress(TextColumn("{task.description:<17}"), BarColumn(bar_width=30),
                  TextColumn("{task.completed}/{task.total}"), TimeElapsedColumn(),
                  console=console, transient=False) as pg:
        ids = {}

        def progress(stage, done, total):
            if stage not in ids:
                ids[stage] = pg.add_task(stage, total=total)
            pg.update(ids[stage], completed=done, total=total)
            if done >= total:
                pg.stop_task(ids[stage])

        path = report.build_report(cfg, progress)
    summary = pd.read_csv(path / "verdict_summary.csv", keep_default_na=False,
                          na_values=[""])
    print_verdict(summary)
    wall = time.perf_counter() - t0
    phases = pd.read_csv(path / "phases.csv")
    print(f"wall time {wall:.1f} s ("
          + ", ".join(f"{r.phase} {r.seconds:.1f} s" for r in phases.itertuples()) + ")")
    print(f"report: {path / 'index.html'}  ({path / 'report.md'})")
    # a failed verdict: status 1 (a precision limit of a float32 engine is not one)
    return 0 if accepted(summary).all() else 1


__all__ = ["run"]
