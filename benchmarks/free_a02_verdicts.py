"""IFToMM A02 (the N four-bar, N = 40) judged in each engine at its recommended
free-motion settings: the rows of the free-motion verdict table.

    python benchmarks/free_a02_verdicts.py run ENGINE OUT.json [--duration S] [--samples N]
        [--wall-limit S]
    python benchmarks/free_a02_verdicts.py table RUN.json [RUN.json ...]

``run`` does what ``xval simulate iftomm-a02-n-four-bar --engine ENGINE --json`` does
(:mod:`reports.cli.simulate_engines`: the built-in case, the engine's recommended free
settings, :func:`sim_models.runs.free.run_free`, judged by
:func:`reports.comparison.free_compare.compare_free` against the exact trajectory at
the case's 401 samples) with one difference: the run's wall-clock limit
(:attr:`sim_models.runs.free_run.FreeRequest.wall_limit`, 120 s in ``xval simulate``) is
``--wall-limit`` (default 3600 s), because A02's 20 s take PyBullet and Pinocchio longer
than 120 s on this machine.  It writes the verdict's JSON (``FreeVerdict.as_json``
without the per-quantity list, which has ~650 entries at N = 40; the ten worst of them
are kept) with the run's notes, the reference's and the judging's wall time and the
load average before and after.  ``table`` prints the Markdown rows (worst error of
range and its quantity, trusted horizon, energy and loop drift, CPU per simulated
second, IFToMM class and B0 error, status).  One engine per process.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time

CASE = "iftomm-a02-n-four-bar"


def run(engine: str, out: str, duration: float, samples: int, wall_limit: float) -> None:
    from analytic.free_motion import simulate
    from reports.comparison.compare import json_safe
    from reports.comparison.free_cases import command_case
    from reports.comparison.free_compare import compare_free, reference_samples
    from sim_models.runs.free import free_settings, run_free
    from sim_models.runs.free_run import FreeRequest
    load0 = os.getloadavg()
    mech, _ = command_case(CASE, duration)
    t0 = time.perf_counter()
    traj = simulate(mech, duration)
    t_ref = time.perf_counter() - t0
    # as reports.cli.simulate_engines.run_engines, with the wall-clock limit raised
    request = FreeRequest(duration=traj.duration, samples=max(1, samples - 1),
                          wall_limit=wall_limit)
    t0 = time.perf_counter()
    ref = reference_samples(traj, request.times())
    t_samples = time.perf_counter() - t0
    r = run_free(mech, engine, free_settings(engine), request, traj)
    t0 = time.perf_counter()
    v = compare_free(r, traj, ref)
    t_judge = time.perf_counter() - t0
    d = v.as_json()
    worst10 = sorted(v.judged, key=lambda c: c.normalised / c.tolerance if c.measured
                     else math.inf, reverse=True)[:10]
    d["comparisons"] = [c.as_json() for c in worst10]
    d["comparisons_note"] = f"the 10 worst of {len(v.judged)} judged quantities"
    d["worst_detail"] = v.worst.as_json()
    d.update(notes=list(r.notes), steps=int(r.steps), stepping_wall_s=float(r.wall),
             reference_wall_s=t_ref, reference_samples_wall_s=t_samples,
             judging_wall_s=t_judge, wall_limit_s=wall_limit,
             loadavg_before=list(load0), loadavg_after=list(os.getloadavg()),
             judged_quantities=len(v.judged))
    with open(out, "w") as f:
        json.dump(json_safe(d), f, indent=1, allow_nan=False)
    w = v.worst
    print(f"{engine}: {'PASS' if v.passed else 'FAIL'}; run ok={v.run_ok} ({v.reason}); "
          f"worst {w.quantity} {w.normalised:.3g} of its {w.normalisation}; horizon "
          f"{v.horizon:.4g} s; energy {v.energy.normalised:.3g}; loop "
          f"{v.loop.normalised:.3g}; CPU {v.cpu_per_simulated_second:.3g} s/s; IFToMM "
          f"{v.iftomm.level if v.iftomm else '-'} "
          f"({v.iftomm.max_error if v.iftomm else math.nan:.3g} m); stepping "
          f"{r.wall:.1f} s, reference {t_ref:.1f} s, samples {t_samples:.1f} s, "
          f"judging {t_judge:.1f} s; load {load0[0]:.2f} -> {os.getloadavg()[0]:.2f}")


def _g(x, fmt=".2g", none="-") -> str:
    return none if x is None else format(x, fmt)


def table(files: list[str]) -> None:
    print("| engine, setting | status | worst error (of range), quantity | trusted horizon "
          "| energy drift | loop drift | CPU s/s | IFToMM class (B0 max error) | load |")
    print("|---|---|---|---|---|---|---|---|---|")
    for fn in files:
        with open(fn) as f:
            d = json.load(f)
        w = d["worst_detail"]
        status = ("pass" if d["verdict"] == "pass" else "FAIL") + (
            "" if d["run_ok"] else f"; stopped at {d['t_fail_s']:.4g} s: {d['reason']}")
        worst = (f"{w['normalised']:.3g}, {w['quantity']}" if w["measured"] else
                 f"not measured from {w['measured_until_s']:.4g} s ({w['quantity']})")
        hz = ("whole run" if d["trusted_horizon_s"] is None
              else f"{d['trusted_horizon_s']:.4g} s")
        if d["lost_by"]:
            hz += f" ({d['lost_by']})"
        a = d["iftomm"]
        cls = (f"{a['level']} ({a['max_error']:.2g} m at {a['at']:.4g} s"
               + ("" if a["measured"] else ", to the stop") + ")") if a else "-"
        la = (d["loadavg_before"][0], d["loadavg_after"][0])
        print(f"| {d['engine']} ({d['integrator']}, {d['timestep']:g} s) | {status} | {worst} "
              f"| {hz} | {_g(d['energy_drift'])} | {_g(d['loop_drift'])} "
              f"| {_g(d['cpu_per_simulated_second'], '.3g')} | {cls} "
              f"| {la[0]:.1f}-{la[1]:.1f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("engine")
    r.add_argument("out")
    r.add_argument("--duration", type=float, default=20.0)
    r.add_argument("--samples", type=int, default=401)
    r.add_argument("--wall-limit", type=float, default=3600.0)
    t = sub.add_parser("table")
    t.add_argument("runs", nargs="+")
    a = ap.parse_args()
    if a.cmd == "run":
        run(a.engine, a.out, a.duration, a.samples, a.wall_limit)
    else:
        table(a.runs)


if __name__ == "__main__":
    main()
