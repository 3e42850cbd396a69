"""Free-motion reference speed and accuracy: the IFToMM cases (a benchmark, not a test).

    python benchmarks/bench_free_motion.py [--a01-duration S] [--a02-duration S] [--n N]
    python benchmarks/bench_free_motion.py --engines [--repeats R] [--cases a,b]
    python benchmarks/bench_free_motion.py --first-call

``--engines`` (issue 34): the exact reference's CPU time, compiled equation of motion
(:mod:`analytic.free_motion.compiled`) stepped by the compiled DOP853 loop
(:mod:`analytic.free_motion.dop853`), by ``solve_ivp`` (the loop off: "exact solve_ivp")
and the numpy path before both, against each
engine at its recommended free settings (``free_settings``; A03 at ``A03_STEP``) on
the same case and duration, one process, interleaved, min and median of the repeats;
then the equation of motion's evaluations per second (one right-hand side call, as
the integrator makes it) before and after, and the largest change of any sampled
quantity against the numpy path and against ``solve_ivp`` (fraction of its range).
``--first-call``: a new process with empty kernel caches (the numpy path answers while
a background process compiles), and a second one once the caches are filled.

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
    ap.add_argument("--engines", action="store_true")
    ap.add_argument("--first-call", action="store_true")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--cases", default="seed,six-bar,a03,a02")
    args = ap.parse_args()
    if args.engines or args.first_call:
        if args.engines:
            engines_table(args.cases.split(","), args.repeats)
        if args.first_call:
            first_call()
        return
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


# --- issue 34: the reference's cost against the engines' --------------------------------
ENGINES = ("mujoco", "pinocchio", "exudyn", "pybullet")
#: A03's step in every engine (see benchmarks/free_engine_grid.py: at the recommended
#: steps the engines lose it)
A03_STEP = 1e-5
#: Quantities compared between the compiled and the numpy path (FreeSamples fields)
QUANTITIES = ("x", "xd", "xdd", "theta", "omega", "alpha", "kinetic", "potential",
              "work_motor", "work_loads", "dissipated")


def _bench_case(name: str):
    """``(mechanism, duration s, engines, engine setting overrides)``."""
    from sim_models.builders.free_cases import released
    if name in ("seed", "six-bar"):
        case = "seed-four-bar" if name == "seed" else "six-bar"
        return released(load_case(case), duration=2.0), 2.0, ENGINES, {}
    if name == "a03":
        return load_case("iftomm-a03-andrews"), 0.03, ENGINES, {"timestep": A03_STEP}
    if name == "a02":
        m = mechanism_from_dict(tomllib.loads(n_four_bar_toml(40)), "A02")
        return m, 20.0, ("mujoco",), {}
    raise SystemExit(f"unknown case {name!r}")


class _NumpyPath:
    """The reference with the compiled path off (the implementation before issue 34)."""

    def __enter__(self):
        import importlib
        self.mod = importlib.import_module("analytic.free_motion.integrate")
        self.saved = self.mod.fast_eom
        self.mod.fast_eom = lambda lk: None

    def __exit__(self, *exc):
        self.mod.fast_eom = self.saved


class _NoLoop:
    """The compiled equation of motion stepped by ``solve_ivp`` (the compiled DOP853 loop
    of :mod:`analytic.free_motion.dop853` off: the implementation before it)."""

    def __enter__(self):
        import os
        self.saved = os.environ.get("XVAL_FREE_LOOP")
        os.environ["XVAL_FREE_LOOP"] = "0"

    def __exit__(self, *exc):
        import os
        if self.saved is None:
            os.environ.pop("XVAL_FREE_LOOP", None)
        else:
            os.environ["XVAL_FREE_LOOP"] = self.saved


def _no_loop_sim(mech, T):
    with _NoLoop():
        return simulate(mech, duration=T)


def _cpu(fn):
    c0 = time.process_time()
    out = fn()
    return time.process_time() - c0, out


def _warm(mech, T):
    """Kernels compiled (or loaded) before timing: the steady state of a machine that
    ran the case once (the first call's cost is measured by ``--first-call``)."""
    from analytic.free_motion.compiled import prepare
    from analytic.free_motion.dop853 import loop_kernel
    assert prepare(mech), "the compiled path does not serve this case"
    assert loop_kernel(compile_now=True) is not None, "no compiled DOP853 loop"
    simulate(mech, duration=min(T, 0.01))


def _engine_runner(mech, T, engine, over, ref):
    from sim_models.runs.free import free_settings, run_free
    from sim_models.runs.free_run import FreeRequest
    settings = free_settings(engine, over)
    req = FreeRequest(T, samples=30 if T < 0.1 else 400, wall_limit=600.0)
    return lambda: run_free(mech, engine, settings, req, ref)


def engines_table(names, repeats: int) -> None:
    import subprocess
    print("load:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    for name in names:
        mech, T, engines, over = _bench_case(name)
        _warm(mech, T)
        ref = simulate(mech, duration=T)
        runners = {"exact": lambda m=mech, T=T: simulate(m, duration=T)}
        for e in list(engines):
            runners[e] = _engine_runner(mech, T, e, over, ref)
            try:
                runners[e]()  # builds once (imports); an engine missing here is left out
            except Exception as exc:  # noqa: BLE001 - reported, the others go on
                print(f"  {e}: not run ({str(exc).splitlines()[0][:100]})")
                del runners[e]
                engines = tuple(x for x in engines if x != e)
        runners["exact solve_ivp"] = lambda m=mech, T=T: _no_loop_sim(m, T)
        runners["exact numpy path"] = lambda m=mech, T=T: _numpy_sim(m, T)
        times = {k: [] for k in runners}
        ratios = {e: [] for e in engines}
        ratios["solve_ivp"] = []
        for _ in range(repeats):  # interleaved: each repeat runs every runner once
            for k, fn in runners.items():
                if k == "exact numpy path" and name == "a02" and times[k]:
                    continue  # 8-20 s a run: once
                times[k].append(_cpu(fn)[0])
            for e in engines:
                ratios[e].append(times["exact"][-1] / times[e][-1])
            ratios["solve_ivp"].append(times["exact"][-1] / times["exact solve_ivp"][-1])
        print(f"\n{name} ({T:g} s): CPU s, min / median of {repeats}")
        for k, v in times.items():
            print(f"  {k:18s} {min(v):8.3f} / {float(np.median(v)):8.3f}")
        for e in (*engines, "solve_ivp"):
            r = ratios[e]
            print(f"  exact / {e:9s} {min(r):8.2f} / {float(np.median(r)):8.2f} "
                  "(ratio within each repeat)")
        _eom_rate(mech, T, ref)
        _changes(mech, T, ref)
        _changes(mech, T, ref, _no_loop_sim, "solve_ivp (no compiled loop)")


def _numpy_sim(mech, T):
    with _NumpyPath():
        return simulate(mech, duration=T)


def _eom_rate(mech, T, ref, n: int = 2000) -> None:
    """Right-hand side evaluations per CPU second at ``n`` states along the run (each a new
    configuration, as the integrator's stages are), compiled and numpy path."""
    from analytic.free_motion.integrate import _System, joint_scale
    seg = ref.segments[0]
    ts = np.linspace(seg.t0, seg.t1, n)
    ys = seg.sol(ts).T
    x0 = seg.xs[0]
    rates = {}
    for how in ("compiled", "numpy"):
        if how == "numpy":
            with _NumpyPath():
                sysm = _System(seg.lk, x0, joint_scale(mech))
        else:
            sysm = _System(seg.lk, x0, joint_scale(mech))
        assert (sysm.fast is not None) == (how == "compiled")
        t0 = time.process_time()
        for t, y in zip(ts, ys, strict=True):
            sysm(t, y)
        rates[how] = n / (time.process_time() - t0)
    print(f"  equation of motion: {rates['numpy']:,.0f} evaluations/s numpy path, "
          f"{rates['compiled']:,.0f} compiled ({rates['compiled'] / rates['numpy']:.0f}x)")


def _changes(mech, T, ref, other=None, what: str = "numpy path") -> None:
    """The largest change of each sampled quantity, compiled against the numpy path (or
    ``other``'s run, said as ``what``)."""
    old = (other or _numpy_sim)(mech, T)
    ts = np.linspace(0.0, T, 201)
    a, b = ref.at(ts, forces=False), old.at(ts, forces=False)
    worst = {}
    for k in QUANTITIES:
        A, B = getattr(a, k), getattr(b, k)
        d = np.abs(A - B)
        worst[k] = float(np.max(np.where(d == 0, 0.0, d / np.maximum(np.ptp(B, axis=0),
                                                                     1e-300))))
    scale = max(float(np.ptp(b.kinetic)), float(np.ptp(b.potential)))
    worst["energy_residual/energy"] = float(np.max(np.abs(a.energy_residual
                                                          - b.energy_residual)) / scale)
    k = max(worst, key=worst.get)
    dt = max((abs(e.t - f.t) for e, f in zip(ref.events, old.events, strict=False)),
             default=0.0)
    print(f"  largest change vs {what}: {worst[k]:.1e} of range ({k}); events "
          f"{len(ref.events)} vs {len(old.events)}, times within {dt:.1e} s; "
          f"evaluations {ref.nfev} vs {old.nfev}")


_FIRST = """
import time, sys
c0, w0 = time.process_time(), time.perf_counter()
from analytic import load_case
from analytic.free_motion import simulate
from analytic.free_motion.integrate import _System
from sim_models.builders.free_cases import released
m = released(load_case("seed-four-bar"), duration=2.0)
c1, w1 = time.process_time(), time.perf_counter()
tr = simulate(m, duration=2.0)
c2, w2 = time.process_time(), time.perf_counter()
from analytic.free_motion.compiled import fast_eom
from analytic.free_motion import dop853
from analytic.kernels.cache import _MODULES
looped = bool(dop853._LOOP) and dop853._LOOP[0].name in _MODULES
print(f"imports {c1 - c0:.2f} s CPU ({w1 - w0:.2f} wall); simulate 2 s: {c2 - c1:.2f} s "
      f"CPU ({w2 - w1:.2f} wall), {tr.nfev} evaluations, compiled path used: "
      f"{fast_eom(tr.segments[0].lk) is not None}, compiled DOP853 loop: {looped}")
"""


def first_call() -> None:
    """A released four-bar in a new process with empty kernel caches, then again once
    the background compiles are done."""
    import os
    import subprocess
    import sys
    import tempfile
    from pathlib import Path
    root = str(Path(__file__).resolve().parents[1])
    with tempfile.TemporaryDirectory() as d:
        env = dict(os.environ, XVAL_KERNEL_CACHE=f"{d}/k", NUMBA_CACHE_DIR=f"{d}/n",
                   PYTHONPATH=root)
        env.pop("XVAL_FUSED", None)
        for label in ("empty caches", "second process"):
            t0 = time.perf_counter()
            r = subprocess.run([sys.executable, "-c", _FIRST], env=env, cwd=root,
                               capture_output=True, text=True)
            print(f"{label}: {r.stdout.strip() or r.stderr[-500:]} "
                  f"(process {time.perf_counter() - t0:.1f} s wall)")
            t0 = time.perf_counter()
            while any(Path(f"{d}/k").glob("*.compiling")):  # background compiles
                time.sleep(0.5)
            if label == "empty caches":
                print(f"  background compiles finished {time.perf_counter() - t0:.1f} s "
                      "after the first process ended; ready: "
                      f"{len(list(Path(f'{d}/k').glob('*.ready')))} kernels")


if __name__ == "__main__":
    main()
