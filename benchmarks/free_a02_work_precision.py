"""IFToMM A02 (the N four-bar, N = 40) over a short horizon: error against CPU time in
each engine over a grid of steps (work-precision).

    python benchmarks/free_a02_work_precision.py run ENGINE OUT.json --steps H [H ...]
        [--duration S] [--samples N] [--wall-limit S]
    python benchmarks/free_a02_work_precision.py plot OUT.png RUN.json [RUN.json ...]

``run`` releases the built-in case ``iftomm-a02-n-four-bar`` for ``--duration`` s
(default 2 s: the first zero-base pass at 0.7216 s and the first stretched pass at
1.2440 s are inside) in one engine at its recommended free-motion settings with only
the step changed, once per step, each run judged as the report's work-precision grid
judges it (:func:`reports.studies.free_studies.free_row` of
:func:`reports.comparison.free_compare.compare_free`, the exact trajectory computed
once) and writes one JSON row per step: the IFToMM reference point's (B0) largest
position error over the run, m; the judging's worst error (of its scale) and its
quantity; CPU seconds of the stepping loop per simulated second stepped; whether the
run reached the end.  A run that stopped keeps its errors up to the stop (``t_fail``)
and is drawn hollow.  ``--wall-limit`` (default 900 s) replaces the 120 s of
:class:`sim_models.runs.free_run.FreeRequest`.  ``plot`` draws both errors against CPU per
simulated second, one line per engine, each point labelled with its step.  One engine
per process.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from dataclasses import asdict

CASE = "iftomm-a02-n-four-bar"
#: The IFToMM accuracy bars on B0's position over the run, m.
BARS = (1e-3, 1e-1)


def _worst_measured(v) -> tuple[str, float]:
    """The judged quantity with the largest error over its tolerance on the measured
    samples, and its error (of its scale): for a run that stopped, the verdict's own
    ``worst`` is the first quantity not measured to the end, whatever its error."""
    c = max(v.judged, key=lambda c: c.normalised / c.tolerance
            if math.isfinite(c.normalised) else -1.0)
    return c.quantity, float(c.normalised)


def run(engine: str, out: str, steps: list[float], duration: float, samples: int,
        wall_limit: float) -> None:
    from analytic.free_motion import simulate
    from reports.comparison.compare import json_safe
    from reports.comparison.free_cases import free_case
    from reports.comparison.free_compare import compare_free, reference_samples
    from reports.studies.free_studies import free_row
    from sim_models.runs.free import free_settings, run_free
    from sim_models.runs.free_run import FreeRequest
    mech = free_case(CASE, duration)
    t0 = time.perf_counter()
    traj = simulate(mech)
    req = FreeRequest(duration=duration, samples=samples, wall_limit=wall_limit)
    ref = reference_samples(traj, req.times())
    t_ref = time.perf_counter() - t0
    rows = []
    for h in steps:
        load0 = os.getloadavg()[0]
        r = run_free(mech, engine, free_settings(engine, {"timestep": h}), req, traj)
        v = compare_free(r, traj, ref)
        row = asdict(free_row(r, v))
        wq, we = _worst_measured(v)
        row.update(step=h, t_fail=r.t_fail, worst_measured=wq, worst_measured_error=we,
                   measured_until=min(c.measured_until for c in v.judged),
                   load_before=load0, load_after=os.getloadavg()[0])
        rows.append(row)
        print(f"{engine} h={h:g}: ok={r.ok} ({r.reason}); B0 {row['position_error']:.3g} m; "
              f"worst {wq} {we:.3g}; CPU {row['cpu_per_s']:.3g} s/s; stepping {r.wall:.1f} s;"
              f" load {load0:.2f}", flush=True)
    with open(out, "w") as f:
        sing = [e.t for e in traj.events if e.kind == "singular"]
        json.dump(json_safe({"engine": engine, "case": CASE, "duration": duration,
                             "singular_s": sing,
                             "samples": samples, "reference_wall_s": t_ref, "rows": rows}),
                  f, indent=1, allow_nan=False)


def plot(png: str, files: list[str]) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    data = []
    for fn in files:
        with open(fn) as f:
            data.append(json.load(f))
    dur = data[0]["duration"]
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.6))
    keys = (("position_error", "B0 largest position error over the run (m)"),
            ("worst_measured_error", "judging's worst error (of its scale)"))
    loads = [x for d in data for r in d["rows"] for x in (r["load_before"], r["load_after"])]
    for d, color in zip(data, plt.rcParams["axes.prop_cycle"].by_key()["color"],
                        strict=False):
        rows = sorted(d["rows"], key=lambda r: r["cpu_per_s"] or math.inf)
        for ax, (key, _) in zip(axes, keys, strict=True):
            xs = [r["cpu_per_s"] for r in rows]
            ys = [r[key] for r in rows]
            ok = [bool(r["ok"]) for r in rows]
            integ = rows[0]["integrator"].split(" (")[0]
            ax.plot(xs, ys, "-", color=color, lw=1.2, alpha=0.6)
            if any(ok):
                ax.plot([x for x, o in zip(xs, ok, strict=True) if o],
                        [y for y, o in zip(ys, ok, strict=True) if o], "o", color=color,
                        label=f"{d['engine']} ({integ})")
            if not all(ok):
                ax.plot([x for x, o in zip(xs, ok, strict=True) if not o],
                        [y for y, o in zip(ys, ok, strict=True) if not o], "o",
                        mfc="white", color=color,
                        label=f"{d['engine']} ({integ}): stopped at " + ", ".join(
                            sorted({f"{r['t_fail']:.3g} s" for r in rows if not r["ok"]}))
                        + " (error up to the stop)")
            for i, (r, x, y) in enumerate(zip(rows, xs, ys, strict=True)):
                txt = f"{r['step']:g} s"
                # alternate above and below: neighbouring steps of a flat line
                ax.annotate(txt, (x, y), textcoords="offset points",
                            xytext=(4, 5 if i % 2 == 0 else -12), fontsize=7, color=color)
    for ax, (key, label) in zip(axes, keys, strict=True):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU s of stepping per simulated s")
        ax.set_ylabel(label)
        ax.grid(True, which="major", alpha=0.3)
        if key == "position_error":
            for b in BARS:
                ax.axhline(b, color="grey", ls=":", lw=1)
                ax.text(0.01, b * 1.15, f"IFToMM bar {b:g} m", color="grey", fontsize=8,
                        transform=ax.get_yaxis_transform())
        else:
            for tol, what in ((1e-2, "coordinates, angles, rates"),
                              (5e-2, "accelerations, reactions")):
                ax.axhline(tol, color="grey", ls=":", lw=1)
                ax.text(0.01, tol * 1.15, f"tolerance {tol:g} ({what})", color="grey",
                        fontsize=8, transform=ax.get_yaxis_transform())
            worst = {r["worst_measured"].rsplit(".", 1)[-1] for d in data for r in d["rows"]}
            if worst == {"force"}:
                ax.set_title("every point's worst quantity is a joint reaction", fontsize=9)
    axes[0].set_title("B0 (tip of crank0): the IFToMM accuracy measure", fontsize=9)
    axes[0].legend(fontsize=8, loc="upper right")
    passes = ", ".join(f"{t:.4f} s" for t in data[0].get("singular_s", []))
    fig.suptitle(f"IFToMM A02 (N = 40), first {dur:g} s (horizontal passes at {passes or 'none'}):"
                 f" error against CPU, each engine's step grid\n"
                 f"recommended settings with the step changed; one engine per process on "
                 f"a shared 2-core machine, load {min(loads):.1f} to {max(loads):.1f}",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    for d in data:
        for r in sorted(d["rows"], key=lambda r: r["step"], reverse=True):
            stop = "" if r["ok"] else f"; stopped at {r['t_fail']:.4g} s: {r['reason']}"
            print(f"{d['engine']:10s} h {r['step']:<7g} B0 {r['position_error']:.2g} m, worst "
                  f"{r['worst_measured']} {r['worst_measured_error']:.2g}, CPU "
                  f"{r['cpu_per_s']:.3g} s/s, load {r['load_before']:.1f}{stop}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("engine")
    r.add_argument("out")
    r.add_argument("--steps", type=float, nargs="+", required=True)
    r.add_argument("--duration", type=float, default=2.0)
    r.add_argument("--samples", type=int, default=200)
    r.add_argument("--wall-limit", type=float, default=900.0)
    p = sub.add_parser("plot")
    p.add_argument("png")
    p.add_argument("runs", nargs="+")
    a = ap.parse_args()
    if a.cmd == "run":
        run(a.engine, a.out, a.steps, a.duration, a.samples, a.wall_limit)
    else:
        plot(a.png, a.runs)


if __name__ == "__main__":
    main()
