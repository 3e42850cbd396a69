"""``python -m reports.cli.studies [--quick] [--out DIR] [--workers N] [--serial]``: the
whole speed/accuracy study (:func:`reports.studies.study.run_study`) printed as tables, and
with ``--out`` written as CSV tables and PNG figures (:func:`reports.studies.study.write_study`).

A maintainer's command, the only one of the studies that reads command-line arguments.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

from reports.studies.study import run_study, write_study


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m reports.cli.studies",
                                 description="Speed against error of the engines.")
    ap.add_argument("--quick", action="store_true", help="the reduced study (~40 s)")
    ap.add_argument("--out", type=Path, default=None, help="write CSV and PNG files here")
    ap.add_argument("--workers", type=int, default=None, help="process-pool size")
    ap.add_argument("--serial", action="store_true", help="no process pool")
    a = ap.parse_args(argv)
    res = run_study(a.quick, pool=False if a.serial else None, workers=a.workers)
    pd.set_option("display.width", 200)
    pd.set_option("display.max_colwidth", 60)
    print(res["cheapest"].drop(columns=["settings"]).to_string(index=False))
    h = res["hard"]
    print(h["high_speed"][["engine", "label", "seconds_per_rev", "accel_error",
                           "force_error", "ok"]].to_string(index=False))
    print(h["near_toggle"][["case", "engine", "label", "transmission_extreme_deg",
                            "accel_error", "force_error", "error_vs_seed_four_bar",
                            "ok"]].to_string(index=False))
    print(h["change_point"][["engine", "label", "branch_after_singular", "final_branch",
                             "flips", "ok"]].to_string(index=False))
    print(h["long_run_summary"].drop(columns=["settings"]).T.to_string(
        float_format=lambda v: f"{v:.3g}"))
    print(res["scene_economy"].drop(columns=["notes"]).to_string(index=False))
    print("analytic seconds per revolution:", res["analytic_seconds_per_rev"])
    print("timings (s):", {k: round(v, 2) for k, v in res["timings"].items()})
    if a.out:
        for p in write_study(res, a.out):
            print("wrote", p)
    return 0


if __name__ == "__main__":
    sys.exit(main())
