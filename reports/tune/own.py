"""``xval tune MODEL.xml``: the user's own MJCF model as a tuned case.

The model is read as ``xval compare MODEL.xml`` and ``xval simulate MODEL.xml`` read it
(:func:`sim_models.own.import_model`), run by MuJoCo with its own options and judged
against the exact solution of the description it maps to: driven
(:func:`sim_models.own.mujoco_own.run_prescribed`) or released
(:func:`sim_models.own.mujoco_own_free.run_free_own`).  A candidate's settings are the
file's with some set over them (:func:`sim_models.own.mujoco_own.apply_tuned`): the
step, the integrator, the solver's iterations and tolerance, and ``solref``/``solimp``
of every equality constraint; the first level of every knob is the file's own value, so
the search starts from the model as written.
"""

from __future__ import annotations

import functools
import math
import time

from reports.comparison.quantities import judged
from reports.tune.space import Knob

#: The integrators a candidate may use (MJCF spellings).
INTEGRATOR_LEVELS = ("RK4", "implicitfast", "Euler")
#: ``solref`` levels in MuJoCo's standard form (time constant s, damping ratio 1), the
#: form users write: MuJoCo's default 0.02 s down to 1 ms (MuJoCo keeps the time
#: constant at least twice the step, so a level below that acts as 2 steps).
SOLREF_LEVELS = ((0.02, 1.0), (0.005, 1.0), (0.002, 1.0), (0.001, 1.0))
#: ``solimp`` levels: near-hard (the harness's own models) and MuJoCo's default.
SOLIMP_LEVELS = {"near-hard": (0.9999, 0.9999, 0.001, 0.5, 2.0),
                 "MuJoCo default": (0.9, 0.95, 0.001, 0.5, 2.0)}
#: Solver levels: a tighter and a looser stop, and fewer iterations (cheaper).
TOLERANCE_LEVELS = (1e-12, 1e-6)
ITERATION_LEVELS = (100, 20)
#: The label of a knob's first level: the value the file gives.
FILE = "(file)"


def is_own(case: str) -> bool:
    """Whether ``case`` names a user's MJCF model (what ``xval tune`` tunes as one)."""
    return str(case).lower().endswith(".xml")


@functools.lru_cache(maxsize=4)
def own_model(case: str, driver: str | None, keyframe: str | None,
              duration: float | None):
    """The imported model (once per worker process; a bad model raises
    :class:`analytic.errors.DescriptionError`, one line)."""
    from sim_models.own import DEFAULT_DURATION, import_model
    return import_model(case, driver, keyframe, duration or DEFAULT_DURATION)


def model_of(tc):
    return own_model(tc.case, tc.driver, tc.keyframe, tc.duration if tc.free else None)


@functools.lru_cache(maxsize=4)
def own_free_reference(case: str, driver: str | None, keyframe: str | None,
                       duration: float | None, samples: int | None):
    """``(imported, traj, request, reference samples)`` of the model released as
    ``xval simulate MODEL.xml --engine mujoco`` releases it."""
    from analytic.free_motion import simulate
    from reports.comparison.free_compare import reference_samples
    from sim_models.runs.free_run import FreeRequest
    imp = own_model(case, driver, keyframe, duration)
    traj = simulate(imp.mechanism)
    n = samples or imp.mechanism.motion.samples
    req = FreeRequest(duration=traj.duration, samples=max(1, n - 1))
    return imp, traj, req, reference_samples(traj, req.times())


def free_reference_of(tc):
    return own_free_reference(tc.case, tc.driver, tc.keyframe, tc.duration, tc.samples)


def check_moves(tc) -> None:
    """A released model that does not move has nothing to judge (one line, as
    ``xval simulate MODEL.xml`` says it)."""
    import numpy as np

    from analytic.errors import DescriptionError
    from reports.regression.own_model import STILL
    imp, traj, _req, _ref = free_reference_of(tc)
    smp = traj.at(np.linspace(0.0, traj.duration, 3 if tc.samples is None else tc.samples),
                  forces=False)
    if np.ptp(smp.x) <= STILL:
        raise DescriptionError(f"released from {imp.compiled.config} the model does not "
                               "move (at rest, no in-plane gravity, spring or motor); give "
                               "a keyframe with a velocity (--keyframe NAME)", tc.case)


def check_runs(tc) -> None:
    """MuJoCo's session can read the model in the description's tree (its joint map):
    an :class:`sim_models.engines.settings.EngineRefusal` here is one line, not a failed
    run in every worker."""
    from sim_models.engines.protocol import compile_linkage
    from sim_models.own.mujoco_own import Mapping
    imp = model_of(tc)
    Mapping(compile_linkage(imp.mechanism, chords="analytic"), imp)


def unit_time(tc) -> float:
    """One revolution of the imported driver (prescribed), 1 s (free)."""
    if tc.free:
        return 1.0
    from sim_models.engines.protocol import travel_time
    return float(travel_time(model_of(tc).mechanism.driver, 2 * math.pi))


# ============================================================================ settings
def split(overrides: dict) -> tuple[float | None, tuple]:
    """``(timestep, tuned pairs)`` of a candidate's overrides."""
    from sim_models.own.mujoco_own import TUNED_KEYS
    tuned = tuple((k, overrides[k]) for k in TUNED_KEYS if k in overrides)
    return overrides.get("timestep"), tuned


def settings_of(tc, overrides: dict):
    """The run's settings record (:func:`sim_models.own.mujoco_own.own_settings`)."""
    from sim_models.own.mujoco_own import own_settings
    step, tuned = split(overrides)
    return own_settings(model_of(tc), prescribed=not tc.free, timestep=step, tuned=tuned)


def file_values(tc) -> dict:
    """The file's own value of every setting a candidate may change, as MJCF writes it
    (``solref``/``solimp``: the first equality constraint's; None without one)."""
    from sim_models.own.mujoco_own import file_settings
    return file_settings(model_of(tc).compiled.model)


def changed(tc, overrides: dict) -> dict:
    """field -> (the file's value, the candidate's) for what a candidate changes."""
    own = file_values(tc)
    out = {}
    for k, v in overrides.items():
        old = own.get(k)
        if old is None or not _same(old, v):
            out[k] = (old, v)
    return out


def _same(a, b) -> bool:
    if isinstance(a, tuple) and isinstance(b, tuple):
        n = min(len(a), len(b))
        return all(math.isclose(x, y, rel_tol=1e-12) for x, y in zip(a[:n], b[:n],
                                                                      strict=True))
    if isinstance(a, float) and isinstance(b, (int, float)):
        return math.isclose(a, b, rel_tol=1e-12)
    return a == b


# ============================================================================ knobs
def _num(v) -> str:
    return " ".join(f"{x:g}" for x in v) if isinstance(v, tuple) else f"{v:g}"


def _knob(name: str, key: str, own, levels: dict, why: str) -> Knob:
    """A knob whose first level is the file's value (no override), then ``levels``
    (label -> value) that differ from it."""
    lv = {f"{_num(own) if not isinstance(own, str) else own} {FILE}": {}}
    for label, v in levels.items():
        if not _same(own, v):
            lv[label] = {key: v}
    return Knob(name, tuple(lv), lv, why)


def own_knobs(tc, limit: int | None = None) -> tuple[Knob, ...]:
    """The knobs of a user's model: its integrator and solver, and (with equality
    constraints) their ``solref`` and ``solimp``, each starting at the file's value."""
    own = file_values(tc)
    knobs = [_knob("integrator", "integrator", own["integrator"],
                   {v: v for v in INTEGRATOR_LEVELS}, "the integration formula")]
    if own["solref"] is not None:
        knobs.append(_knob("solref", "solref", own["solref"],
                           {_num(v): v for v in SOLREF_LEVELS},
                           "the equality constraints' time constant (how soft the loop is)"))
        knobs.append(_knob("solimp", "solimp", own["solimp"], SOLIMP_LEVELS,
                           "the equality constraints' impedance"))
    knobs.append(_knob("solver tolerance", "tolerance", own["tolerance"],
                       {_num(v): v for v in TOLERANCE_LEVELS},
                       "the constraint solver's stopping rule"))
    knobs.append(_knob("solver iterations", "iterations", own["iterations"],
                       {str(v): v for v in ITERATION_LEVELS},
                       "the constraint solver's iteration cap"))
    knobs = tuple(k for k in knobs if len(k.levels) > 1)
    return knobs if limit is None else knobs[:limit]


# ============================================================================ runs
def measure(tc, s, overrides: dict, timed: bool, steps: int, repeats: int):
    """A candidate's run on the user's model (:func:`reports.tune.measure.measure_task`'s
    own branch): ``(Measured fields)``."""
    step, tuned = split(overrides)
    if tc.free:
        return _free(tc, s, overrides, step, tuned, timed, steps, repeats)
    return _prescribed(tc, s, overrides, step, tuned, timed, steps, repeats)


def _prescribed(tc, s, overrides, step, tuned, timed, steps, repeats):
    from reports.comparison.compare import compare_run
    from reports.tune.measured import Measured, prescribed_errors
    from sim_models.own.mujoco_own import OwnMujocoSession, run_prescribed
    from sim_models.runs.engine_run import RunRequest
    from sim_models.runs.timing import time_steps
    imp, req = model_of(tc), RunRequest()
    t0 = time.process_time()
    tree, r = run_prescribed(imp, req, step, tuned)
    cpu = time.process_time() - t0
    comps = judged(compare_run(r)) if r.ok else []
    errs = prescribed_errors(comps)
    cost = math.nan
    if timed and r.ok and r.steps > 0:
        with OwnMujocoSession(tree, imp, s) as session:
            sps = time_steps(session, float(r.timestep), min(steps, int(r.steps)), repeats,
                             time.process_time)
        cost = 1.0 / sps if sps > 0 else math.nan
    return Measured(dict(overrides), bool(r.ok), r.reason or "", errs,
                    float(r.steps_per_rev), int(r.steps), cpu, float(req.revolutions),
                    s.describe(), cost)


def _free(tc, s, overrides, step, tuned, timed, steps, repeats):
    import numpy as np

    from reports.comparison.free_compare import compare_free
    from reports.tune.measured import Measured, free_errors
    from sim_models.engines.free_protocol import free_start
    from sim_models.engines.protocol import compile_linkage
    from sim_models.own.mujoco_own_free import OwnFreeSession, run_free_own
    from sim_models.runs.timing import time_free_steps
    imp, traj, req, ref = free_reference_of(tc)
    t0 = time.process_time()
    r = run_free_own(imp, req, traj, step, tuned)
    cpu = time.process_time() - t0
    v = compare_free(r, traj, ref)
    errs = free_errors(v)
    dur = float(req.duration)
    cost = math.nan
    if timed and r.ok and r.steps > 0:
        tree = compile_linkage(imp.mechanism, chords="analytic")
        session = OwnFreeSession(tree, imp, s)
        try:
            start = free_start(tree, traj.at(np.array([0.0]), forces=False))
            sps = time_free_steps(session, start, float(r.timestep),
                                  min(steps, int(r.steps)), repeats, time.process_time)
        finally:
            session.close()
        cost = 1.0 / sps if sps > 0 else math.nan
    return Measured(dict(overrides), bool(r.ok), r.reason or "", errs,
                    float(r.steps) / dur, int(r.steps), cpu, dur, s.describe(), cost)


# ============================================================================ the file
def tuned_text(tc, changes: dict, why: dict, header: str):
    """The user's file with ``changes`` (field -> new value) written into its
    attributes (:func:`reports.tune.model.tuned_model_text`: nothing else changes)."""
    from pathlib import Path

    from reports.tune.model import ModelWriteError, tuned_model_text
    try:
        text = Path(tc.case).read_bytes().decode("utf-8")
    except UnicodeDecodeError as e:
        raise ModelWriteError(f"{tc.case}: not UTF-8 text ({e.reason} at byte {e.start}); "
                              "--write-model edits a UTF-8 MJCF file") from None
    try:
        return tuned_model_text(text, changes, why, None, header)
    except ModelWriteError as e:
        raise ModelWriteError(f"{tc.case}: {e}") from None


def read_back(path: str, tc, overrides: dict) -> list[str]:
    """What MuJoCo reads from the written file that differs from the tuned run's
    settings (``key: file / run``; empty: the file carries them all)."""
    from analytic.errors import DescriptionError
    from sim_models.own import import_model
    from sim_models.own.mujoco_own import option_items, own_settings
    try:
        imp = import_model(path, tc.driver, tc.keyframe)
    except DescriptionError as e:  # e.g. an <include> not found beside the written file
        return [f"the written file is not read as the model was: {e}"]
    step, tuned = split(overrides)
    want = own_settings(model_of(tc), prescribed=False, timestep=step, tuned=tuned)
    got = option_items(imp.compiled.model)
    exp = dict(x.split("=", 1) for x in want.options.split(";")[0].split())
    if step is not None:
        exp["timestep"] = f"{step:g}"
    return [f"{k}: {got.get(k)} / {v}" for k, v in exp.items() if got.get(k) != v]


__all__ = ["FILE", "changed", "check_moves", "check_runs", "file_values", "is_own", "measure",
           "model_of", "own_knobs", "read_back", "settings_of", "tuned_text", "unit_time"]
