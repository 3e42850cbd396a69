"""First calls and start-up, each in fresh processes (issue 23).

* ``first_calls``: on a new machine (empty kernel and numba caches: ``XVAL_KERNEL_CACHE``
  and ``NUMBA_CACHE_DIR`` in new temporary folders) the first ``Linkage.solve`` of the
  four-bar, then of the six-bar in the same process (a second new structure), through
  the front door (numpy answers, the kernels compile in background processes) and the
  seconds until the background compiles have marked both kernels ready; a fresh
  process's first call once they are cached (front door; and the kernel forced,
  ``XVAL_FUSED=always``: importing numba and loading it); the foreground compile of
  each kernel (``XVAL_FUSED=always`` on empty caches, background compiles off); and
  pylinkage's first ``step_fast_with_kinematics`` on an empty and a warm numba cache.
* ``cli``: ``xval cases``, ``xval --help``, ``xval solve seed-four-bar --json``, best of 5.
* ``allocator``: the front door's solve at 3,600 and 36,000 points in processes with
  and without :func:`analytic.perf.tune_allocator`, alternated.

    python benchmarks/bench_startup.py [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CASES = ("seed-four-bar", "six-bar")
POINTS = 3600

_FIRST = """
import json, sys, time
t0 = time.perf_counter()
import numpy as np
from analytic import Linkage, load_case
t_import = time.perf_counter() - t0
out = {"import_s": t_import}
x = np.linspace(0.0, 2 * np.pi, %d, endpoint=False)
for case in %r:
    lk = Linkage(load_case(case))
    t = time.perf_counter()
    kin, frc = lk.solve(x)
    out[case] = {"first_call_s": time.perf_counter() - t, "path": type(kin).__name__}
from analytic import fused
out["compile_log"] = fused.COMPILE_LOG
print(json.dumps(out))
"""

_PYLINKAGE = """
import json, time, sys
sys.path.insert(0, %r)
from benchmarks.bench_solver import pylinkage_four_bar
pl = pylinkage_four_bar(%d)
t = time.perf_counter()
pl.step_fast_with_kinematics(iterations=%d)
print(json.dumps({"first_call_s": time.perf_counter() - t}))
"""


def _py(code: str, env: dict, timeout: float = 600.0) -> dict:
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       env=env, cwd=ROOT, timeout=timeout)
    if p.returncode:
        return {"error": p.stderr.strip().splitlines()[-1:]}
    return json.loads(p.stdout.strip().splitlines()[-1])


def _env(kc: str, nc: str, **extra) -> dict:
    env = dict(os.environ)
    env.pop("XVAL_FUSED", None)
    env.update(XVAL_KERNEL_CACHE=kc, NUMBA_CACHE_DIR=nc, **extra)
    return env


def first_calls(wait_s: float = 600.0) -> dict:
    out = {}
    with tempfile.TemporaryDirectory() as d:
        kc, nc = os.path.join(d, "k"), os.path.join(d, "n")
        env = _env(kc, nc, XVAL_BACKGROUND_COMPILE="1")
        t0 = time.perf_counter()
        out["new_machine_front_door"] = _py(_FIRST % (POINTS, CASES), env)
        while time.perf_counter() - t0 < wait_s:  # the background compiles
            ready = [f for f in os.listdir(kc) if f.endswith(".ready")]
            if len(ready) >= len(CASES) and not any(f.endswith(".compiling")
                                                     for f in os.listdir(kc)):
                break
            time.sleep(0.5)
        out["background_compiles_ready_after_s"] = time.perf_counter() - t0
        for k in range(3):
            out[f"warm_front_door_{k}"] = _py(_FIRST % (POINTS, CASES), env)
            out[f"warm_kernel_forced_{k}"] = _py(_FIRST % (POINTS, CASES),
                                                 dict(env, XVAL_FUSED="always"))
    with tempfile.TemporaryDirectory() as d:
        env = _env(os.path.join(d, "k"), os.path.join(d, "n"), XVAL_BACKGROUND_COMPILE="0",
                   XVAL_FUSED="always")
        out["new_machine_kernel_compiled_in_foreground"] = _py(_FIRST % (POINTS, CASES), env)
    try:
        import pylinkage  # noqa: F401
    except ImportError:
        return out
    with tempfile.TemporaryDirectory() as d:
        env = _env(os.path.join(d, "k"), os.path.join(d, "n"))
        code = _PYLINKAGE % (ROOT, POINTS, POINTS)
        out["pylinkage_new_machine"] = _py(code, env)
        out["pylinkage_warm"] = [_py(code, env) for _ in range(3)]
    return out


def best_of(cmd: list[str], n: int = 5) -> float:
    best = float("inf")
    for _ in range(n):
        t = time.perf_counter()
        subprocess.run(cmd, capture_output=True, cwd=ROOT)
        best = min(best, time.perf_counter() - t)
    return best


def cli() -> dict:
    xval = [sys.executable, "-m", "reports.cli.xval"]
    return {"xval cases": best_of(xval + ["cases"]),
            "xval --help": best_of(xval + ["--help"]),
            "xval solve seed-four-bar --json": best_of(xval + ["solve", "seed-four-bar",
                                                               "--json"]),
            "python -c pass": best_of([sys.executable, "-c", "pass"]),
            "python -c 'import analytic'": best_of([sys.executable, "-c", "import analytic"])}


_ALLOC = """
import json, sys, time
import numpy as np
from analytic import Linkage, load_case, fused
if %r:
    from analytic.perf import tune_allocator
    tune_allocator()
lk = Linkage(load_case("seed-four-bar"))
fused.kernel_for(lk).state(np.zeros(2), level=3)
out = {}
for n in (3600, 36000):
    x = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    best = []
    for _ in range(15):
        t = time.perf_counter()
        for _ in range(360000 // n):
            lk.solve(x)
        best.append((time.perf_counter() - t) / 360000 * 1e9)
    out[n] = min(best)
print(json.dumps(out))
"""


def allocator(rounds: int = 3) -> dict:
    res = {"plain": [], "tuned": []}
    for _ in range(rounds):
        for k in res:
            res[k].append(_py(_ALLOC % (k == "tuned"), dict(os.environ)))
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", help="write the figures to this JSON file")
    args = ap.parse_args(argv)
    out = {"load_before": os.getloadavg()}
    out["cli_best_of_5_s"] = cli()
    out["allocator_ns_per_config"] = allocator()
    out["first_calls"] = first_calls()
    out["load_after"] = os.getloadavg()
    print(json.dumps(out, indent=1))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)
    return out


if __name__ == "__main__":
    main()
