"""Free-motion runs of the engines (issue 21): :func:`run_free` releases a linkage in an
engine from the exact reference state and returns its :class:`FreeEngineRun`.

    from analytic import load_case
    from sim_models.runs.free import run_free
    from sim_models.runs.free_run import FreeRequest
    r = run_free(load_case("iftomm-a01-pendulum"), "mujoco", request=FreeRequest(2.0))

Each engine's free session lives beside its prescribed one (:data:`FREE_SESSIONS`);
the run loop, readout and energy are :mod:`sim_models.engines.free_protocol` (one for all).
"""

from __future__ import annotations

import dataclasses
import importlib

from analytic import Mechanism
from analytic.free_motion import simulate

from ..builders.tree import SimTree
from ..engines.free_protocol import FreeSession, drive_free
from ..engines.protocol import compile_linkage
from ..engines.registry import UnknownEngineError, skipped_engines
from ..engines.settings import EngineRefusal, EngineSettings
from .free_run import FreeEngineRun, FreeRequest
from .free_step import choose_step

#: engine name -> (module, free session class)
FREE_SESSIONS: dict[str, tuple[str, str]] = {
    "mujoco": ("sim_models.engines.mujoco.free", "MujocoFreeSession"),
    "pybullet": ("sim_models.engines.pybullet.free", "PybulletFreeSession"),
    "exudyn": ("sim_models.engines.exudyn.free", "ExudynFreeSession"),
    "pinocchio": ("sim_models.engines.pinocchio.free", "PinocchioFreeSession"),
    "mujoco_warp": ("sim_models.engines.mujoco_warp.free", "MujocoWarpFreeSession"),
}


def free_engine_names() -> tuple[str, ...]:
    """The engines with a free-motion run (an optional engine whose library is not
    installed is left out: :func:`sim_models.engines.registry.skipped_engines`)."""
    return tuple(n for n in FREE_SESSIONS if n not in skipped_engines())


def free_session_class(engine: str) -> type[FreeSession]:
    """The free session class of ``engine`` (:class:`UnknownEngineError` if none)."""
    if engine not in FREE_SESSIONS:
        raise UnknownEngineError(f"engine {engine!r} has no free-motion run; engines with "
                                 f"one: {', '.join(FREE_SESSIONS)}")
    mod, cls = FREE_SESSIONS[engine]
    return getattr(importlib.import_module(mod), cls)


def free_settings(engine: str, overrides=None) -> EngineSettings:
    """The recommended free-motion settings of ``engine`` with ``overrides`` applied
    (``key=value`` strings or typed values; :class:`SettingsError` naming the key)."""
    return free_session_class(engine).settings_class.from_overrides(overrides, engine)


def open_free_session(mech: Mechanism | SimTree, engine: str,
                      settings: EngineSettings | None = None) -> FreeSession:
    """A built free session of ``engine`` (close it after use)."""
    cls = free_session_class(engine)
    if settings is not None and not isinstance(settings, cls.settings_class):
        raise EngineRefusal(f"engine {engine!r}: free-motion settings must be "
                            f"{cls.settings_class.__name__}, got {type(settings).__name__}")
    return cls(compile_linkage(mech), settings)


def run_free(mech: Mechanism | SimTree, engine: str, settings: EngineSettings | None = None,
             request: FreeRequest | None = None, reference=None,
             step_from_motion: bool | None = None) -> FreeEngineRun:
    """Release ``mech`` (its ``[motion]``) in ``engine`` from the reference's state at
    t = 0 and read it at ``request.times()`` (default: the description's duration and
    samples).  ``reference``: the :class:`analytic.free_motion.FreeTrajectory` if already
    computed (else it is computed here, for the initial state and energy scale).  A
    diverging run returns ``ok = False`` with ``t_fail`` and ``reason``; an engine that
    cannot build the model raises :class:`EngineRefusal`.

    ``step_from_motion``: shorten the step where the exact motion turns a body further
    in one step than :data:`sim_models.runs.free_step.MAX_TURN_PER_STEP` (the run's
    ``step_choice`` says so); default: only when ``settings`` is None (the recommended
    ones).  A caller whose user set the step passes False: a set step always wins."""
    tree = compile_linkage(mech)
    fm = tree.mech.motion
    if fm is None:
        raise EngineRefusal(f"mechanism {tree.mech.name!r} has no [motion] table: nothing "
                            "to release")
    request = request or FreeRequest(duration=fm.duration, samples=max(1, fm.samples - 1))
    choice = None
    if settings is None if step_from_motion is None else step_from_motion:
        settings = settings if settings is not None else free_settings(engine)
        if reference is None:
            reference = simulate(tree.mech, duration=request.duration)
        choice = choose_step(reference, request.times(), float(settings.timestep))
        if choice is not None:
            settings = dataclasses.replace(settings, timestep=choice.chosen)
    session = open_free_session(tree, engine, settings)
    try:
        run = drive_free(session, request, reference)
    finally:
        session.close()
    run.step_choice = choice
    return run


__all__ = ["FREE_SESSIONS", "free_engine_names", "free_session_class", "free_settings",
           "open_free_session", "run_free"]
