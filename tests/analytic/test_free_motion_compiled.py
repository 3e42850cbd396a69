"""The compiled equation of motion (issue 34) against the numpy path it replaces.

The expected numbers are the numpy path's (``dynamics.coefficients`` and ``terms``, the
implementation before the compiled path; kept as the fallback), run here in the same
process with the compiled path switched off.  The independent checks of the motion
itself (elliptic period, published Andrews reference, absolute coordinates, energy
balance) are in ``test_free_motion*.py`` and run on whichever path is compiled.
"""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
import tomllib
from dataclasses import replace

import numpy as np
import pytest

from analytic import load_case
from analytic.free_motion import compiled, simulate
from analytic.free_motion.iftomm import n_four_bar_toml
from analytic.toml_io import mechanism_from_dict

pytest.importorskip("numba")
integrate_mod = importlib.import_module("analytic.free_motion.integrate")

#: Largest change of any sampled quantity, as a fraction of its range over the run
#: (the issue's bar).  The two paths differ by rounding in the sums (~1e-16 relative);
#: DOP853 at rtol 1e-13 then picks slightly different steps, so the trajectories differ
#: by a fraction of the integration error (measured 5e-15..5e-13 of range).
CHANGE_REL = 1e-12
#: The same across coordinate switches (the non-Grashof rocker): a switch time moved by
#: rounding moves the steps of every later segment; measured 7e-12..9e-12 of range on the
#: accelerations over 3 s and 21 switches (the motion's own error, 1e-9 of the link
#: length by the absolute-coordinate check, is a hundred times larger).  Not a defect of
#: the compiled path: the numpy path against itself with the initial rate one unit in
#: the last place larger moves by 1.7e-11 of range (switch times by 2e-13 s), so no
#: rounding-level change of the right-hand side stays within 1e-12 on this run.
SWITCHING_REL = 2e-11
#: The switching rocker since its coupler coordinates have a closed form (the compiled
#: path now serves all of its segments, not a third): the numpy path against itself
#: with the initial rate one ulp larger / smaller moves 2.6e-11 / 4.1e-11 of range
#: (1.7e-11 before), so the compiled path's rounding differences are judged at 2.5x the
#: larger spread, not at a bar the run's own rounding passes (compiled vs numpy measured
#: 3.4e-11; against the absolute-coordinate reference the run is 1.6e-10 of range in
#: rates, 9.3e-10 before).
ROCKER_REL = 1e-10
#: Energies (residual) are compared against the run's energy scale, not their range
#: (the residual's own range is rounding).
QUANTITIES = ("x", "xd", "xdd", "theta", "omega", "alpha", "kinetic", "potential",
              "work_motor", "work_loads", "dissipated")


@pytest.fixture(scope="module")
def eom_ready():
    compiled.eom_kernel(compile_now=True)


def _seed(elements: bool):
    from .test_free_motion import _seed_released
    return _seed_released(elements)


def _cases():
    from sim_models.builders.free_cases import released

    from .test_free_motion import _rocker_mech
    a02 = mechanism_from_dict(tomllib.loads(n_four_bar_toml(8)), "A02")  # chain only
    return {
        "seed": (lambda: released(load_case("seed-four-bar"), duration=1.0), 1.0, CHANGE_REL),
        "six-bar": (lambda: released(load_case("six-bar"), duration=1.0), 1.0, CHANGE_REL),
        "a01": (lambda: load_case("iftomm-a01-pendulum"), 2.0, CHANGE_REL),
        "a03": (lambda: load_case("iftomm-a03-andrews"), 0.03, CHANGE_REL),
        "a02-n8": (lambda: a02, 1.0, CHANGE_REL),
        "seed-spring-damper-motor": (lambda: _seed(True), 2.0, CHANGE_REL),
        "rocker-switching": (_rocker_mech, 3.0, ROCKER_REL),
    }


def largest_change(a, b, times) -> dict[str, float]:
    """Per quantity: the largest difference of ``a``'s samples from ``b``'s, relative to
    ``b``'s range over the run (energies' residual: to the energy scale)."""
    sa, sb = a.at(times, forces=False), b.at(times, forces=False)
    out = {}
    for k in QUANTITIES:
        A, B = getattr(sa, k), getattr(sb, k)
        rng = np.ptp(B, axis=0)
        d = np.abs(A - B)
        out[k] = float(np.max(np.where(d == 0, 0.0, d / np.maximum(rng, 1e-300))))
    scale = max(float(np.ptp(sb.kinetic)), float(np.ptp(sb.potential)), 1e-300)
    out["energy_residual"] = float(np.max(np.abs(sa.energy_residual - sb.energy_residual))
                                   / scale)
    return out


def _run_both(mech, T, monkeypatch):
    used = []
    real = compiled.FastEOM.evaluate

    def counting(self, *a):
        got = real(self, *a)
        used.append(got is not None)
        return got

    monkeypatch.setattr(compiled.FastEOM, "evaluate", counting)
    assert compiled.prepare(mech)
    fast = simulate(mech, duration=T)
    monkeypatch.setattr(integrate_mod, "fast_eom", lambda lk: None)
    ref = simulate(mech, duration=T)
    return fast, ref, used


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow)
                                  if n == "rocker-switching" else n for n in _cases()])
def test_compiled_matches_numpy_path(name, eom_ready, monkeypatch):
    make, T, tol = _cases()[name]
    mech = make()
    fast, ref, used = _run_both(mech, T, monkeypatch)
    assert sum(used) > 0.5 * len(used), "the compiled path answered few states"
    assert_same_run(fast, ref, T, tol)


def assert_same_run(fast, ref, T: float, tol: float):
    """Two runs of one release the same to ``tol``: the evaluations (when ``tol`` is the
    rounding bar), the switches (coordinates, times within ``tol`` of the duration), the
    events (kinds, times) and every sampled quantity (fraction of its range)."""
    assert fast.nfev == ref.nfev or tol > CHANGE_REL
    assert [(a, b) for _, a, b in fast.switches] == [(a, b) for _, a, b in ref.switches]
    assert max((abs(a[0] - b[0]) for a, b in zip(fast.switches, ref.switches, strict=True)),
               default=0.0) <= tol * T
    assert [e.kind for e in fast.events] == [e.kind for e in ref.events]
    assert max((abs(e.t - f.t) for e, f in zip(fast.events, ref.events, strict=True)),
               default=0.0) <= tol * T
    worst = largest_change(fast, ref, np.linspace(0.0, T, 101))
    assert max(worst.values()) <= tol, worst


def test_slider_coordinate_with_joint_elements(eom_ready, monkeypatch):
    """Prismatic joints in the layout: a slider-crank released from its slider with a
    joint spring, damper and motor on it (the numpy path's numbers)."""
    from analytic import Linkage
    from analytic.motion_spec import FreeMotion, JointDamper, JointSpring, Motor
    m = load_case("seed-slider-crank")
    s0 = float(Linkage(m).kinematics(np.radians([30.0])).slider("slide")[0][0])
    fm = FreeMotion("slide", s0, 0.0, 0.05, springs=(JointSpring("slide", 2000.0, s0 - 0.01),),
                    dampers=(JointDamper("slide", 1.0),),
                    motors=(Motor("slide", 0.0, (0.0, 0.05), (5.0, 2.0)),))
    mech = replace(m, gravity=(0.0, -9.81), motion=fm)
    fast, ref, used = _run_both(mech, 0.05, monkeypatch)
    assert any(used)
    worst = largest_change(fast, ref, np.linspace(0.0, 0.05, 51))
    assert max(worst.values()) <= SWITCHING_REL, worst


def test_first_call_waits_for_no_compile(tmp_path):
    """Empty caches: the numpy path answers, nothing is compiled in the calling process
    (a background process would compile; here it is turned off)."""
    code = (
        "import time\n"
        "from analytic import load_case\n"
        "from analytic.free_motion import simulate, compiled\n"
        "from analytic import fused\n"
        "from sim_models.builders.free_cases import released\n"
        "m = released(load_case('seed-four-bar'), duration=0.2)\n"
        "tr = simulate(m, duration=0.2)\n"
        "assert tr.nfev > 0\n"
        "assert not fused.COMPILE_LOG, fused.COMPILE_LOG\n"
        "assert not compiled._MODULES, list(compiled._MODULES)\n"
        "print('ok')\n")
    env = dict(os.environ, XVAL_KERNEL_CACHE=str(tmp_path / "k"),
               NUMBA_CACHE_DIR=str(tmp_path / "n"), XVAL_BACKGROUND_COMPILE="0")
    env.pop("XVAL_FUSED", None)
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    r = subprocess.run([sys.executable, "-c", code], env=env, cwd=root, capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr[-2000:]
