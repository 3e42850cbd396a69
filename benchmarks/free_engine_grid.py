"""Free motion in the engines: error against CPU time over a small settings grid, and
the measurements at each engine's recommended settings (a benchmark, not a test).

    python benchmarks/free_engine_grid.py grid  [--out grid.csv]
    python benchmarks/free_engine_grid.py measure [--out measure.csv]
    python benchmarks/free_engine_grid.py drift

``grid``: each engine's settings grid on A01 (5 s) and the seed four-bar released under
gravity (2 s); ``measure``: the recommended settings on A01 (20 s), A03 (0.03 s), the
released seed four-bar (2 s and 20 s); ``drift``: the released seed four-bar's energy
drift over 20 s with the step and the constraint softness varied separately.

Columns: the worst joint-coordinate error over the run and at its end, each relative to
that coordinate's range over the run (the reference's), the worst energy drift relative
to the energy scale, the worst loop gap relative to the size, and the stepping loop's
wall time per simulated second (``FreeEngineRun.wall``; readout and build excluded).
References: DOP853 at rtol 1e-13, computed once per process.
"""

from __future__ import annotations

import argparse
import csv
import functools
import os
import sys

import numpy as np

from analytic import load_case
from analytic.free_motion import simulate
from sim_models.builders.free_cases import released
from sim_models.builders.tree import SimTree
from sim_models.runs.free import free_settings, run_free
from sim_models.runs.free_run import FreeRequest

GRID = {
    "mujoco": ([{"integrator": i, "timestep": h} for i in ("RK4", "implicitfast", "Euler")
                for h in (2e-3, 1e-3, 5e-4, 2.5e-4)]
               + [{"solref": (-1 / t ** 2, -2 / t)} for t in (3e-3, 3e-2, 1e-1)]
               + [{"invweight_scale": s} for s in (1.0, 1e-5)]),
    "pybullet": ([{"timestep": h} for h in (4e-4, 1e-4, 2.5e-5)]
                 + [{"erp": e} for e in (0.2, 0.8)] + [{"solver_iterations": 100},
                                                       {"first_step": 0.0}]),
    "exudyn": [{"timestep": h, "spectral_radius": r} for h in (4e-3, 2e-3, 1e-3, 5e-4)
               for r in (0.6, 0.8, 0.95)],
}


#: The step of A03 (Andrews' squeezer, 0.03 s) in every engine, s: at the recommended
#: steps (1e-4..5e-4 s) the engines lose it (MuJoCo's loop opens at 1e-3 s, Exudyn's
#: error is 3e-3 at 1e-4 s); 1e-5 s gives MuJoCo 7.8e-6, Exudyn 3.3e-5, PyBullet 4.4e-3
#: (measured; README "Free motion in the engines").
A03_STEP = 1e-5


def case(name: str, duration: float):
    if name == "seed-released":
        return released(load_case("seed-four-bar"), duration=duration)
    return load_case(name)


@functools.lru_cache(maxsize=8)
def reference(name: str, duration: float):
    """The exact trajectory (computed once per process: it does not pickle)."""
    return simulate(case(name, duration), duration=duration)


def row(name: str, duration: float, engine: str, over: dict, samples: int = 400) -> dict:
    mech = case(name, duration)
    ref = reference(name, duration)
    run = run_free(mech, engine, free_settings(engine, over),
                   FreeRequest(duration, samples=samples), ref)
    s = ref.at(run.times, forces=False)
    rng = np.maximum(np.ptp(s.x, axis=0), 1e-12)
    err = np.abs(run.x - s.x) / rng
    E = run.kinetic + run.potential
    size = SimTree(mech).size
    with np.errstate(invalid="ignore"):
        out = {"case": name, "duration": duration, "engine": engine,
               "settings": " ".join(f"{k}={v}" for k, v in over.items()) or "recommended",
               "ok": run.ok, "reason": run.reason or "",
               "err_worst": float(np.nanmax(err)) if np.isfinite(err).any() else np.nan,
               "err_end": float(np.max(err[-1])),
               "energy_drift": float(np.nanmax(np.abs(E - run.extra["E0"])))
               / run.extra["energy_scale"],
               "gap": float(np.nanmax(run.loop_gap)) / size,
               "cpu_per_s": run.cpu_per_simulated_second, "steps": run.steps,
               "timestep": run.timestep}
    if name == "iftomm-a03-andrews":
        out["angles_end"] = " ".join(f"{j}={v:.10g}" for j, v in zip(run.joint_names,
                                                                     run.x[-1], strict=True))
    return out


def write(rows: list[dict], out: str | None) -> None:
    keys = list(dict.fromkeys(k for r in rows for k in r))
    f = open(out, "w", newline="") if out else sys.stdout  # noqa: SIM115
    w = csv.DictWriter(f, keys)
    w.writeheader()
    for r in rows:
        w.writerow({k: (f"{v:.3g}" if isinstance(v, float) else v) for k, v in r.items()})
    if out:
        f.close()


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("grid", "measure", "drift"))
    ap.add_argument("--out")
    ap.add_argument("--engines", default="mujoco,pybullet,exudyn")
    a = ap.parse_args(argv)
    engines = a.engines.split(",")
    rows = []
    if a.what == "grid":
        for name, dur in (("iftomm-a01-pendulum", 5.0), ("seed-released", 2.0)):
            for e in engines:
                for over in [{}] + GRID[e]:
                    rows.append(row(name, dur, e, over))
                    print(rows[-1], file=sys.stderr, flush=True)
    elif a.what == "measure":
        for name, dur in (("iftomm-a01-pendulum", 20.0), ("iftomm-a03-andrews", 0.03),
                          ("seed-released", 2.0), ("seed-released", 20.0)):
            for e in engines:
                # A03 is stiff (the crank reaches ~1400 rad/s): its own step
                over = {"timestep": A03_STEP} if name == "iftomm-a03-andrews" else {}
                rows.append(row(name, dur, e, over, samples=30 if dur < 0.1 else 400))
                print(rows[-1], file=sys.stderr, flush=True)
    else:
        drift = {"mujoco": [{}, {"timestep": 2.5e-4}, {"solref": (-1e2, -20.0)},
                            {"solref": (-1e6, -2e3)}],
                 "pybullet": [{}, {"timestep": 2.5e-5}, {"erp": 0.2}, {"erp": 0.5}],
                 "exudyn": [{}, {"timestep": 2.5e-4}, {"spectral_radius": 1.0},
                            {"spectral_radius": 0.95}]}
        for e in engines:
            for over in drift[e]:
                rows.append(row("seed-released", 20.0, e, over))
                print(rows[-1], file=sys.stderr, flush=True)
    write(rows, a.out)


if __name__ == "__main__":
    os.environ.setdefault("MUJOCO_GL", "disable")
    main()
