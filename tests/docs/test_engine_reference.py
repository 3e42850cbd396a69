"""The generated engine-settings reference (docs/_ext/xval_engines.py, the page
docs/reference/engines.md) lists every registered engine, prescribed and free, with
every field of its settings class, its recommended default and the range that
``--set`` checks: read here from the registry and the classes, independently."""

from __future__ import annotations

import dataclasses
import importlib.util
import sys
from pathlib import Path

from sim_models.engines import ranges
from sim_models.engines.registry import BUILTIN
from sim_models.runs.free import FREE_SESSIONS, free_session_class

EXT = Path(__file__).resolve().parents[2] / "docs" / "_ext" / "xval_engines.py"


def _extension():
    spec = importlib.util.spec_from_file_location("xval_engines_under_test", EXT)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def test_every_engine_is_listed_with_both_settings_classes():
    listed = {name: (driven, free) for name, _, driven, free, _ in
              _extension().engine_settings()}
    assert list(listed) == [e.name for e in BUILTIN]
    for name in FREE_SESSIONS:
        assert listed[name][1] is free_session_class(name).settings_class


def test_every_field_with_its_default_and_range():
    ext = _extension()
    for _, _, driven, free, _ in ext.engine_settings():
        for cls in (driven, free):
            rows = {r[0]: r for r in ext.settings_rows(cls)}
            assert list(rows) == [f.name for f in dataclasses.fields(cls)]
            for f in dataclasses.fields(cls):
                rng = cls.RANGES[f.name]
                parts = rng if isinstance(rng, tuple) else (rng,)
                for part in parts:  # each component's accepted range, as --set says it
                    assert part.text() in rows[f.name][2], (cls.__name__, f.name)
            timestep = rows["timestep"]
            assert float(timestep[1]) == cls().timestep
            assert ranges.TIMESTEP.text() in timestep[2]
