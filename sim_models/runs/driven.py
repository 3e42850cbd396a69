"""The front door of the engine runs: any registered engine, by name.

::

    from sim_models.runs.driven import run, rerun, instantaneous, open_session
    tree = compile_linkage(mech)                        # once per mechanism
    r = run(tree, "mujoco")                             # recommended settings
    r = run(tree, "pybullet", make_settings("pybullet", {"timestep": "1e-4"}))
    r2 = rerun(r)                                       # the same run again, exactly
    f = instantaneous(tree, "mujoco", values=[0.5, 1.0])

Every run goes through :func:`sim_models.engines.protocol.drive` (the one run loop) with the
engine's :class:`~sim_models.engines.protocol.Session` from :mod:`sim_models.engines.registry`; the
sampling conventions are in :mod:`sim_models.engines.protocol`.
"""

from __future__ import annotations

import time

import numpy as np

from analytic import Mechanism

from ..builders.tree import SimModelError, SimTree  # noqa: F401 - SimTree: the compiled linkage
from ..engines.protocol import (
    EngineRefusal,
    EngineRun,
    EngineSettings,
    Plan,
    Recorder,
    RunRequest,
    Session,
    compile_linkage,
    drive,
    finish,
    plan_samples,
)
from ..engines.registry import engine_names, get_engine
from .timing import time_steps


def open_session(tree: Mechanism | SimTree, engine: str,
                 settings: EngineSettings | None = None) -> Session:
    """A session of ``engine`` on the compiled linkage (a Mechanism is compiled first).
    Close it (or use it as a context manager) when done."""
    eng = get_engine(engine)
    tree = compile_linkage(tree)
    if settings is not None and not isinstance(settings, eng.settings_class):
        raise EngineRefusal(f"engine {eng.name!r} needs {eng.settings_class.__name__}, got "
                            f"{type(settings).__name__}")
    return eng.session_class(tree, settings)


def run(mech: Mechanism | SimTree, engine: str, settings: EngineSettings | None = None,
        revolutions: int = RunRequest.revolutions, samples: int = RunRequest.samples,
        max_violation: float = RunRequest.max_violation,
        max_speed_error: float = RunRequest.max_speed_error, chords: str = RunRequest.chords,
        plan: Plan | None = None, wall_limit: float | None = None) -> EngineRun:
    """Simulate the linkage in ``engine`` and sample it (see :mod:`sim_models.engines.protocol`).

    Parameters
    ----------
    mech
        The compiled linkage (:class:`SimTree`, from :func:`compile_linkage`) or a
        description (compiled here, with ``chords``).
    engine
        A registered engine name (:func:`sim_models.engines.registry.engine_names`).
    settings
        The engine's settings object (default: its recommended settings).
    revolutions, samples
        Turns simulated (the last sampled at ``samples`` of the sweep's inputs), or, for
        a motion sampled by time, the input's travel in turns and the sample count.
    max_violation, max_speed_error
        Divergence thresholds: loop gap relative to the mechanism's size, driver-rate
        error relative to its speed.
    plan
        A ready sampling plan (e.g. equal times over a long run); default
        :func:`plan_samples`.
    wall_limit
        Seconds of stepping after which the run ends as a failed run that says so
        (None: no limit).

    Raises
    ------
    EngineRefusal
        When the engine cannot run this motion.
    SettingsError
        For a request outside :mod:`sim_models.engines.ranges`.  A diverging simulation
        is a run with ``ok = False``, never an exception.
    """
    # the request first: a value out of range is refused before anything is built
    request = RunRequest(revolutions, samples, max_violation, max_speed_error,
                         mech.chords_mode if isinstance(mech, SimTree) else chords, "run",
                         wall_limit)
    tree = compile_linkage(mech, chords=chords)
    plan = plan or plan_samples(tree, revolutions, samples)
    with open_session(tree, engine, settings) as session:
        return drive(session, plan, request)


def not_run(mech: Mechanism | SimTree, engine: str, settings: EngineSettings | None,
            reason: str, revolutions: int = RunRequest.revolutions,
            samples: int = RunRequest.samples) -> EngineRun:
    """The :class:`EngineRun` of an engine that could not run at all (it raised while
    building or stepping): ``ok = False``, ``reason``, every sample NaN, so that it is
    compared, printed and counted as a failed run ("not measured" from the first
    sample) beside the engines that did run."""
    tree = compile_linkage(mech)
    plan = plan_samples(tree, revolutions, samples)
    stand_in = _NoSession(tree, engine, settings)
    rec = Recorder(tree, plan)  # every sample NaN: not reached
    return finish(stand_in, plan, rec, RunRequest(revolutions, samples), reason,
                  float(tree.driver_path(0.0)[0]), 0.0, 0.0, 0)


class _NoSession:
    """What :func:`finish` reads of a session, for :func:`not_run` (no engine built)."""

    engine_readings = False

    def __init__(self, tree: SimTree, engine: str, settings: EngineSettings | None):
        self.tree, self.name = tree, engine
        self.settings = settings if settings is not None else \
            get_engine(engine).settings_class()
        self.notes: list[str] = []

    def extra(self) -> dict:
        return {}


def rerun(r: EngineRun) -> EngineRun:
    """Run ``r`` again from its own record (mechanism, settings object, request), on
    the compiled :class:`~analytic.Linkage` it carries (not a rebuilt one)."""
    req = r.request
    tree = compile_linkage(r.mechanism, r.linkage, chords=req.chords)
    base = r.engine.split("-")[0]
    if req.mode == "instantaneous":
        return instantaneous(tree, base, r.settings, r.values)
    return run(tree, base, r.settings, req.revolutions, req.samples, req.max_violation,
               req.max_speed_error)


def instantaneous(mech: Mechanism | SimTree, engine: str,
                  settings: EngineSettings | None = None, values=None) -> EngineRun:
    """The engine's accelerations and forces at the analytic state (positions, velocities
    and the driver's prescribed acceleration from :meth:`Linkage.kinematics`) for each
    driver value (rad or m; default the reference), without stepping.  Engines without a
    forward-dynamics call refuse (:class:`EngineRefusal`)."""
    eng = get_engine(engine)
    if eng.session_class.forward_at is Session.forward_at:
        able = [n for n in engine_names() if has_instantaneous(n)]
        raise EngineRefusal(f"engine {eng.name!r} has no instantaneous mode (no forward-"
                            f"dynamics call at a given state); engines with one: "
                            f"{', '.join(able) or 'none'}")
    tree = compile_linkage(mech)
    d = tree.mech.driver
    vals = np.atleast_1d(np.asarray(d.value if values is None else values, float))
    kin = tree.linkage.kinematics(vals, on_singular="flag")
    q, qd, _ = tree.coords(kin)
    plan = Plan(vals, np.zeros(len(vals)), kin.velocity, kin.acceleration, False, False,
                0.0, 0.0, 1)
    with open_session(tree, engine, settings) as session:
        rec = Recorder(tree, plan)
        t0 = time.perf_counter()
        for i in range(len(vals)):
            session.forward_at(q[i], qd[i], float(kin.acceleration[i]), [i], rec)
            rec.speed[i] = tree.driver_sigma * qd[i, tree.driver_tree] - kin.velocity[i]
        wall = time.perf_counter() - t0
        request = RunRequest(1, len(vals), mode="instantaneous")
        return finish(session, plan, rec, request, None, None, wall, 0.0, 0,
                      engine=f"{session.name}-instantaneous")


def time_engine(mech: Mechanism | SimTree, engine: str, settings: EngineSettings | None,
                h: float, n: int, repeats: int = 3, clock=None) -> float:
    """Steps per second of ``n`` bare steps of ``h`` s (the session's own
    :meth:`~sim_models.engines.protocol.Session.advance`, the loop the runs use, without
    readout), best of ``repeats``: :func:`sim_models.runs.timing.time_steps` (``clock``:
    its clock, None for wall time)."""
    with open_session(mech, engine, settings) as session:
        return time_steps(session, h, n, repeats) if clock is None else \
            time_steps(session, h, n, repeats, clock)


def has_instantaneous(name: str) -> bool:
    """Whether engine ``name`` has a forward-dynamics call (the instantaneous mode)."""
    try:
        return get_engine(name).session_class.forward_at is not Session.forward_at
    except (ImportError, SimModelError):  # an engine whose library is missing
        return False


def mujoco_instantaneous(mech: Mechanism | SimTree, settings=None, values=None) -> EngineRun:
    """:func:`instantaneous` in MuJoCo (kept for the tests and the report's floor table)."""
    return instantaneous(mech, "mujoco", settings, values)


__all__ = ["EngineRefusal", "EngineRun", "has_instantaneous", "instantaneous",
           "mujoco_instantaneous", "not_run",
           "open_session", "rerun", "run", "time_engine"]
