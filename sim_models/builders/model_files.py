"""The generated model files of the built-in cases (``sim_models/models/``).

For each case ``<case>.xml`` (MJCF written by ``MjSpec.to_xml`` from
:func:`sim_models.builders.viewer_model.viewer_spec`:
:func:`sim_models.builders.mjcf.build_mjcf` plus the drive as an actuator and the assembled
state as a keyframe, so a viewer shows it turning), ``<case>.urdf`` and ``<case>.closures.json``
(the loop-closing point-to-point constraints PyBullet needs; pivots in the links'
centre-of-mass frames).  The files are generated, never edited: ``xval models``
rewrites them and a test fails when the committed ones are stale.

The MJCF carries the recommended solver settings except ``invweight_scale``, which
scales the compiled model's ``body_invweight0``/``dof_invweight0`` and cannot be
expressed in MJCF: a model opened from the file (e.g. in MuJoCo's viewer) has stock,
softer loop constraints.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

from analytic import Mechanism, case_names, load_case
from analytic.errors import OutputError

from .mjcf import MujocoSettings
from .urdf import build_urdf
from .viewer_model import viewer_xml

MODELS_DIR = Path(__file__).parents[1] / "models"


def model_texts(case: str) -> dict[str, str]:
    """File name -> text of the generated models of one built-in case or TOML file (the
    files of a TOML file are named after it).  The MJCF is the viewer model
    (:func:`sim_models.builders.viewer_model.viewer_xml`): the harness's model with its drive as
    an actuator and the assembled state as keyframe ``assembled``."""
    mech = load_case(case)
    name = case if case in case_names() else Path(case).stem
    return mechanism_model_texts(mech, name)


def mechanism_model_texts(mech: Mechanism, name: str) -> dict[str, str]:
    """File name -> text of the generated models of ``mech``, files named ``name.*``."""
    xml = viewer_xml(mech, MujocoSettings())
    urdf, closures = build_urdf(mech)
    return {f"{name}.xml": xml, f"{name}.urdf": urdf,
            f"{name}.closures.json": json.dumps([asdict(c) for c in closures], indent=2) + "\n"}


def write_models(out: str | Path = MODELS_DIR, cases: list[str] | None = None) -> list[Path]:
    """Write the model files of ``cases`` (built-in names or TOML files; default every
    built-in case) into ``out``; returns the paths."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for case in cases or case_names():
        texts = model_texts(case)
        for name in texts:
            if Path(case).is_file() and (out / name).exists() and \
                    (out / name).samefile(case):
                raise OutputError(f"--out {str(out)!r}: the model file {name!r} would "
                                  f"overwrite the case file {case!r}; give another folder")
        for name, text in texts.items():
            p = out / name
            p.write_text(text)
            paths.append(p)
    return paths
