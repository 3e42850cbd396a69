"""Engine models of the linkages and their runs, behind one protocol and registry.

Front door::

    from sim_models import compile_linkage, run, make_settings
    tree = compile_linkage(mech)                  # the analytic solution, compiled once
    r = run(tree, "mujoco", make_settings("mujoco", {"integrator": "Euler"}))
    f = run_free(released_mech, "mujoco", request=FreeRequest(duration=1.0))  # released

The rooms, along the data flow: :mod:`sim_models.builders` (the compiled linkage and the
engine models built from it), :mod:`sim_models.engines` (the protocol, the registry, one
folder per engine), :mod:`sim_models.runs` (a run of any engine by name, its plan and its
records), :mod:`sim_models.own` (models that users bring) and ``models/`` (the generated
model files).  No engine library is imported until an engine is asked for.
"""

from .builders.mjcf import EngineVersionError, MujocoSettings, build_mjcf, compile_mjcf
from .builders.tree import SimModelError, SimTree, UnsupportedClosureError
from .builders.urdf import Closure, build_urdf
from .engines.protocol import (
    EngineRefusal,
    EngineRun,
    EngineSettings,
    Session,
    SettingsError,
    compile_linkage,
)
from .engines.registry import engine_names, get_engine, make_settings, register_engine
from .runs.driven import instantaneous, mujoco_instantaneous, open_session, rerun, run


def __getattr__(name):  # without importing pybullet, or the free motion, eagerly
    if name == "PybulletSettings":
        from .engines.pybullet.driven import PybulletSettings
        return PybulletSettings
    if name == "run_free":
        from .runs.free import run_free
        return run_free
    if name in ("FreeRequest", "FreeEngineRun"):
        from .runs import free_run
        return getattr(free_run, name)
    raise AttributeError(name)


__all__ = ["Closure", "EngineRefusal", "EngineRun", "EngineSettings", "EngineVersionError",
           "FreeEngineRun", "FreeRequest", "MujocoSettings", "PybulletSettings", "Session",
           "SettingsError", "SimModelError", "SimTree", "UnsupportedClosureError", "build_mjcf",
           "build_urdf", "compile_linkage", "compile_mjcf", "engine_names", "get_engine",
           "instantaneous", "make_settings", "mujoco_instantaneous", "open_session",
           "register_engine", "rerun", "run", "run_free"]
