"""Solver throughput: configurations per second for 3600-point sweeps.

Measures positions + velocities + accelerations + forces of every body and joint
for ``seed-four-bar`` and ``six-bar``, and, in the same run, a hand-written
vectorised numpy closed form of the four-bar's positions, velocities and
accelerations (no forces) as the yardstick: the machine is shared and noisy, so
the ratio is the robust figure.  Best of ``--repeat`` runs.

    python benchmarks/bench_solver.py [--points 3600] [--repeat 20] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import numpy as np

from analytic import Linkage, load_case


def hand_four_bar(th2, a=0.1, b=0.3, c=0.25, d=0.4, w2=15.0):
    """Positions, velocities, accelerations of the S4 four-bar, written out by hand."""
    ax, ay = a * np.cos(th2), a * np.sin(th2)
    ex, ey = d - ax, -ay
    D2 = ex * ex + ey * ey
    k = (b * b - c * c + D2) / (2 * D2)
    h = np.sqrt(b * b / D2 - k * k)
    bx, by = ax + k * ex - h * ey, ay + k * ey + h * ex
    th3 = np.arctan2(by - ay, bx - ax)
    th4 = np.arctan2(by, bx - d)
    s23, s34, s24 = np.sin(th2 - th3), np.sin(th3 - th4), np.sin(th4 - th2)
    w3 = a * w2 / b * s24 / s34
    w4 = a * w2 / c * (-s23) / (-s34)
    c2, c3, c4 = np.cos(th2), np.cos(th3), np.cos(th4)
    s2, s3, s4 = np.sin(th2), np.sin(th3), np.sin(th4)
    C = a * w2 * w2 * c2 + b * w3 * w3 * c3 - c * w4 * w4 * c4
    F = -a * w2 * w2 * s2 - b * w3 * w3 * s3 + c * w4 * w4 * s4
    det = c * s4 * b * c3 - b * s3 * c * c4
    al3 = (C * c * c4 - c * s4 * F) / det
    al4 = (C * b * c3 - b * s3 * F) / det
    return th3, th4, w3, w4, al3, al4


def best(fn, repeat):
    fn()
    t = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        t.append(time.perf_counter() - t0)
    return min(t)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=3600)
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--json", help="write the figures to this JSON file")
    args = ap.parse_args(argv)
    n = args.points
    x = np.linspace(0, 2 * np.pi, n, endpoint=False)
    out = {"points": n, "machine": platform.processor() or platform.machine(),
           "python": platform.python_version(), "numpy": np.__version__}
    from analytic.perf import tune_allocator

    def measure(suffix):
        t_hand = best(lambda: hand_four_bar(x), args.repeat)
        out[f"hand_closed_form_four_bar_kinematics{suffix}"] = n / t_hand
        for case in ("seed-four-bar", "six-bar"):
            lk = Linkage(load_case(case))
            t_kin = best(lambda lk=lk: lk.kinematics(x), args.repeat)
            t_all = best(lambda lk=lk: lk.forces(lk.kinematics(x)), args.repeat)
            out[f"{case}_kinematics{suffix}"] = n / t_kin
            out[f"{case}_kinematics_and_forces{suffix}"] = n / t_all

    # the same process, first with glibc's default allocator, then tuned
    # (analytic.perf.tune_allocator, as the xval command runs)
    measure("_default_allocator")
    out["allocator_tuned"] = tune_allocator()
    measure("")
    print(f"{n}-point sweeps, best of {args.repeat} (configurations per second):")
    for k, v in out.items():
        if isinstance(v, float):
            print(f"  {k:63s} {v / 1e6:8.3f} M/s")
    ratio = (out["seed-four-bar_kinematics_and_forces"]
             / out["hand_closed_form_four_bar_kinematics"])
    out["ratio_four_bar_with_forces_to_hand_kinematics"] = ratio
    print(f"  ratio solver(four-bar, with forces) / hand closed form (no forces): {ratio:.3f}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=2)
    return out


if __name__ == "__main__":
    main()
