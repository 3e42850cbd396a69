"""Runs and baselines of a user's own engine model (MJCF ``.xml``, or URDF ``.urdf`` with
its closures), for every door that is not the command line's own: ``xval baseline
record MODEL.xml --engine mujoco [--free] [--driver J] [--keyframe K]``, ``baseline
check``, and the pytest plugin (``xval.assert_agrees("model.xml", engine="mujoco")``,
``xval.assert_free_agrees``, ``xval_baseline``).

A baseline's identity of the model is the parsed model: the imported description's
content with the compiled model's options (:func:`sim_models.own.mujoco_own.option_items`:
timestep, integrator, solver, each constraint's ``solref``/``solimp``) and the import
options given (``own.driver``, ``own.keyframe``), so a comment or a reformatted file is
no change and a moved anchor or a new ``solref`` is, named.  Its runs are MuJoCo's on the
file as it is: driven (:func:`sim_models.own.mujoco_own.run_prescribed`) or released from
the model's own state (:func:`sim_models.own.mujoco_own_free.run_free_own`).  Run
requests go through the command line's ranges (:class:`sim_models.runs.engine_run.RunRequest`,
:func:`reports.regression.baseline_free.free_request_problem`).
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from reports.comparison.compare import compare_run
from reports.comparison.runs import Verdict
from reports.regression import model_identity as mid
from reports.regression.baseline_free import free_request_problem, is_free
from sim_models.engines.protocol import EngineRefusal
from sim_models.engines.settings import SettingsError

#: A reference whose joint coordinates all stay within this (rad or m) does not move:
#: rounding of a closed loop at rest is ~1e-16 rad; a motion worth judging is far above.
STILL = 1e-9
#: The engines a user's model runs in.
OWN_ENGINES = ("mujoco",)


@dataclass(frozen=True)
class ImportOptions:
    """How a user's model is read (``xval import``'s options): the input joint (None:
    the one actuated joint), the keyframe (None: ``qpos0``), the loop closures a URDF
    cannot hold (:class:`sim_models.own.Close`)."""

    driver: str | None = None
    keyframe: str | None = None
    closes: tuple = ()


#: The import options of each mechanism imported here (by ``id``, the mechanism kept
#: alive beside them): a baseline's runner gets the mechanism, not how it was read.
_READ: dict[int, tuple[object, ImportOptions]] = {}


def is_model_file(name) -> bool:
    """Whether ``name`` (a path, or a mechanism's ``source``) is a user's MJCF model."""
    return bool(name) and str(name).lower().endswith(".xml")


def is_own_file(name) -> bool:
    """Whether ``name`` is a user's engine model the pytest plugin runs (MJCF or URDF)."""
    return isinstance(name, (str, os.PathLike)) and \
        os.fspath(name).lower().endswith((".xml", ".urdf"))


def import_own(path: str, opts: ImportOptions = ImportOptions(), duration: float | None = None):
    """The model imported (:func:`sim_models.own.import_model`), its options remembered
    for the runner."""
    from sim_models.own import DEFAULT_DURATION, import_model
    imp = import_model(str(path), opts.driver, opts.keyframe,
                       DEFAULT_DURATION if duration is None else duration, tuple(opts.closes))
    _READ[id(imp.mechanism)] = (imp.mechanism, opts)
    return imp


def options_of(mech) -> ImportOptions:
    """How ``mech`` was read, if here; else its driver (a mechanism loaded otherwise)."""
    kept = _READ.get(id(mech))
    if kept is not None and kept[0] is mech:
        return kept[1]
    return ImportOptions(driver=mech.driver.joint)


def own_content(path: str, driver: str | None = None, keyframe: str | None = None,
                recorded: dict | None = None) -> tuple[object, dict]:
    """``(Mechanism, content)``: the model imported and its identity's content; the
    import options from ``recorded`` (a baseline's content) when given."""
    from sim_models.own.mujoco_own import option_items
    if recorded is not None:
        driver, keyframe = (recorded_options(recorded).get(k) for k in ("driver", "keyframe"))
    imp = import_own(path, ImportOptions(driver, keyframe))
    flat = mid.content(imp.mechanism)
    flat.update({f"mjcf.{k}": v for k, v in option_items(imp.compiled.model).items()})
    flat.update({f"own.{k}": v for k, v in (("driver", driver), ("keyframe", keyframe))
                 if v is not None})
    return imp.mechanism, flat


def recorded_options(content: dict | None) -> dict:
    """The import options (``driver``, ``keyframe``) a baseline's model content holds."""
    c = content or {}
    return {k: c[f"own.{k}"] for k in ("driver", "keyframe") if f"own.{k}" in c}


def own_source(model: str, base_dir: Path, driver: str | None = None,
               keyframe: str | None = None):
    """``(ModelSource, Mechanism)`` of a user's MJCF file (a path relative to
    ``base_dir`` in the baseline)."""
    from reports.regression.baseline import ModelSource
    p = Path(model).resolve()
    mech, flat = own_content(str(p), driver, keyframe)
    rel = Path(os.path.relpath(p, base_dir)).as_posix()
    return ModelSource("file", rel, mid.digest_of_content(flat), flat), mech


def check_engine(path, engine: str, free: bool = False) -> None:
    """MuJoCo runs any user's model; PyBullet a URDF, driven (its free run is not built)."""
    if engine == "pybullet" and str(path).lower().endswith(".urdf") and not free:
        return
    if engine not in OWN_ENGINES:
        raise EngineRefusal(f"{path}: a user's engine model runs in MuJoCo only "
                            "(engine 'mujoco'; a URDF's driven runs also in 'pybullet')")


def run_key(path, opts: ImportOptions) -> tuple:
    """A session cache key of a user's file as it is now (its bytes) read with ``opts``."""
    data = Path(path).read_bytes() if Path(path).is_file() else b""
    return (str(Path(path).resolve()), hashlib.sha256(data).hexdigest(), repr(opts))


def check_request(request: dict):
    """The run request through the command line's ranges (:class:`SettingsError` naming
    the key and value): a free one's duration and samples, a driven one's
    :class:`sim_models.runs.engine_run.RunRequest`, which is returned."""
    from sim_models.runs.engine_run import RunRequest
    if is_free(request):
        bad = free_request_problem(request)
        if bad:
            key, value, problem = bad
            raise SettingsError(f"free run {key}={value!r}: {problem}", key, value, problem)
        return None
    return RunRequest(request["revolutions"], request["samples"], request["max_violation"],
                      request["max_speed_error"])


def prescribed_own(path, opts: ImportOptions, request: dict, engine: str = "mujoco"):
    """MuJoCo (or PyBullet, on a URDF) on the file, driven as ``request`` (a baseline's
    prescribed request) asks: ``(EngineRun, judged comparisons)``."""
    from sim_models.own.mujoco_own import run_prescribed
    from sim_models.own.pybullet_own import run_prescribed_pybullet
    check_engine(path, engine)
    req = check_request(request)
    imp = import_own(path, opts)
    tree, r = (run_prescribed_pybullet(imp, req) if engine == "pybullet"
               else run_prescribed(imp, req))
    return r, Verdict(tree, r, tuple(compare_run(r))).judged()


def free_own(path, opts: ImportOptions, duration: float, samples: int):
    """MuJoCo on the file released from its own state for ``duration`` s, read at
    ``samples`` times: ``(FreeEngineRun, FreeVerdict)``.  ``duration`` and ``samples``
    in ``xval simulate``'s ranges; a model that would not move is refused."""
    from analytic.free_motion import simulate
    from reports.comparison.free_compare import compare_free, reference_samples
    from sim_models.own.mujoco_own_free import run_free_own
    from sim_models.runs.free_run import FreeRequest
    check_request({"mode": "free", "duration": duration, "samples": samples})
    imp = import_own(path, opts, float(duration))
    traj = simulate(imp.mechanism)
    refuse_still(imp, traj, samples)
    request = FreeRequest(duration=traj.duration, samples=int(samples) - 1)
    run = run_free_own(imp, request, traj)
    return run, compare_free(run, traj, reference_samples(traj, request.times()))


def refuse_still(imp, traj, samples: int) -> None:
    """An :class:`EngineRefusal` when the released model does not move (nothing to
    judge a run against)."""
    smp = traj.at(np.linspace(0.0, traj.duration, int(samples)), forces=False)
    if np.ptp(smp.x) <= STILL:
        raise EngineRefusal(f"{imp.compiled.path}: released from {imp.compiled.config} the "
                            "model does not move (at rest, no in-plane gravity, spring or "
                            "motor); give a keyframe with a velocity (--keyframe NAME)")


def run_and_compare_own(mech, engine: str, settings, request: dict):
    """MuJoCo on the user's file (``mech.source``) as ``request`` asks, driven or
    released (``settings`` unused: the model runs with its own options):
    ``(run, judged comparisons)``."""
    check_engine(mech.source, engine, is_free(request))
    opts = options_of(mech)
    if is_free(request):
        run, v = free_own(mech.source, opts, request["duration"], request["samples"])
        return run, free_comparisons(v)
    return prescribed_own(mech.source, opts, request, engine)


def free_comparisons(v) -> list:
    """A free verdict's judged quantities as a baseline records them (the loop drift only
    where the mechanism has a loop)."""
    return [c for c in v.judged if v.has_loop or c is not v.loop]


__all__ = ["ImportOptions", "OWN_ENGINES", "STILL", "check_engine", "check_request",
           "free_comparisons", "free_own", "import_own", "is_model_file", "is_own_file",
           "options_of", "own_content", "own_source", "prescribed_own", "recorded_options",
           "refuse_still", "run_and_compare_own", "run_key"]
