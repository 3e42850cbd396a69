"""Engine harness against its bare stepping loop: one revolution at the recommended settings.

For each registered engine and case, in one process and interleaved (every repeat runs
every engine x case x method once, in turn; the order of harness and bare alternates),
so the ratios hold on a shared, noisy machine even when the absolute times move:

* ``harness``: :func:`sim_models.engines.protocol.drive` on an open session: one revolution
  (``revolutions=1``, 36 samples, the sampling plan of a verdict run), reset, stepping,
  sampling, divergence checks, conversion to the analytic conventions and the
  :class:`~sim_models.runs.engine_run.EngineRun`; the model build is not timed (the bare
  loop has none either);
* ``bare``: the engine library's own step call in a plain Python loop, on the same
  model and data, from the same reset, for the same number of steps at the run's step
  (counted in the harness run: pre-roll and finite-difference steps included):

  - MuJoCo: ``mujoco.mj_step(model, data)``;
  - PyBullet: ``p.stepSimulation(physicsClientId=cid)``;
  - Exudyn: its solver loop is C++: one ``MainSolverImplicitSecondOrder.SolveSteps``
    call over all the steps (the call the session makes once per sample interval), from
    the session's initialised solver.  A Python loop of single steps is not Exudyn's
    own loop (each ``SolveSteps`` call has a fixed cost), so it is not the yardstick.

  The bare loops apply no loads and do not re-target a motor: for a case with a load
  whose moment moves with the pose (MuJoCo) or any load (PyBullet, whose external forces
  are cleared by every step), or an accelerating input (PyBullet's motor target), the
  harness does per-step engine input that the bare loop omits; the built-in seed
  four-bar and six-bar have neither.

Ratio = harness / bare, min over repeats of each (``min``) and median of each
(``median``), by the wall clock (``perf_counter``: what a user waits) and by the
process's CPU time (``process_time``: all its threads, not the time other processes
held the cores; on a loaded machine the wall clock of a 60 ms loop moves by 30%);
``paired med`` is the median of each repeat's own ratio (the two runs of a repeat are
adjacent in time, so a load change between repeats cancels).  The machine's load
(``os.getloadavg``) is printed before and after.

    python benchmarks/bench_harness.py [--cases seed-four-bar,six-bar] [--engines all]
        [--repeats 15] [--json FILE] [--profile ENGINE:CASE]
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import os
import platform
import pstats
import statistics
import sys
import time

from analytic import load_case
from sim_models.engines.protocol import compile_linkage, drive, plan_samples
from sim_models.engines.registry import available_engines
from sim_models.runs.driven import open_session
from sim_models.runs.engine_run import RunRequest

CASES = ("seed-four-bar", "six-bar")
REVOLUTIONS, SAMPLES = 1, 36


# ============================================================================ bare loops
def bare_mujoco(session, h: float, n: int) -> float:
    """Seconds of ``n`` ``mj_step`` calls on the session's model and data."""
    mj, m, d = session.mj, session.model, session.data
    session.reset(0.0, h)
    m.opt.timestep = h
    step = mj.mj_step
    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(n):
        step(m, d)
    return time.perf_counter() - t0, time.process_time() - c0


def bare_pybullet(session, h: float, n: int) -> float:
    """Seconds of ``n`` ``stepSimulation`` calls on the session's client."""
    sim = session.sim
    session.reset(0.0, h)
    step, cid = sim.p.stepSimulation, sim.cid
    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(n):
        step(physicsClientId=cid)
    return time.perf_counter() - t0, time.process_time() - c0


def bare_exudyn(session, h: float, n: int) -> float:
    """Seconds of one ``SolveSteps`` call of ``n`` steps of ``h`` (Exudyn's own loop)."""
    session.reset(0.0, h)
    sol = session.solver
    sol.it.endTime = n * h
    sol.it.currentStepSize = h
    sol.it.maxStepSize = h
    t0, c0 = time.perf_counter(), time.process_time()
    sol.SolveSteps(session.mbs, session.sim)
    return time.perf_counter() - t0, time.process_time() - c0


BARE = {"mujoco": bare_mujoco, "pybullet": bare_pybullet, "exudyn": bare_exudyn}


# ============================================================================ harness
def harness(session, plan, request) -> tuple[tuple[float, float], object]:
    """``(wall, cpu)`` seconds of one :func:`drive`, and its run."""
    t0, c0 = time.perf_counter(), time.process_time()
    r = drive(session, plan, request)
    return (time.perf_counter() - t0, time.process_time() - c0), r


def library_steps(engine: str, session, plan, request) -> tuple[int, float, object]:
    """Steps the engine library takes in one harness run, and the run's step (s)."""
    r = drive(session, plan, request)
    n = int(r.steps)
    if engine == "pybullet":  # count stepSimulation calls (pre-roll included)
        sim = session.sim
        counter = _Counting(sim.p, "stepSimulation")
        sim.p = counter
        try:
            drive(session, plan, request)
        finally:
            sim.p = counter.module
        n = counter.calls
    return n, float(r.timestep), r


class _Counting:
    """A module stand-in that counts the calls of one of its functions."""

    def __init__(self, module, name: str):
        self.module, self.name, self.calls = module, name, 0

    def __getattr__(self, attr):
        fn = getattr(self.module, attr)
        if attr != self.name:
            return fn

        def counted(*a, **k):
            self.calls += 1
            return fn(*a, **k)
        return counted


class Pair:
    """One engine x case: its open session, plan and step count."""

    def __init__(self, engine: str, case: str):
        self.engine, self.case = engine, case
        tree = compile_linkage(load_case(case))
        self.plan = plan_samples(tree, REVOLUTIONS, SAMPLES)
        self.request = RunRequest(REVOLUTIONS, SAMPLES)
        self.cm = open_session(tree, engine, None)
        self.session = self.cm.__enter__()
        self.n, self.h, r = library_steps(engine, self.session, self.plan, self.request)
        if not r.ok:
            raise SystemExit(f"{engine} {case}: the harness run failed: {r.reason}")
        self.times = {"harness": [], "bare": []}

    def once(self, first: str) -> None:
        order = ("harness", "bare") if first == "harness" else ("bare", "harness")
        for what in order:
            if what == "harness":
                self.times[what].append(harness(self.session, self.plan, self.request)[0])
            else:
                self.times[what].append(BARE[self.engine](self.session, self.h, self.n))

    def close(self) -> None:
        self.cm.__exit__(None, None, None)

    def row(self) -> dict:
        out = {"engine": self.engine, "case": self.case, "steps": self.n, "h": self.h}
        for j, clock in enumerate(("wall", "cpu")):
            hs = [x[j] for x in self.times["harness"]]
            bs = [x[j] for x in self.times["bare"]]
            out.update({
                f"{clock}_harness_min_ms": 1e3 * min(hs),
                f"{clock}_harness_median_ms": 1e3 * statistics.median(hs),
                f"{clock}_bare_min_ms": 1e3 * min(bs),
                f"{clock}_bare_median_ms": 1e3 * statistics.median(bs),
                f"{clock}_ratio_min": min(hs) / min(bs),
                f"{clock}_ratio_median": statistics.median(hs) / statistics.median(bs),
                f"{clock}_ratio_paired_median": statistics.median(
                    h / b for h, b in zip(hs, bs, strict=True))})
        return out


def profile(engine: str, case: str, top: int = 25) -> str:
    """cProfile of 5 harness runs (tottime), as text."""
    pair = Pair(engine, case)
    try:
        pr = cProfile.Profile()
        pr.enable()
        for _ in range(5):
            harness(pair.session, pair.plan, pair.request)
        pr.disable()
    finally:
        pair.close()
    out = io.StringIO()
    pstats.Stats(pr, stream=out).sort_stats("tottime").print_stats(top)
    return out.getvalue()


# ============================================================================ main
def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--engines", default="all")
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--json", default=None)
    ap.add_argument("--profile", default=None, help="ENGINE:CASE: cProfile the harness")
    a = ap.parse_args(argv)
    if a.profile:
        eng, case = a.profile.split(":")
        print(profile(eng, case))
        return 0
    engines = available_engines() if a.engines == "all" else tuple(a.engines.split(","))
    load0 = os.getloadavg()
    print(f"# {platform.node()} {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cpus, python {sys.version.split()[0]}; "
          f"load {load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f}")
    pairs = [Pair(e, c) for e in engines for c in a.cases.split(",")]
    try:
        for k in range(a.repeats):
            for p in pairs:
                p.once("harness" if k % 2 == 0 else "bare")
    finally:
        for p in pairs:
            p.close()
    load1 = os.getloadavg()
    rows = [p.row() for p in pairs]
    print(f"# {a.repeats} repeats, interleaved; load after {load1[0]:.2f} {load1[1]:.2f} "
          f"{load1[2]:.2f}")
    for clock in ("wall", "cpu"):
        print(f"{clock:9s} {'case':15s} {'steps':>6s} {'harness ms min/med':>20s} "
              f"{'bare ms min/med':>18s} {'ratio min':>9s} {'ratio med':>9s} "
              f"{'paired med':>10s}")
        for r in rows:
            print(f"{r['engine']:9s} {r['case']:15s} {r['steps']:6d} "
                  f"{r[clock + '_harness_min_ms']:9.2f}/{r[clock + '_harness_median_ms']:8.2f}  "
                  f"{r[clock + '_bare_min_ms']:8.2f}/{r[clock + '_bare_median_ms']:8.2f} "
                  f"{r[clock + '_ratio_min']:9.3f} {r[clock + '_ratio_median']:9.3f} "
                  f"{r[clock + '_ratio_paired_median']:10.3f}")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"load_before": load0, "load_after": load1, "repeats": a.repeats,
                       "rows": rows}, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
