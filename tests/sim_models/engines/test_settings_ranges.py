"""One range per setting (sim_models/engines/ranges.py), checked by the settings dataclasses and
RunRequest themselves: every field of every engine's settings has an impossible value
here that is refused, the ends of each range are accepted, and the settings the studies
use are inside.  The command-line and baseline doors are in
tests/reports/test_ranges_doors.py (same table)."""

from __future__ import annotations

import dataclasses
import math

import pytest

from sim_models.engines.registry import available_engines, get_engine, make_settings
from sim_models.engines.settings import SettingsError
from sim_models.runs.engine_run import RunRequest

#: (engine, key, value as typed after --set, words the refusal must contain).  Each is a
#: value no run can honour: a negative count or factor, an impedance MuJoCo would clamp,
#: a step that runs for hours or turns 86 deg a step.  The issue's reproducers are the
#: first of each key.
IMPOSSIBLE = [
    ("mujoco", "timestep", "1e-9", "1e-06 to 0.1 s"),
    ("mujoco", "timestep", "10", "1e-06 to 0.1 s"),
    ("mujoco", "integrator", "RK5", "use one of RK4, implicitfast, implicit, Euler"),
    ("mujoco", "solref", "-1,2", "direct form"),
    ("mujoco", "solref", "0.02,-1", "direct form"),
    ("mujoco", "solimp", "2,2,2,2,2", "dmin (1 of 5): 2 is out of range"),
    ("mujoco", "solimp", "0.9,0,0.001,0.5,2", "dmax (2 of 5): 0 is out of range"),
    ("mujoco", "solimp", "0.9,0.95,0,0.5,2", "width (3 of 5)"),
    ("mujoco", "solimp", "0.9,0.95,0.001,1,2", "midpoint (4 of 5)"),
    ("mujoco", "solimp", "0.9,0.95,0.001,0.5,0.5", "power (5 of 5)"),
    ("mujoco", "iterations", "-5", "1 to 1000"),
    ("mujoco", "iterations", "0", "1 to 1000"),
    ("mujoco", "tolerance", "-1", "0 to 1"),
    ("mujoco", "armature", "-1e8", "above 0 and at most 1e+12"),
    ("mujoco", "armature", "0", "above 0"),
    ("mujoco", "diagexact", "maybe", "use true or false"),
    ("mujoco", "invweight_scale", "-1", "above 0"),
    ("mujoco", "invweight_scale", "0", "above 0"),
    ("mujoco", "scene", "garden", "use one of minimal"),
    ("pybullet", "timestep", "0", "1e-06 to 0.1 s"),
    ("pybullet", "solver_iterations", "0", "1 to 1000"),
    ("pybullet", "residual_threshold", "-1", "at least 0"),
    ("pybullet", "erp", "1.5", "0 to 1"),
    ("pybullet", "erp", "-0.1", "0 to 1"),
    ("pybullet", "motor_force", "0", "above 0"),
    ("pybullet", "max_joint_velocity", "-1", "above 0"),
    ("pybullet", "average_impulses", "2", "use true or false"),
    ("pybullet", "midpoint_velocity", "sometimes", "use true or false"),
    ("pybullet", "preroll_steps", "-100", "0 to 10000"),
    ("exudyn", "timestep", "1e-9", "1e-06 to 0.1 s"),
    ("exudyn", "steps_per_rev", "100000000", "1 to 1e+06"),
    ("exudyn", "steps_per_rev", "0", "1 to 1e+06"),
    ("exudyn", "spectral_radius", "1.5", "0 to 1"),
    ("exudyn", "newton_tolerance", "0", "1e-15 to 1"),
    ("exudyn", "newton_tolerance", "1e-20", "1e-15 to 1"),
    ("exudyn", "sample_by", "both", "use one of integrator, state"),
]

#: Values at the ends of the ranges (and the studies' extremes): accepted.
POSSIBLE = [
    ("mujoco", "timestep", "1e-6"), ("mujoco", "timestep", "0.1"),
    ("mujoco", "solref", "0.02,1"), ("mujoco", "solref", "-1e4,0"),
    ("mujoco", "solimp", "0.0001,0.9999,0.001,0.5,1"), ("mujoco", "iterations", "1"),
    ("mujoco", "iterations", "1000"), ("mujoco", "tolerance", "0"),
    ("mujoco", "armature", "1e12"), ("mujoco", "invweight_scale", "1"),
    ("pybullet", "erp", "0"), ("pybullet", "erp", "1"), ("pybullet", "preroll_steps", "0"),
    ("pybullet", "residual_threshold", "0"),
    ("exudyn", "steps_per_rev", "1000000"), ("exudyn", "spectral_radius", "0"),
    ("exudyn", "newton_tolerance", "1e-15"),
]

ENGINES = [e for e in ("mujoco", "pybullet", "exudyn") if e in available_engines()]


def _rows(table):
    return [pytest.param(*r, id=f"{r[0]}.{r[1]}={r[2]}") for r in table if r[0] in ENGINES]


@pytest.mark.parametrize("engine", ENGINES)
def test_every_field_has_a_range_and_an_impossible_value(engine):
    """The audit: each field of each engine's settings has a range (the defaults pass
    it) and at least one row of IMPOSSIBLE, so a new field without either fails here."""
    cls = get_engine(engine).settings_class
    fields = {f.name for f in dataclasses.fields(cls)}
    assert set(cls.RANGES) == fields
    cls()  # the recommended settings are inside
    assert {k for e, k, *_ in IMPOSSIBLE if e == engine} == fields


@pytest.mark.parametrize("engine, key, value, words", _rows(IMPOSSIBLE))
def test_impossible_setting_is_refused_by_the_dataclass(engine, key, value, words):
    """Through make_settings (strings, as --set gives them) and, for a typed value, the
    dataclass itself: one SettingsError naming the key, its value and the range."""
    with pytest.raises(SettingsError) as e:
        make_settings(engine, {key: value})
    assert e.value.key == key and words in str(e.value), str(e.value)
    assert f"engine {engine!r} setting {key}=" in str(e.value)
    assert "\n" not in str(e.value)
    typed = get_engine(engine).settings_class.field_types()[key]
    if typed in (int, float):
        try:
            number = typed(float(value))
        except ValueError:
            return
        with pytest.raises(SettingsError, match=key):
            get_engine(engine).settings_class(**{key: number})


@pytest.mark.parametrize("engine, key, value", [pytest.param(*r, id=f"{r[0]}.{r[1]}={r[2]}")
                                                for r in POSSIBLE if r[0] in ENGINES])
def test_range_ends_are_accepted(engine, key, value):
    s = make_settings(engine, {key: value})
    assert getattr(s, key) is not None


def test_the_studies_settings_are_inside_the_ranges():
    """The report's speed-against-error grid and hard-case plans (every case, the full
    variant) build their settings through the same ranges: none may be refused."""
    from analytic.cases import case_names
    from reports.studies import hard_cases
    from reports.studies import speed_accuracy as studies
    n = 0
    for case in case_names():
        for p in studies.grid_plan(case, quick=False):
            if p["engine"] in ENGINES:
                make_settings(p["engine"], p["settings"])
                n += 1
    for plans in hard_cases._hard_plan(False).values():
        for engine, rows in plans.items():
            for _, settings in (rows if isinstance(rows, list) else [rows]):
                if engine in ENGINES:
                    make_settings(engine, settings)
                    n += 1
    assert n > 100


REQUESTS = [
    ("revolutions", 0), ("revolutions", -3), ("revolutions", True), ("revolutions", 100000),
    ("samples", 1), ("samples", 10_000_000), ("max_violation", math.nan),
    ("max_violation", 0.0), ("max_violation", 2.0), ("max_speed_error", -1.0),
    ("chords", "bogus"), ("mode", "fast"),
]


@pytest.mark.parametrize("key, value", REQUESTS, ids=[f"{k}={v}" for k, v in REQUESTS])
def test_run_request_out_of_range_is_refused(key, value):
    with pytest.raises(SettingsError) as e:
        RunRequest(**{key: value})
    assert e.value.key == key and f"run request {key}=" in str(e.value)


def test_run_request_ends_and_instantaneous_states():
    RunRequest(1, 2)
    RunRequest(1000, 3600, 1.0, 1.0, "analytic")
    RunRequest(1, 1, mode="instantaneous")  # one state is enough there
    with pytest.raises(SettingsError, match="samples"):
        RunRequest(1, 1)


def test_run_refuses_a_request_before_building_anything(monkeypatch):
    """driven.run checks the request first: no session is opened."""
    from sim_models.runs import driven
    monkeypatch.setattr(driven, "open_session", lambda *a, **k: pytest.fail("opened"))
    monkeypatch.setattr(driven, "compile_linkage", lambda *a, **k: pytest.fail("compiled"))
    with pytest.raises(SettingsError, match="revolutions"):
        driven.run(object(), "mujoco", revolutions=0)


def test_set_conflicts_and_precedence():
    """A flag and a --set of one setting, or one key twice with different values, are
    refused; ENGINE.KEY wins over a plain KEY whatever the order (the README says so)."""
    from sim_models.engines.registry import settings_from_options, split_overrides
    engines = [e for e in ("mujoco", "pybullet") if e in ENGINES]
    with pytest.raises(SettingsError, match=r"--integrator RK4 and --set integrator=Euler"):
        settings_from_options(engines, ["integrator=Euler"],
                              {"--integrator": ("integrator", "RK4")})
    with pytest.raises(SettingsError, match="both set mujoco's timestep"):
        settings_from_options(engines, ["timestep=1e-3", "timestep=2e-3"])
    for order in (["timestep=1e-4", "mujoco.timestep=2e-4"],
                  ["mujoco.timestep=2e-4", "timestep=1e-4"]):
        s = settings_from_options(engines, order)
        assert s["mujoco"].timestep == 2e-4
        if "pybullet" in s:
            assert s["pybullet"].timestep == 1e-4
    assert split_overrides(["timestep=1e-4", "timestep=1e-4"], ["mujoco"]) == \
        {"mujoco": {"timestep": "1e-4"}}
    with pytest.raises(SettingsError, match=r"^--set mujoco\.iterations=-5: -5 is out"):
        settings_from_options(engines, ["mujoco.iterations=-5"])
    with pytest.raises(SettingsError, match=r"^argument --integrator: no engine run here has "
                                            r"a setting 'integrator' \(engines: pybullet\)"):
        settings_from_options(["pybullet"], [], {"--integrator": ("integrator", "RK4")})
    with pytest.raises(SettingsError, match=r"^argument --timestep: 10 is out of range"):
        settings_from_options(engines, [], {"--timestep": ("timestep", 10.0)})
