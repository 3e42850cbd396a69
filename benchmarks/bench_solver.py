"""Solver speed and memory against pylinkage and a hand-written closed form, one process.

Everything is measured in one process, interleaved (each repeat runs every method
once, in turn), so the ratios hold on a shared, noisy machine even when the absolute
rates move.  Sizes 360 / 3.6k / 36k / 360k / 3.6M input values of the S4 four-bar
(``seed-four-bar``) and the Watt six-bar (``six-bar``).

Methods (configurations per second, min and median over the repeats):

* ``hand_kinematics``: a vectorised numpy closed form of the four-bar's angles, rates
  and accelerations written out by hand (no forces): the yardstick;
* ``pylinkage_positions`` / ``pylinkage_kinematics``: pylinkage's numba solver
  (``step_fast`` / ``step_fast_with_kinematics``) on the same four-bar (optional: the
  ``bench`` extra);
* ``fused_joint_positions``: the fused kernel's joint points (every joint's x + iy,
  the output of pylinkage's ``step_fast``; checked equal to it to 1e-12 m first);
* ``fused_positions``: the fused kernel's poses (every body's ``exp(i theta)`` and
  origin, from which every point follows: what pylinkage's joint coordinates hold);
  ``fused_angles``: the same plus the unwrapped angles ``q``;
* ``fused_kinematics``: ``q, q', q''`` (every body's angle, rate, acceleration and
  every slider's); ``fused_kinematics_forces``: plus every joint force, the drive
  effort and the power terms, in the same pass (:meth:`analytic.fused.FusedKernel.state`);
* ``fused_..._preallocated``: the same into outputs allocated once (blocked
  evaluation reuses its outputs so; fresh outputs pay the kernel's page faults);
* ``linkage_kinematics``, ``linkage_solve``, ``linkage_kinematics_forces``: through the
  front door (the kernel at every size once loaded): ``Linkage.kinematics(x)``,
  ``Linkage.solve(x)`` and ``Linkage.forces(Linkage.kinematics(x))``, the last one pass
  of the kernel from its second call on (the kinematics pass writes the forces while
  the caller reads them: ``Linkage._forces_guess``).  Each has its own ``Linkage``, as
  a caller repeating one call has (one ``Linkage`` that alternates kinematics-only
  and kinematics + forces calls pays one extra pass at each switch);
* ``numpy_kinematics_forces``: the same on the numpy path (``XVAL_FUSED=0``), up to
  360k points (at 3.6M it holds several GB).

Each repeat times ``max(1, 36000 // n)`` calls in a row (the time per call is their
mean), then the next method: small sizes are not one interruption away from a wrong min.

Memory: tracemalloc's peak during one call, per configuration (numba-allocated arrays,
as pylinkage's, are invisible to it), and the process's resident peak.

    python benchmarks/bench_solver.py [--sizes 360,3600,...] [--json FILE]
        [--cli-points 10000000]   # also time `xval sweep seed-four-bar --csv` in /usr/bin/time -v
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
import tracemalloc

import numpy as np

from analytic import Linkage, load_case
from analytic.fused import COMPILE_LOG, FusedKernel
from analytic.perf import tune_allocator

A, B, C, D, W2 = 0.1, 0.3, 0.25, 0.4, 15.0  # the S4 four-bar, m and rad/s
SIZES = (36, 360, 3600, 36_000, 360_000, 3_600_000)


def hand_four_bar(th2, a=A, b=B, c=C, d=D, w2=W2):
    """Angles, rates and accelerations of the S4 four-bar, written out by hand."""
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
    Cc = a * w2 * w2 * c2 + b * w3 * w3 * c3 - c * w4 * w4 * c4
    F = -a * w2 * w2 * s2 - b * w3 * w3 * s3 + c * w4 * w4 * s4
    det = c * s4 * b * c3 - b * s3 * c * c4
    al3 = (Cc * c * c4 - c * s4 * F) / det
    al4 = (Cc * b * c3 - b * s3 * F) / det
    return th3, th4, w3, w4, al3, al4


def pylinkage_four_bar(n: int):
    """The same four-bar in pylinkage, stepping 2 pi / n per step at 15 rad/s."""
    from pylinkage.actuators import Crank
    from pylinkage.components import Ground
    from pylinkage.dyads import RRRDyad
    from pylinkage.simulation import Linkage as PL
    o2, o4 = Ground(0.0, 0.0, name="O2"), Ground(D, 0.0, name="O4")
    crank = Crank(anchor=o2, radius=A, angular_velocity=2 * math.pi / n, name="A")
    rocker = RRRDyad(crank.output, o4, distance1=B, distance2=C, name="B")
    pl = PL([o2, o4, crank, rocker], name="four-bar")
    pl.set_input_velocity(crank, omega=W2)
    return pl


def machine() -> dict:
    model = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            model = next(ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name"))
    except (OSError, StopIteration):
        pass
    import numba
    return {"cpu": model, "cores": os.cpu_count(), "python": platform.python_version(),
            "numpy": np.__version__, "numba": numba.__version__,
            "pylinkage": _version("pylinkage")}


def _version(mod):
    try:
        from importlib.metadata import version
        return version(mod)
    except Exception:  # noqa: BLE001 - not installed
        return None


def load() -> str:
    return "load average {:.2f} {:.2f} {:.2f}".format(*os.getloadavg())


def methods(n: int, with_pylinkage: bool, numpy_path: bool) -> dict:
    x = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    lk4, lk6 = Linkage(load_case("seed-four-bar")), Linkage(load_case("six-bar"))
    # the front door's calls, each on its own Linkage (see the module docstring)
    lk_k, lk_s, lk_kf = (Linkage(load_case("seed-four-bar")) for _ in range(3))
    fk4, fk6 = FusedKernel(lk4), FusedKernel(lk6)
    fns = {"hand_kinematics": lambda: hand_four_bar(x)}
    if with_pylinkage:
        pl = pylinkage_four_bar(n)
        fns["pylinkage_positions"] = lambda: pl.step_fast(iterations=n)
        fns["pylinkage_kinematics"] = lambda: pl.step_fast_with_kinematics(iterations=n)
    out2, out3 = fk4.alloc(n, 2), fk4.alloc(n, 3)
    fns.update({
        "fused_joint_positions": lambda: fk4.joint_positions(x),
        "fused_positions": lambda: fk4.poses(x),
        "fused_angles": lambda: fk4.state(x, level=1),
        "fused_kinematics": lambda: fk4.state(x, level=2),
        "fused_kinematics_forces": lambda: fk4.state(x, level=3),
        "fused_kinematics_preallocated": lambda: fk4.state(x, level=2, out=out2),
        "fused_kinematics_forces_preallocated": lambda: fk4.state(x, level=3, out=out3),
        "six_bar_fused_kinematics_forces": lambda: fk6.state(x, level=3),
        "linkage_kinematics": lambda: lk_k.kinematics(x),
        "linkage_solve": lambda: lk_s.solve(x),
        "linkage_kinematics_forces": lambda: lk_kf.forces(lk_kf.kinematics(x)),
    })
    if numpy_path:
        def numpy_kf():
            os.environ["XVAL_FUSED"] = "0"
            try:
                return lk4.forces(lk4.kinematics(x))
            finally:
                del os.environ["XVAL_FUSED"]
        fns["numpy_kinematics_forces"] = numpy_kf
    return fns


def same_four_bar(n: int = 360) -> float:
    """Largest distance (m) between pylinkage's joint positions and the kernel's on the
    same four-bar at the same crank angles: the two solve the same problem."""
    pl = pylinkage_four_bar(n)
    got = np.asarray(pl.step_fast(iterations=n))  # step k: crank at 2 pi (k + 1) / n
    theirs = got[..., 0] + 1j * got[..., 1]
    fk = FusedKernel(Linkage(load_case("seed-four-bar")))
    ours = fk.joint_positions(2 * math.pi * np.arange(1, n + 1) / n)
    # pylinkage's joints: O2, O4, A, B; ours in the description's order O2, A, B, O4
    return float(np.max(np.abs(theirs - ours[:, [0, 3, 1, 2]])))


def repeats(n: int) -> int:
    return max(3, min(40, int(2e6 / n)))


def calls_per_repeat(n: int) -> int:
    """Calls timed together in one repeat: ~36,000 configurations' worth, so that a
    repeat at 360 points lasts milliseconds (one call, tens of microseconds, is at the
    mercy of a single interruption on a shared machine).  Every method gets the same."""
    return max(1, 36_000 // n)


def measure(n: int, with_pylinkage: bool) -> dict:
    fns = methods(n, with_pylinkage, numpy_path=n <= 360_000)
    for f in fns.values():  # warm-up (compiles or loads the kernels)
        f()
    peak = {}
    for k, f in fns.items():
        tracemalloc.start()
        f()
        peak[k] = tracemalloc.get_traced_memory()[1] / n
        tracemalloc.stop()
    times = {k: [] for k in fns}
    inner = calls_per_repeat(n)
    for _ in range(repeats(n)):
        for k, f in fns.items():
            t0 = time.perf_counter()
            for _ in range(inner):
                f()
            times[k].append((time.perf_counter() - t0) / inner)
    out = {}
    for k, t in times.items():
        out[k] = {"rate_min_time": n / min(t), "rate_median": n / float(np.median(t)),
                  "ns_per_config_min": min(t) / n * 1e9, "bytes_per_config_peak": peak[k],
                  "repeats": len(t), "times": t}
    out["_resident_peak_MB"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return out


def ratios(res: dict) -> dict:
    """The issue's figures, each the ratio of two methods timed in the same repeats:
    the min over repeats of each, and the median of the per-repeat ratios."""
    def r(n, a, b):
        ta, tb = np.array(res[n][a]["times"]), np.array(res[n][b]["times"])
        return {"min": float(tb.min() / ta.min()), "median": float(np.median(tb / ta))}
    def t(n, a, b):  # time of a over time of b (below 1: a is faster)
        ta, tb = np.array(res[n][a]["times"]), np.array(res[n][b]["times"])
        return {"min": float(ta.min() / tb.min()), "median": float(np.median(ta / tb))}
    out = {}
    for n in res:
        row = {}
        if "pylinkage_kinematics" in res[n]:
            row["time: front door kinematics / pylinkage step_fast_with_kinematics"] = t(
                n, "linkage_kinematics", "pylinkage_kinematics")
            row["time: front door solve (kinematics + forces) / pylinkage kinematics"] = t(
                n, "linkage_solve", "pylinkage_kinematics")
        row["time: front door solve / one-pass kernel kinematics + forces"] = t(
            n, "linkage_solve", "fused_kinematics_forces")
        row["time: forces(kinematics(x)) / one-pass kernel kinematics + forces"] = t(
            n, "linkage_kinematics_forces", "fused_kinematics_forces")
        if "pylinkage_kinematics" in res[n]:
            row["kinematics / pylinkage step_fast_with_kinematics"] = r(
                n, "fused_kinematics", "pylinkage_kinematics")
            row["Linkage kinematics+forces / pylinkage step_fast_with_kinematics"] = r(
                n, "linkage_kinematics_forces", "pylinkage_kinematics")
            row["positions (joint points) / pylinkage step_fast"] = r(
                n, "fused_joint_positions", "pylinkage_positions")
            row["positions (poses) / pylinkage step_fast"] = r(
                n, "fused_positions", "pylinkage_positions")
            row["angles / pylinkage step_fast"] = r(n, "fused_angles", "pylinkage_positions")
        row["kinematics+forces / hand kinematics"] = r(n, "fused_kinematics_forces",
                                                         "hand_kinematics")
        row["Linkage kinematics+forces / hand kinematics"] = r(
            n, "linkage_kinematics_forces", "hand_kinematics")
        row["six-bar kinematics+forces / four-bar kinematics+forces"] = r(
            n, "six_bar_fused_kinematics_forces", "fused_kinematics_forces")
        if "numpy_kinematics_forces" in res[n]:
            row["kinematics+forces / numpy path"] = r(n, "fused_kinematics_forces",
                                                      "numpy_kinematics_forces")
        out[n] = row
    sizes = sorted(res)
    if 36_000 in res and sizes[-1] > 36_000:
        big = sizes[-1]
        out["flatness"] = {
            k: res[big][k]["ns_per_config_min"] / res[36_000][k]["ns_per_config_min"]
            for k in res[big] if not k.startswith("_")}
        out["flatness_sizes"] = [36_000, big]
    return out


def flatness(small: int = 36_000, big: int = 3_600_000, repeats: int = 3) -> dict:
    """Cost per configuration at ``big`` points over that at ``small``, interleaved so
    that the machine's load is the same for both: each repeat times one call at
    ``big`` and ``big // small`` calls at ``small`` (the same configurations in all)."""
    lk4 = Linkage(load_case("seed-four-bar"))
    fk4 = FusedKernel(lk4)
    xs = np.linspace(0.0, 2 * math.pi, small, endpoint=False)
    xb = np.linspace(0.0, 2 * math.pi, big, endpoint=False)
    o_s, o_b = fk4.alloc(small, 3), fk4.alloc(big, 3)
    k = big // small
    meth = {
        "hand_kinematics": lambda x, o: hand_four_bar(x),
        "fused_kinematics_forces": lambda x, o: fk4.state(x, level=3),
        "fused_kinematics_forces_preallocated": lambda x, o: fk4.state(x, level=3, out=o),
        "linkage_kinematics_forces": lambda x, o: lk4.forces(lk4.kinematics(x)),
    }
    ratios = {m: [] for m in meth}
    for _ in range(repeats):
        for m, f in meth.items():
            t0 = time.perf_counter()
            f(xb, o_b)
            tb = time.perf_counter() - t0
            t0 = time.perf_counter()
            for _ in range(k):
                f(xs, o_s)
            ts = time.perf_counter() - t0
            ratios[m].append(tb / ts)
    return {m: {"min": float(min(r)), "median": float(np.median(r)), "all": r}
            for m, r in ratios.items()}


LABELS = {
    "hand_kinematics": "hand closed form, four-bar kinematics (numpy, no forces)",
    "pylinkage_positions": "pylinkage `step_fast`, four-bar positions",
    "pylinkage_kinematics": "pylinkage `step_fast_with_kinematics`",
    "fused_joint_positions": "fused kernel, four-bar positions (every joint's x, y)",
    "fused_positions": "fused kernel, four-bar positions (every body's pose)",
    "fused_angles": "fused kernel, four-bar positions with angles",
    "fused_kinematics": "fused kernel, four-bar kinematics",
    "fused_kinematics_forces": "fused kernel, four-bar kinematics + forces",
    "fused_kinematics_preallocated": "the same, kinematics into preallocated outputs",
    "fused_kinematics_forces_preallocated": "the same, kinematics + forces preallocated",
    "six_bar_fused_kinematics_forces": "fused kernel, six-bar kinematics + forces",
    "linkage_kinematics": "`Linkage.kinematics(x)` (front door), four-bar",
    "linkage_solve": "`Linkage.solve(x)` (front door, kinematics + forces, one pass)",
    "linkage_kinematics_forces": "`Linkage.forces(Linkage.kinematics(x))`, four-bar",
    "numpy_kinematics_forces": "the same on the numpy path (`XVAL_FUSED=0`)",
}


def markdown(info: dict, res: dict, rat: dict) -> str:
    """The README's speed tables from one run."""
    sizes = sorted(res)
    lines = [f"One run, {info['machine']['cpu']} ({info['machine']['cores']} cores, shared), "
             f"Python {info['machine']['python']}, numpy {info['machine']['numpy']}, numba "
             f"{info['machine']['numba']}, pylinkage {info['machine']['pylinkage']}; "
             f"{info['load_before']} before, {info['load_after']} after.  Millions of "
             "configurations per second, min time (median) over the repeats; memory is "
             "tracemalloc's peak per configuration at the largest size measured.", "",
             "| method | " + " | ".join(f"{n:,}" for n in sizes) + " | B/config |",
             "|---|" + "---|" * (len(sizes) + 1)]
    for k, label in LABELS.items():
        cells = []
        for n in sizes:
            v = res[n].get(k)
            cells.append("-" if v is None else
                         f"{v['rate_min_time'] / 1e6:.2f} ({v['rate_median'] / 1e6:.2f})")
        big = max((n for n in sizes if k in res[n]), default=None)
        mem = "-" if big is None else f"{res[big][k]['bytes_per_config_peak']:.0f}"
        if any(c != "-" for c in cells):
            lines.append(f"| {label} | " + " | ".join(cells) + f" | {mem} |")
    lines += ["", "Ratios, each of two methods timed in the same repeats (min of each, "
              "median of the per-repeat ratios):", "",
              "| ratio | " + " | ".join(f"{n:,}" for n in sizes) + " |",
              "|---|" + "---|" * len(sizes)]
    keys = []
    for n in sizes:
        keys += [k for k in rat[n] if k not in keys]
    for k in keys:
        cells = [f"{rat[n][k]['min']:.2f} ({rat[n][k]['median']:.2f})" if k in rat[n] else "-"
                 for n in sizes]
        lines.append(f"| {k} | " + " | ".join(cells) + " |")
    if "flatness_interleaved" in rat:
        b = max(sizes)
        lines += ["", f"Cost per configuration at {b:,} points over that at 36,000, the two "
                  "interleaved in the same repeats (min, median): " + ", ".join(
                      f"{LABELS.get(k, k)} {v['min']:.2f} ({v['median']:.2f})"
                      for k, v in rat["flatness_interleaved"].items()) + "."]
    if "flatness" in rat:
        a, b = rat["flatness_sizes"]
        lines += ["", f"Cost per configuration at {b:,} points over that at {a:,} (min "
                  "times): " + ", ".join(f"`{k}` {v:.2f}" for k, v in rat["flatness"].items())
                  + "."]
    return "\n".join(lines)


def cli_sweep(points: int) -> dict:
    """``xval sweep seed-four-bar --points N --csv F`` under ``/usr/bin/time -v``."""
    with tempfile.TemporaryDirectory() as d:
        csv = os.path.join(d, "sweep.csv")
        cmd = ["/usr/bin/time", "-v", sys.executable, "-m", "reports.cli.xval", "sweep",
               "seed-four-bar", "--points", str(points), "--csv", csv]
        t0 = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        rss = next((int(ln.split(":")[1]) for ln in p.stderr.splitlines()
                    if "Maximum resident set size" in ln), None)
        rows = sum(1 for _ in open(csv)) - 1 if os.path.exists(csv) else 0
        size = os.path.getsize(csv) if os.path.exists(csv) else 0
    return {"points": points, "exit": p.returncode, "wall_s": wall,
            "max_resident_MB": rss / 1024 if rss else None, "rows": rows,
            "csv_MB": size / 2 ** 20, "stderr_tail": p.stderr.splitlines()[-3:]
            if p.returncode else []}


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default=",".join(map(str, SIZES)))
    ap.add_argument("--json", help="write the figures to this JSON file")
    ap.add_argument("--markdown", help="write the README's speed tables to this file")
    ap.add_argument("--flatness", type=int, default=3,
                    help="repeats of the interleaved 36k-vs-largest-size cost test (0: skip)")
    ap.add_argument("--startup", action="store_true",
                    help="also time first calls and xval start-up in fresh processes "
                         "(benchmarks/bench_startup.py)")
    ap.add_argument("--cli-points", type=int, default=0,
                    help="also run xval sweep seed-four-bar --points N --csv under "
                         "/usr/bin/time -v")
    return ap


def main(argv=None):
    args = _parser().parse_args(argv)
    tune_allocator()  # as the xval command does
    # the front door as a user meets it: the kernel at every size once in the process
    os.environ.pop("XVAL_FUSED", None)
    try:
        import pylinkage  # noqa: F401
        with_pl = True
    except ImportError:
        with_pl = False
        print("pylinkage not installed (pip install -e '.[bench]'): its rows are skipped")
    info = {"machine": machine(), "load_before": load(),
            "uptime": subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()}
    if with_pl:
        info["pylinkage_vs_kernel_max_m"] = d = same_four_bar()
        if not d <= 1e-12:
            raise SystemExit(f"pylinkage and the kernel disagree by {d:.3g} m: not the same "
                             "four-bar, nothing to compare")
    print(json.dumps(info, indent=1))
    t0 = time.perf_counter()
    FusedKernel(Linkage(load_case("seed-four-bar"))).state(np.zeros(4), level=3)
    info["first_call_seconds_four_bar"] = time.perf_counter() - t0
    res = {}
    for n in map(int, args.sizes.split(",")):
        res[n] = measure(n, with_pl)
        print(f"\n{n} points ({load()}, resident peak {res[n]['_resident_peak_MB']:.0f} MB)")
        for k, v in res[n].items():
            if not k.startswith("_"):
                print(f"  {k:34s} {v['rate_min_time'] / 1e6:8.3f} M/s  median "
                      f"{v['rate_median'] / 1e6:8.3f}  {v['ns_per_config_min']:8.1f} ns  "
                      f"{v['bytes_per_config_peak']:8.1f} B/config")
    rat = ratios(res)
    print("\nratios (same repeats; min of each, and median of per-repeat ratios):")
    for n, row in rat.items():
        if not isinstance(n, int):
            continue
        for k, v in row.items():
            print(f"  {n:>8} {k:62s} {v['min']:6.2f}  median {v['median']:6.2f}")
    if "flatness" in rat:
        a, b = rat["flatness_sizes"]
        print(f"\ncost per configuration at {b} / at {a} points (min times):")
        for k, v in rat["flatness"].items():
            print(f"  {k:34s} {v:6.2f}")
    if 36_000 in res and args.flatness:
        rat["flatness_interleaved"] = flatness(36_000, max(res), args.flatness)
        print(f"\ncost per configuration at {max(res)} / at 36000, interleaved repeats "
              "(min, median):")
        for k, v in rat["flatness_interleaved"].items():
            print(f"  {k:40s} {v['min']:6.2f}  median {v['median']:6.2f}")
    info["load_after"] = load()
    info["compile_log_s"] = COMPILE_LOG
    info["resident_peak_MB"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print("\n" + info["load_after"], f"; resident peak {info['resident_peak_MB']:.0f} MB")
    if args.startup:
        import bench_startup
        info["startup"] = {"cli_best_of_5_s": bench_startup.cli(),
                           "allocator_ns_per_config": bench_startup.allocator(),
                           "first_calls": bench_startup.first_calls()}
        info["load_after_startup"] = load()
        print(json.dumps(info["startup"], indent=1))
    if args.cli_points:
        info["cli_sweep"] = cli_sweep(args.cli_points)
        print("xval sweep:", json.dumps(info["cli_sweep"]))
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write(markdown(info, res, rat) + "\n")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"info": info, "results": {str(k): v for k, v in res.items()},
                       "ratios": {str(k): v for k, v in rat.items()}}, f, indent=1)
    return info, res, rat


if __name__ == "__main__":
    main()
