"""IFToMM A02 (the N four-bar) in every engine at its recommended free-motion settings.

    python benchmarks/free_a02_engines.py run ENGINE OUT.npz [--duration S] [--n N]
    python benchmarks/free_a02_engines.py plot OUT.png RUN.npz [RUN.npz ...]

``run`` releases A02 in one engine (``sim_models.runs.free.run_free`` with the
engine's default :func:`sim_models.runs.free.free_settings`) and saves, at the 401
published sample times, the position of B0 (tip of ``crank0``: its pin is the
origin and the link is 1 m, so B0 = (cos, sin) of its angle) from the engine and from
the reference (:func:`analytic.free_motion.simulate`), the run's status and its
stepping time.  ``plot`` draws B0's x against time for the reference and each engine
and each engine's B0 error against time (log scale, with the IFToMM accuracy bars
1e-3 and 1e-1 m), and prints each engine's accuracy class: the largest B0 error over
the run within 1e-3 m, within 1e-1 m, or neither.  Each engine is a separate process
so that slow ones run side by side (the wall-clock limit of one run is
``--wall-limit`` s; a run stopped by it says so).
"""

from __future__ import annotations

import argparse
import math
import time
import tomllib

import numpy as np

#: IFToMM accuracy bars on the reference point's position over the run (m).
CLASSES = (1e-3, 1e-1)


def _a02(n: int):
    from analytic.free_motion.iftomm import n_four_bar_toml
    from analytic.toml_io import mechanism_from_dict
    return mechanism_from_dict(tomllib.loads(n_four_bar_toml(n)), f"iftomm-a02 N={n}")


def run(engine: str, out: str, duration: float, n: int, wall_limit: float) -> None:
    from analytic.free_motion import simulate
    from sim_models.runs.free import free_settings, run_free
    from sim_models.runs.free_run import FreeRequest
    m = _a02(n)
    t0 = time.perf_counter()
    ref = simulate(m, duration=duration)
    t_ref = time.perf_counter() - t0
    req = FreeRequest(duration=duration, samples=400, wall_limit=wall_limit)
    r = run_free(m, engine, free_settings(engine), req, reference=ref)
    k = list(r.body_names).index("crank0")
    th = r.theta[:, k]
    s = ref.at(r.times, forces=False)
    th_ref = s.theta[:, m.bodies.index(m.body("crank0"))]
    np.savez(out, engine=engine, t=r.times, b0=np.stack([np.cos(th), np.sin(th)], 1),
             b0_ref=np.stack([np.cos(th_ref), np.sin(th_ref)], 1), ok=r.ok,
             reason=str(r.reason), t_fail=np.nan if r.t_fail is None else r.t_fail,
             wall=r.wall, steps=r.steps, timestep=r.timestep, integrator=r.integrator,
             t_ref=t_ref, n=n, duration=duration)
    print(f"{engine}: ok={r.ok} ({r.reason}), {r.steps} steps of {r.timestep:g} s "
          f"({r.integrator}), stepping {r.wall:.1f} s; reference {t_ref:.1f} s")


def _class(err: float) -> str:
    for c in CLASSES:
        if err <= c:
            return f"within {c:g} m"
    return f"outside {CLASSES[-1]:g} m"


def plot(png: str, runs: list[str]) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    data = [dict(np.load(f, allow_pickle=False)) for f in runs]
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(12.5, 7.5), sharex=True)
    d0 = data[0]
    ax1.plot(d0["t"], d0["b0_ref"][:, 0], "k-", lw=2.5, label="reference (exact, 1e-9 m)")
    rows = []
    for d in data:
        e = str(d["engine"])
        err = np.hypot(*(d["b0"] - d["b0_ref"]).T)
        fin = np.isfinite(err)
        worst = float(np.max(err[fin])) if fin.any() else math.nan
        label = (f"{e} ({str(d['integrator']).split(' (')[0]}, h = {float(d['timestep']):g} s)"
                 + ("" if bool(d["ok"]) else f": stopped at {float(d['t_fail']):.3g} s"))
        ax1.plot(d["t"], d["b0"][:, 0], "--", lw=1.2, label=label)
        ax2.semilogy(d["t"][fin], np.maximum(err[fin], 1e-16), lw=1.2, label=e)
        rows.append((e, worst, _class(worst) if bool(d["ok"]) else "run stopped: "
                     + str(d["reason"]), float(d["wall"]), float(d["duration"])))
    # the horizontal passes of the reference (B0 crosses y = 0): the change points
    y = d0["b0_ref"][:, 1]
    for i in np.flatnonzero(np.sign(y[:-1]) * np.sign(y[1:]) < 0):
        for ax in (ax1, ax2):
            ax.axvline(0.5 * (d0["t"][i] + d0["t"][i + 1]), color="0.85", lw=0.8, zorder=0)
    for c in CLASSES:
        ax2.axhline(c, color="grey", ls=":", lw=1)
        ax2.text(d0["t"][0], c * 1.3, f"IFToMM bar {c:g} m", color="grey", fontsize=8)
    ax1.set_ylabel("B0 x (m)")
    ax1.set_title(f"IFToMM A02, N = {int(d0['n'])}: B0 (tip of crank0) against time\n"
                  "grey lines: the horizontal passes (change points of all windows)",
                  fontsize=10)
    ax1.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax2.set_ylabel("|B0 - B0 reference| (m)")
    ax2.set_xlabel("t (s)")
    ax2.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    fig.savefig(png, dpi=110, bbox_inches="tight")
    for e, worst, cls, wall, dur in rows:
        print(f"{e:10s} largest B0 error {worst:.3g} m over the run: {cls}; "
              f"stepping {wall:.1f} s ({wall / dur:.3g} s per simulated s)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("engine")
    r.add_argument("out")
    r.add_argument("--duration", type=float, default=20.0)
    r.add_argument("--n", type=int, default=40)
    r.add_argument("--wall-limit", type=float, default=3000.0)
    p = sub.add_parser("plot")
    p.add_argument("png")
    p.add_argument("runs", nargs="+")
    a = ap.parse_args()
    if a.cmd == "run":
        run(a.engine, a.out, a.duration, a.n, a.wall_limit)
    else:
        plot(a.png, a.runs)


if __name__ == "__main__":
    main()
