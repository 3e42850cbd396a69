"""``xval report``'s run: the options into a :class:`reports.report.build.ReportConfig`,
progress by phase, the console verdict and the wall time (the report itself is
:mod:`reports.report.build`).
"""

from __future__ import annotations

import datetime as _dt
import time
from pathlib import Path

import pandas as pd
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from analytic.errors import OutputError
from reports.cli import options as opt
from reports.cli.compare import note_skipped_engines
from reports.report import build as report
from reports.report.console import free_counts_line, free_failure_lines, print_verdict
from reports.report.tables import accepted


def run(args) -> int:
    """``xval report`` entry point: progress by phase, the console verdict, wall time."""
    t0 = time.perf_counter()
    stamp = _dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    out = Path(args.out) if args.out else report.DEFAULT_OUT / stamp
    cfg = report.ReportConfig(out=out, quick=args.quick, cases=tuple(args.cases or ()),
                              samples=report.SAMPLES[args.quick], workers=args.workers,
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
    free = _free_verdicts(path)
    if free is not None:
        for ln in free_failure_lines(free) + [free_counts_line(free)]:
            print(ln)
    wall = time.perf_counter() - t0
    phases = pd.read_csv(path / "phases.csv")
    print(f"wall time {wall:.1f} s ("
          + ", ".join(f"{r.phase} {r.seconds:.1f} s" for r in phases.itertuples()) + ")")
    print(f"report: {path / 'index.html'}  ({path / 'report.md'})")
    return exit_status(summary, free)


def _free_verdicts(path: Path) -> pd.DataFrame | None:
    """The report's free-motion verdicts, None when it ran no free-motion section."""
    f = path / "free_verdicts.csv"
    if not f.exists():
        return None
    return pd.read_csv(f, keep_default_na=False, na_values=[""])


def exit_status(summary: pd.DataFrame, free: pd.DataFrame | None) -> int:
    """1 when any prescribed verdict or any free-motion verdict failed (a precision
    limit of a float32 engine, and a listed known engine limit, reports/comparison/free_limits.py,
    are reported and not counted), else 0."""
    failed = not accepted(summary).all()
    if free is not None and len(free):
        failed = failed or bool((free["verdict"].astype(str) == "FAIL").any())
    return 1 if failed else 0


__all__ = ["exit_status", "run"]


def cmd_report(args) -> int:
    try:
        status = run(args)
        note_skipped_engines()  # the report ran every installed engine (after the
        return status           # inputs were checked: bad input stays one line)
    except OSError as e:  # the output folder was checked at --out; a race or a full disk
        if e.filename is None:
            raise
        raise OutputError(f"cannot write {e.filename!r}: {e.strerror}") from None


def register(sub) -> None:
    """Add ``report`` to ``xval``'s subparsers."""
    s = sub.add_parser("report", help="the validation report (HTML, Markdown, CSV)")
    s.add_argument("--out", type=opt.output_dir,
                   help="output directory (default reports/out/<timestamp>)")
    s.add_argument("--quick", action="store_true",
                   help="the quick variant (about 25 s on an idle 2-core machine)")
    s.add_argument("--cases", nargs="+", type=opt.case_or_file,
                   help="only these cases (built-in names or TOML files)")
    s.add_argument("--workers", type=opt.workers,
                   help=f"process-pool size, 1 to {opt.MAX_WORKERS} (default: cores)")
    s.add_argument("--dask", metavar="SCHEDULER_ADDRESS", type=opt.scheduler_address,
                   help="run the study tasks on an existing Dask distributed scheduler")
    s.set_defaults(func=cmd_report)
