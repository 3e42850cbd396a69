"""The engine protocol and registry: every registered engine is picked up here.

Independent expectations: the prescribed driver path is the closed form
``v0 + w t + a t^2 / 2``; the analytic reference comes from :mod:`analytic`; import
rules are read from the source files' syntax trees.
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

from analytic import load_case
from analytic.toml_io import load_mechanism
from sim_models import compile_linkage
from sim_models.engines.protocol import EngineRefusal, SettingsError, plan_samples
from sim_models.engines.registry import (
    UnknownEngineError,
    engine_names,
    get_engine,
    missing_library,
)
from sim_models.runs.driven import rerun, run

from ..conftest import ENGINE_RELATIVE, assert_run_within

#: every registered engine; one whose optional library is missing is skipped, saying so
ENGINES = [pytest.param(n, marks=pytest.mark.skipif(missing_library(n) is not None,
                                                    reason=str(missing_library(n))))
           for n in engine_names()]

ROOT = Path(__file__).resolve().parents[3]
ENGINE_LIBRARIES = {"mujoco", "pybullet", "pybullet_data", "exudyn", "pinocchio", "mujoco_warp",
                    "warp"}
BUGS = Path(__file__).resolve().parents[2] / "data" / "bugs"


def _imports(path: Path) -> set[str]:
    """Every module a file imports (module level and inside functions); relative imports
    resolved against its package."""
    tree = ast.parse(path.read_text(), str(path))
    pkg = path.parent.relative_to(ROOT).parts
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = list(pkg[:len(pkg) - node.level + 1])
                mod = ".".join(base + ([node.module] if node.module else []))
                if node.module is None:  # from . import x
                    out |= {f"{mod}.{a.name}" for a in node.names}
                else:
                    out.add(mod)
            else:
                out.add(node.module or "")
    return out


@pytest.mark.parametrize("package", ["reports", "analytic"])
def test_no_engine_library_outside_sim_models(package):
    """Outside sim_models/ no module imports an engine library (issue 9)."""
    bad = {}
    for f in sorted((ROOT / package).rglob("*.py")):
        libs = {m.split(".")[0] for m in _imports(f)} & ENGINE_LIBRARIES
        if libs:
            bad[str(f.relative_to(ROOT))] = sorted(libs)
    assert not bad, bad


@pytest.mark.parametrize("package", ["sim_models", "reports"])
def test_no_circular_imports(package):
    """The import graph of each package (function-level imports included) is acyclic."""
    files = {".".join(f.relative_to(ROOT).with_suffix("").parts): f
             for f in (ROOT / package).rglob("*.py")}
    files = {k.removesuffix(".__init__"): v for k, v in files.items()}
    graph = {}
    for mod, f in files.items():
        deps = set()
        for m in _imports(f):
            while m and m not in files:
                m = m.rpartition(".")[0]
            if m and m != mod and m != package:
                deps.add(m)
        graph[mod] = deps
    state: dict[str, int] = {}

    def visit(m, stack):
        state[m] = 1
        for d in graph.get(m, ()):
            if state.get(d) == 1:
                raise AssertionError(" -> ".join([*stack, m, d]))
            if d not in state:
                visit(d, [*stack, m])
        state[m] = 2

    for m in graph:
        if m not in state:
            visit(m, [])


def test_every_engine_is_one_folder_and_one_registry_line():
    """A registered engine's driven session is ``sim_models/engines/NAME/driven.py`` and
    its released one (where it has one) ``NAME/free.py``; every engine folder there is
    registered (README, "Adding an engine")."""
    from sim_models.engines.registry import BUILTIN
    from sim_models.runs.free import FREE_SESSIONS
    folders = {p.parent.name for p in (ROOT / "sim_models" / "engines").glob("*/__init__.py")}
    for e in BUILTIN:
        assert e.module == f"sim_models.engines.{e.name}.driven", e
        assert (ROOT / "sim_models" / "engines" / e.name / "driven.py").is_file(), e.name
    for name, (module, _) in FREE_SESSIONS.items():
        assert module == f"sim_models.engines.{name}.free", (name, module)
    assert folders == {e.name for e in BUILTIN}, folders ^ {e.name for e in BUILTIN}
    assert set(FREE_SESSIONS) <= folders


def test_the_front_door_names_the_runs():
    """``sim_models`` hands out the driven and the released run by name (the released one
    loaded on first use), the same objects as their rooms'."""
    import sim_models
    from sim_models.runs import driven, free, free_run
    assert sim_models.run is driven.run and sim_models.run_free is free.run_free
    assert sim_models.FreeRequest is free_run.FreeRequest
    assert sim_models.FreeEngineRun is free_run.FreeEngineRun
    assert set(sim_models.__all__) >= {"run", "run_free", "rerun", "compile_linkage"}
    with pytest.raises(AttributeError):
        sim_models.no_such_name  # noqa: B018


def test_registry_names_and_unknown():
    assert {"mujoco", "pybullet"} <= set(engine_names())
    with pytest.raises(UnknownEngineError, match="engines: mujoco"):
        get_engine("bullet3")


def _available(name):
    try:
        return get_engine(name)
    except (ImportError, UnknownEngineError) as e:  # pragma: no cover
        pytest.skip(f"{name}: {e}")


@pytest.mark.parametrize("name", ENGINES)
def test_settings_from_key_value_strings(name):
    eng = _available(name)
    s0 = eng.settings()
    assert isinstance(s0, eng.settings_class)
    # every field round-trips through its own key=value string
    fields = s0.as_dict()
    again = eng.settings({k: (",".join(map(str, v)) if isinstance(v, tuple) else str(v))
                          for k, v in fields.items()})
    assert again == s0
    s = eng.settings({"timestep": "1e-4"})
    assert s.timestep == 1e-4 and s != s0
    with pytest.raises(SettingsError, match="no setting 'warp'"):
        eng.settings({"warp": "9"})
    with pytest.raises(SettingsError, match="timestep"):
        eng.settings({"timestep": "fast"})


@pytest.mark.parametrize("name", ENGINES)
def test_run_is_reproducible_from_its_record(name, tmp_path):
    """An EngineRun carries its mechanism and settings object: re-running it gives the
    same samples, also for a case loaded from a file under another name."""
    _available(name)
    src = Path(load_case("seed-four-bar").source or "")
    mech = load_case("seed-four-bar")
    if src.is_file():
        text = src.read_text().replace('name = "seed-four-bar"', 'name = "renamed-four-bar"')
        p = tmp_path / "renamed.toml"
        p.write_text(text)
        mech = load_mechanism(p)
    tree = compile_linkage(mech)
    r = run(tree, name, revolutions=2, samples=12)
    assert r.ok, r.reason
    assert r.mechanism is mech and r.settings == get_engine(name).settings()
    assert r.linkage is tree.linkage  # the compiled object itself travels back up
    assert_run_within(r, ENGINE_RELATIVE, name)
    # the arithmetic the run records is the one its settings declare (the error floor's)
    assert r.extra.get("precision", "float64") == r.settings.arithmetic.name
    r2 = rerun(r)
    assert r2.linkage is tree.linkage  # re-run on the Linkage it carries, not a new one
    for k in ("values", "alpha", "drive_effort", "joint_force"):
        np.testing.assert_allclose(getattr(r2, k), getattr(r, k), rtol=1e-9, atol=1e-9,
                                   err_msg=k)


def test_instantaneous_run_carries_its_compiled_linkage():
    """The instantaneous mode's run, too, carries the very Linkage of the tree it was
    made from (and its mechanism is that Linkage's)."""
    from sim_models.runs.driven import instantaneous
    _available("mujoco")
    tree = compile_linkage(load_case("seed-four-bar"))
    r = instantaneous(tree, "mujoco", values=[0.5, 1.0])
    assert r.linkage is tree.linkage and r.mechanism is tree.linkage.mech


def test_a_tree_refuses_the_linkage_of_another_description():
    """A SimTree given a Linkage built from another description (an equal copy
    included) refuses it, naming both: the Linkage a run carries is its own
    description's."""
    from analytic import Linkage
    from sim_models import SimModelError, SimTree
    a, b = load_case("seed-four-bar"), load_case("seed-four-bar")
    with pytest.raises(SimModelError, match="another description"):
        SimTree(a, Linkage(b))
    lk = Linkage(a)
    assert compile_linkage(a, lk).linkage is lk


def _free_engines():
    from sim_models.runs.free import FREE_SESSIONS
    return [pytest.param(n, marks=pytest.mark.skipif(missing_library(n) is not None,
                                                     reason=str(missing_library(n))))
            for n in FREE_SESSIONS]


@pytest.mark.parametrize("name", _free_engines())
def test_free_settings_round_trip_and_declare_the_engines_arithmetic(name):
    """Every free session's settings round-trip through key=value strings and declare
    the same arithmetic as the engine's prescribed settings (float32 for MuJoCo Warp)."""
    from sim_models.runs.free import free_session_class, free_settings
    s0 = free_settings(name)
    fields = s0.as_dict()
    again = free_settings(name, {k: (",".join(map(str, v)) if isinstance(v, tuple)
                                     else str(v)) for k, v in fields.items()})
    assert again == s0 and free_session_class(name).name == name
    assert type(s0).arithmetic == get_engine(name).settings_class.arithmetic
    with pytest.raises(SettingsError, match="no setting 'warp'"):
        free_settings(name, {"warp": "9"})


def test_plan_by_time_for_a_reversing_input():
    """A crank that stops and turns back is sampled at equal times; the values are the
    prescribed path's closed form there."""
    tree = compile_linkage(load_mechanism(BUGS / "reversing-input.toml")) \
        if (BUGS / "reversing-input.toml").is_file() else pytest.skip("no bug files")
    d = tree.mech.driver
    p = plan_samples(tree, 2, 36)
    assert p.by_time and np.all(np.diff(p.times) > 0)
    t = p.times
    np.testing.assert_allclose(p.values, d.value + d.velocity * t + 0.5 * d.acceleration * t ** 2,
                               rtol=0, atol=1e-12)
    # it covers the reversal (the rate changes sign inside the run)
    assert p.velocity[0] * p.velocity[-1] < 0
    # two turns of travel: 0.056 rad out and back, the rest beyond
    out = d.velocity ** 2 / (2 * abs(d.acceleration))
    assert abs(p.values[-1] - d.value) == pytest.approx(4 * math.pi - 2 * out, rel=1e-9)


@pytest.mark.parametrize("name", ENGINES)
def test_reversing_input_runs_to_a_verdict(name):
    if not (BUGS / "reversing-input.toml").is_file():
        pytest.skip("no bug files")
    _available(name)
    from reports.comparison.compare import compare_run
    tree = compile_linkage(load_mechanism(BUGS / "reversing-input.toml"))
    r = run(tree, name)
    comps = compare_run(r)
    assert comps and all(np.isfinite(c.normalised) for c in comps if r.ok)


def test_a_motionless_driver_is_refused():
    from dataclasses import replace
    mech = load_case("seed-four-bar")
    still = replace(mech, driver=replace(mech.driver, velocity=0.0, acceleration=0.0))
    with pytest.raises(EngineRefusal, match="no motion"):
        run(still, "mujoco")


#: PyBullet's velocity motor sets v_{n+1}; with the target at mid-step the input's
#: position follows the prescribed path to round-off (measured 1e-12 rad), with the
#: target at the step's end it drifts by a h t / 2 (hibbeler-16-31: 3.9e-4 of peak).
PRESCRIBED_PATH_RAD = 1e-9


def test_pybullet_accelerating_input_stays_on_its_path():
    pytest.importorskip("pybullet")
    tree = compile_linkage(load_case("hibbeler-16-31"))
    assert tree.mech.driver.acceleration != 0
    r = run(tree, "pybullet", samples=12)
    assert r.ok, r.reason
    d, t = tree.mech.driver, r.times
    path = d.value + d.velocity * t + 0.5 * d.acceleration * t ** 2
    off = (r.measured_values - path + math.pi) % (2 * math.pi) - math.pi
    assert np.max(np.abs(off)) < PRESCRIBED_PATH_RAD


def test_limited_range_reversing_input_stays_off_its_limits():
    """A collar input that decelerates, turns back and runs toward its other limit
    (hibbeler-16-30 with a = -12 m/s^2): sampled by time, never within half a sample
    spacing of a limit position of the solver's feasible range, and it passes."""
    from dataclasses import replace

    from reports.comparison.compare import compare_run, verdict
    mech = load_case("hibbeler-16-30")
    mech = replace(mech, driver=replace(mech.driver, acceleration=-12.0))
    tree = compile_linkage(mech)
    (lo, hi), = tree.linkage.feasible_ranges()
    p = plan_samples(tree, 2, 24)
    x = p.values[np.isfinite(p.times)]
    assert p.by_time and len(x) >= 12
    assert x.min() >= lo + (hi - lo) / 48 * 0.99 and x.max() <= hi - (hi - lo) / 48 * 0.99
    assert np.any(np.diff(x) < 0) and np.any(np.diff(x) > 0)  # out and back
    r = run(tree, "mujoco", samples=24)
    assert r.ok and verdict(compare_run(r))
