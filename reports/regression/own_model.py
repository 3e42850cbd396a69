"""Baselines of a user's own MJCF model (``xval baseline record MODEL.xml --engine
mujoco``): its identity is the parsed model, the imported description's content with the
compiled model's options (:func:`sim_models.own.mujoco_own.option_items`: timestep,
integrator, solver, each constraint's ``solref``/``solimp``), so a comment or a
reformatted file is no change and a moved anchor or a new ``solref`` is, named; its runs
are MuJoCo's on the file as it is (:func:`sim_models.own.mujoco_own.run_prescribed`).
The reference configuration is the model's ``qpos0`` and the driver the description's."""

from __future__ import annotations

import os
from pathlib import Path

from reports.comparison.compare import compare_run
from reports.comparison.runs import Verdict
from reports.regression import model_identity as mid
from sim_models.engine_base import EngineRefusal


def is_model_file(name) -> bool:
    """Whether ``name`` (a path, or a mechanism's ``source``) is a user's MJCF model."""
    return bool(name) and str(name).lower().endswith(".xml")


def own_content(path: str, driver: str | None = None) -> tuple[object, dict]:
    """``(Mechanism, content)``: the model imported and its identity's content."""
    from sim_models.own import import_model
    from sim_models.own.mujoco_own import option_items
    imp = import_model(path, driver)
    flat = mid.content(imp.mechanism)
    flat.update({f"mjcf.{k}": v for k, v in option_items(imp.compiled.model).items()})
    return imp.mechanism, flat


def own_source(model: str, base_dir: Path):
    """``(ModelSource, Mechanism)`` of a user's MJCF file (a path relative to
    ``base_dir`` in the baseline)."""
    from reports.regression.baseline import ModelSource
    p = Path(model).resolve()
    mech, flat = own_content(str(p))
    rel = Path(os.path.relpath(p, base_dir)).as_posix()
    return ModelSource("file", rel, mid.digest_of_content(flat), flat), mech


def run_and_compare_own(mech, engine: str, settings, request: dict):
    """MuJoCo on the user's file (``mech.source``), driven as ``request`` asks:
    ``(EngineRun, judged comparisons)``."""
    from sim_models.engine_run import RunRequest
    from sim_models.own import import_model
    from sim_models.own.mujoco_own import run_prescribed
    if engine != "mujoco":
        raise EngineRefusal(f"{mech.source}: a user's MJCF model runs in MuJoCo only "
                            "(--engine mujoco)")
    if request.get("mode") != "run":
        raise EngineRefusal(f"{mech.source}: a baseline of a user's model records "
                            "prescribed runs only (no --free yet)")
    imp = import_model(mech.source, mech.driver.joint)
    req = RunRequest(request["revolutions"], request["samples"], request["max_violation"],
                     request["max_speed_error"])
    tree, r = run_prescribed(imp, req)
    return r, Verdict(tree, r, tuple(compare_run(r))).judged()
