"""Free-motion reference speed and accuracy: the IFToMM cases (a benchmark, not a test).

    python benchmarks/bench_free_motion.py [--a01-duration S] [--a02-duration S] [--n N]

Times :func:`analytic.free_motion.simulate` on A03 (Andrews' squeezer, 0.03 s), A01
(the pendulum, 20 s by default; the published run is 2000 s) and A02 (the N four-bar,
N = 40 and 20 s as published), and prints the right-hand side evaluations, the
agreement with the published A03 reference and with a second run at ten times the
tolerance (an estimate of the integration error), the work-energy balance, and for A02
the position of B0 at 5, 10, 15 and 20 s and the horizontal crossings against the
parallelogram branch's own one-degree-of-freedom equation (every crank at the same
angle phi: ((N+1)/3 + N) phi'' = -g ((N+1)/2 + N) cos phi, integrated here by Radau).
"""

from __future__ import annotations

import argparse
import math
import time
import tomllib

import numpy as np

from analytic import load_case
from analytic.free_motion import simulate
from analytic.free_motion.iftomm import n_four_bar_toml
from analytic.toml_io import mechanism_from_dict

ANDREWS_REF = {"O": 0.1581077119629904e2, "F": -0.1575637105984298e2,
               "B": 0.4082224013073101e-1, "H": -0.5347301163226948,
               "A5": 0.5244099658805304, "G": 0.5347301163226948,
               "A7": 0.1048080741042263e1}


def _timed(mech, **kw):
    """The trajectory and the wall time of :func:`simulate` (s); the process's CPU time
    is kept in ``_timed.cpu`` (on a shared machine it says more than the wall time)."""
    t0, c0 = time.perf_counter(), time.process_time()
    traj = simulate(mech, **kw)
    _timed.cpu = time.process_time() - c0
    return traj, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--a01-duration", type=float, default=20.0)
    ap.add_argument("--a02-duration", type=float, default=20.0)
    ap.add_argument("--n", type=int, default=40)
    ap.add_argument("--only-a02", action="store_true")
    args = ap.parse_args()
    if not args.only_a02:
        _a03_a01(args)
    _a02(args.n, args.a02_duration)


def _phi_ode(n: int, duration: float):
    """The parallelogram branch as one pendulum-like equation in the crank angle."""
    from scipy.integrate import solve_ivp
    inertia, weight = (n + 1) / 3 + n, 9.81 * ((n + 1) / 2 + n)

    def rhs(t, y):
        return [y[1], -weight / inertia * math.cos(y[0])]

    def horizontal(t, y):
        return math.sin(y[0])

    return solve_ivp(rhs, (0.0, duration), [math.pi / 2, -1.0], method="Radau", rtol=1e-13,
                     atol=1e-14, dense_output=True, events=horizontal)


def _a02(n: int, duration: float) -> None:
    m = mechanism_from_dict(tomllib.loads(n_four_bar_toml(n)), "A02")
    traj, dt = _timed(m, duration=duration)
    ref = _phi_ode(n, duration)
    times = [t for t in (5.0, 10.0, 15.0, 20.0) if t <= duration] or [duration]
    s = traj.at(times, forces=False)
    k = m.bodies.index(m.body("crank0"))
    print(f"A02 N four-bar N = {n}, {duration:g} s: {dt:.1f} s ({_timed.cpu:.1f} s of CPU), "
          f"{traj.nfev} evaluations")
    for i, t in enumerate(times):
        phi = float(ref.sol(t)[0])
        b0 = np.array([math.cos(s.theta[i, k]), math.sin(s.theta[i, k])])
        err = np.hypot(*(b0 - [math.cos(phi), math.sin(phi)]))
        print(f"  t = {t:g} s: B0 = ({b0[0]:.12f}, {b0[1]:.12f}) m, off the phi equation by "
              f"{err:.2e} m")
    sing = [e.t for e in traj.events if e.kind == "singular"]
    hor = ref.t_events[0]
    print(f"  singular crossings: {len(sing)} listed, {len(hor)} horizontal passes of the phi "
          "equation; largest time difference "
          f"{max(abs(a - b) for a, b in zip(sing, hor, strict=False)) if sing else math.nan:.2e} s")
    e = traj.at(np.linspace(0, duration, 81), forces=False)
    print(f"  work-energy residual {np.max(np.abs(e.energy_residual)):.2e} J")


def _a03_a01(args) -> None:
    m = load_case("iftomm-a03-andrews")
    traj, dt = _timed(m)
    cpu = _timed.cpu
    loose, _ = _timed(m, rtol=1e-12)
    s, s2 = traj.at([0.03], forces=False), loose.at([0.03], forces=False)
    rel = max(abs(s.joint(j)[0, 0] / r - 1) for j, r in ANDREWS_REF.items())
    self_rel = max(abs(s.joint(j)[0, 0] / s2.joint(j)[0, 0] - 1) for j in ANDREWS_REF)
    e = traj.at(np.linspace(0, 0.03, 61), forces=False)
    print(f"A03 andrews 0.03 s: {dt:.2f} s ({cpu:.2f} s of CPU), {traj.nfev} evaluations, "
          f"max relative difference from the published angles {rel:.2e}, from rtol 1e-12 "
          f"{self_rel:.2e}, "
          f"work-energy residual {np.max(np.abs(e.energy_residual)):.2e} J")
    m = load_case("iftomm-a01-pendulum")
    traj, dt = _timed(m, duration=args.a01_duration)
    e = traj.at(np.linspace(0, args.a01_duration, 401), forces=False)
    print(f"A01 pendulum {args.a01_duration:g} s: {dt:.2f} s, {traj.nfev} evaluations, "
          f"energy residual {np.max(np.abs(e.energy_residual)):.2e} J")


if __name__ == "__main__":
    main()
