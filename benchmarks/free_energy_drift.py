"""Energy drift over 20 s of a conservative released linkage in every free-motion engine,
and its cause, separated by measurement (a benchmark, not a test).

    python benchmarks/free_energy_drift.py [--engines mujoco,pybullet,exudyn,pinocchio]
                                           [--samples 1001] [--out drift.csv]

The conservative case: the seed four-bar released at rest from its driver's reference
value under 9.81 m/s^2, no spring, damper, motor or load, 20 s (one loop, closed by each
engine's constraint stabilisation).  For each engine, at its recommended free-motion
setting and with one thing changed at a time:

* the **integrator's share**: the open-chain pendulum A01 (no loop constraint) with the
  same integrator and step, and the step halved on the four-bar (an integrator's drift
  falls with its order; a constraint stabilisation tied to the step does not, or grows);
* the **constraint stabilisation's share**: the loop-constraint settings at the same
  step (MuJoCo's solref time constant and solimp, PyBullet's ERP, Exudyn's rho_inf, which
  is its numerical dissipation, Pinocchio's Baumgarte gain), and MuJoCo's RK4 against
  implicitfast.

Columns: ``drift_max`` = max |E(t) - E(0)| over the samples, relative to the energy scale
(max KE + range of PE of the exact trajectory); ``drift_end`` signed, at t = 20 s
(negative: energy lost); ``gap`` = largest loop gap over the size; ``cpu`` = stepping
seconds per simulated second (``FreeEngineRun.wall``).  E is the harness's one energy
function for every engine (``sim_models/engines/free_protocol.py``), so a drift is the engine's.
References: DOP853 at rtol 1e-13, computed once per case.  Prints the machine's load.
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
from sim_models.runs.free import free_engine_names, free_settings, run_free
from sim_models.runs.free_run import FreeRequest

DURATION = 20.0
SEED = "seed-released"
A01 = "iftomm-a01-pendulum"

#: Per engine: (what it isolates, case, overrides of the recommended free settings).
PLAN = {
    "mujoco": [
        ("recommended (RK4 5e-4 s, solref 10 ms)", SEED, {}),
        ("open chain A01, same integrator and step", A01, {}),
        ("step halved (2.5e-4 s)", SEED, {"timestep": 2.5e-4}),
        ("step doubled (1e-3 s)", SEED, {"timestep": 1e-3}),
        ("solref 100 ms (softer)", SEED, {"solref": (-1e2, -20.0)}),
        ("solref 1 ms (stiffer)", SEED, {"solref": (-1e6, -2e3)}),
        ("solimp 0.9,0.95 (softer impedance)", SEED,
         {"solimp": (0.9, 0.95, 0.001, 0.5, 2.0)}),
        ("implicitfast 5e-4 s", SEED, {"integrator": "implicitfast"}),
        ("A01 implicitfast 5e-4 s", A01, {"integrator": "implicitfast"}),
    ],
    "pybullet": [
        ("recommended (1e-4 s, ERP 1)", SEED, {}),
        ("open chain A01, same integrator and step", A01, {}),
        ("step halved (5e-5 s)", SEED, {"timestep": 5e-5}),
        ("ERP 0.2", SEED, {"erp": 0.2}),
        ("ERP 0.8", SEED, {"erp": 0.8}),
    ],
    "exudyn": [
        ("recommended (5e-4 s, rho_inf 0.8)", SEED, {}),
        ("open chain A01, same integrator and step", A01, {}),
        ("step halved (2.5e-4 s)", SEED, {"timestep": 2.5e-4}),
        ("rho_inf 0.95", SEED, {"spectral_radius": 0.95}),
        ("rho_inf 1 (no numerical dissipation)", SEED, {"spectral_radius": 1.0}),
        ("A01 rho_inf 1", A01, {"spectral_radius": 1.0}),
    ],
    "pinocchio": [
        ("recommended (RK4 1e-3 s, Baumgarte 0.05)", SEED, {}),
        ("open chain A01, same integrator and step", A01, {}),
        ("step halved (5e-4 s)", SEED, {"timestep": 5e-4}),
        ("Baumgarte 0 (no correction)", SEED, {"baumgarte": 0.0}),
        ("Baumgarte 0.5 (stiffer)", SEED, {"baumgarte": 0.5}),
    ],
}


def case(name: str):
    if name == SEED:
        return released(load_case("seed-four-bar"), duration=DURATION)
    return load_case(name)


@functools.lru_cache(maxsize=4)
def reference(name: str):
    return simulate(case(name), duration=DURATION)


def row(engine: str, what: str, name: str, over: dict, samples: int) -> dict:
    mech = case(name)
    ref = reference(name)
    out = {"engine": engine, "what": what, "case": name,
           "settings": " ".join(f"{k}={v}" for k, v in over.items()) or "recommended"}
    try:
        run = run_free(mech, engine, free_settings(engine, over),
                       FreeRequest(DURATION, samples=samples), ref)
    except Exception as e:  # noqa: BLE001 - a refused setting is a row
        return {**out, "ok": False, "reason": f"{type(e).__name__}: {e}"}
    E = run.kinetic + run.potential
    d = (E - run.extra["E0"]) / run.extra["energy_scale"]
    fin = np.isfinite(d)
    gap = run.loop_gap[np.isfinite(run.loop_gap)] if run.loop_gap.size else np.array([])
    return {**out, "ok": run.ok, "reason": run.reason or "",
            "t_end": float(run.times[fin][-1]) if fin.any() else 0.0,
            "drift_max": float(np.max(np.abs(d[fin]))) if fin.any() else np.nan,
            "drift_end": float(d[fin][-1]) if fin.any() else np.nan,
            "gap": float(np.max(gap)) / SimTree(mech).size if gap.size else np.nan,
            "cpu": run.cpu_per_simulated_second, "timestep": run.timestep,
            "integrator": run.integrator}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--engines", default=",".join(free_engine_names()))
    ap.add_argument("--samples", type=int, default=1001)
    ap.add_argument("--out")
    a = ap.parse_args(argv)
    print(f"load before: {os.getloadavg()}", file=sys.stderr, flush=True)
    rows = []
    for e in a.engines.split(","):
        for what, name, over in PLAN.get(e, []):
            rows.append(row(e, what, name, over, a.samples))
            print(rows[-1], file=sys.stderr, flush=True)
    print(f"load after: {os.getloadavg()}", file=sys.stderr, flush=True)
    keys = list(dict.fromkeys(k for r in rows for k in r))
    f = open(a.out, "w", newline="") if a.out else sys.stdout  # noqa: SIM115
    w = csv.DictWriter(f, keys)
    w.writeheader()
    for r in rows:
        w.writerow({k: (f"{v:.3g}" if isinstance(v, float) else v) for k, v in r.items()})
    if a.out:
        f.close()


if __name__ == "__main__":
    os.environ.setdefault("MUJOCO_GL", "disable")
    main()
