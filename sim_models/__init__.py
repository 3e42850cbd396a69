"""Engine models of the linkages (MuJoCo via MjSpec, PyBullet via URDF) and their runs.

Front door::

    from sim_models import run, mujoco_instantaneous, MujocoSettings, PybulletSettings
    r = run(mech, "mujoco", MujocoSettings(), revolutions=2, samples=36)

Neither engine is imported until a model is built.
"""

from .engines import EngineRun, mujoco_instantaneous, run
from .mjcf import EngineVersionError, MujocoSettings, build_mjcf, compile_mjcf
from .tree import SimModelError, SimTree, UnsupportedClosureError
from .urdf import Closure, build_urdf


def __getattr__(name):  # PybulletSettings without importing pybullet eagerly
    if name == "PybulletSettings":
        from .pybullet_sim import PybulletSettings
        return PybulletSettings
    raise AttributeError(name)


__all__ = ["Closure", "EngineRun", "EngineVersionError", "MujocoSettings", "PybulletSettings",
           "SimModelError", "SimTree", "UnsupportedClosureError", "build_mjcf", "build_urdf",
           "compile_mjcf", "mujoco_instantaneous", "run"]
