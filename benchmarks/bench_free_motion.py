"""Free-motion reference speed and accuracy: the IFToMM cases (a benchmark, not a test).

    python benchmarks/bench_free_motion.py [--a01-duration S]

Times :func:`analytic.free_motion.simulate` on A03 (Andrews' squeezer, 0.03 s) and A01
(the pendulum, 20 s by default; the published run is 2000 s), and prints the right-hand
side evaluations, the agreement with the published A03 reference and with a second run
at ten times the tolerance (an estimate of the integration error), and the
work-energy balance.  A02 (the N four-bar) is not run: the solver's position analysis
cannot follow its rhombus windows through the horizontal (see the README, "Free
motion").
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from analytic import load_case
from analytic.free_motion import simulate

ANDREWS_REF = {"O": 0.1581077119629904e2, "F": -0.1575637105984298e2,
               "B": 0.4082224013073101e-1, "H": -0.5347301163226948,
               "A5": 0.5244099658805304, "G": 0.5347301163226948,
               "A7": 0.1048080741042263e1}


def _timed(mech, **kw):
    t0 = time.perf_counter()
    traj = simulate(mech, **kw)
    return traj, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--a01-duration", type=float, default=20.0)
    args = ap.parse_args()
    m = load_case("iftomm-a03-andrews")
    traj, dt = _timed(m)
    loose, _ = _timed(m, rtol=1e-12)
    s, s2 = traj.at([0.03], forces=False), loose.at([0.03], forces=False)
    rel = max(abs(s.joint(j)[0, 0] / r - 1) for j, r in ANDREWS_REF.items())
    self_rel = max(abs(s.joint(j)[0, 0] / s2.joint(j)[0, 0] - 1) for j in ANDREWS_REF)
    e = traj.at(np.linspace(0, 0.03, 61), forces=False)
    print(f"A03 andrews 0.03 s: {dt:.2f} s, {traj.nfev} evaluations, max relative "
          f"difference from the published angles {rel:.2e}, from rtol 1e-12 {self_rel:.2e}, "
          f"work-energy residual {np.max(np.abs(e.energy_residual)):.2e} J")
    m = load_case("iftomm-a01-pendulum")
    traj, dt = _timed(m, duration=args.a01_duration)
    e = traj.at(np.linspace(0, args.a01_duration, 401), forces=False)
    print(f"A01 pendulum {args.a01_duration:g} s: {dt:.2f} s, {traj.nfev} evaluations, "
          f"energy residual {np.max(np.abs(e.energy_residual)):.2e} J")
    print("A02 N four-bar: not run (see the module docstring)")


if __name__ == "__main__":
    main()
