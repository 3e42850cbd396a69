"""Settings files: engine settings written by ``xval tune --out`` and read by every door
that runs engines (``xval compare``, ``xval simulate --engine``, ``xval baseline
record`` with ``--settings FILE``, and the pytest fixtures' ``settings=`` argument).

A settings file is JSON::

    {"xval_settings": 1, "mode": "run",          # "run" (prescribed) or "free"
     "engines": {"mujoco": {"timestep": 0.0005, "solref": [-10000.0, -200.0], ...}},
     "tuned": {...}}                             # optional: what xval tune measured

Each engine's fields pass its settings class's ranges (:mod:`sim_models.engines.ranges`, the
same check as ``--set``), so a bad file is one line naming the file, the engine, the key
and the accepted range (status 2 at the command line).  A field left out takes the
recommended value.  ``mode`` keeps a free-motion file (MuJoCo's free settings have
no armature; PyBullet's a ``first_step``) from a prescribed run and back.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from analytic.errors import LinkageError
from sim_models.engines.settings import SettingsError

FORMAT_KEY = "xval_settings"
FORMAT_VERSION = 1
MODES = ("run", "free")


class SettingsFileError(LinkageError):
    """A settings file that cannot be read or holds a bad value (one line: the file, the
    engine and key, why)."""


@dataclass(frozen=True)
class SettingsFile:
    """A read settings file: ``path``, ``mode`` and each engine's checked overrides
    (typed values; tuples for settings of several numbers)."""

    path: str
    mode: str
    engines: Mapping[str, dict]

    def overrides(self, engine: str) -> dict:
        return dict(self.engines.get(engine, {}))


def settings_class(engine: str, mode: str):
    """The settings class of ``engine`` for ``mode`` (``run``: the registry's; ``free``:
    the free-motion session's)."""
    if mode == "free":
        from sim_models.runs.free import free_session_class
        return free_session_class(engine).settings_class
    from sim_models.engines.registry import get_engine
    return get_engine(engine).settings_class


def _json_value(v):
    return list(v) if isinstance(v, tuple) else v


def settings_document(per_engine: Mapping[str, object], mode: str,
                      tuned: Mapping | None = None) -> dict:
    """The JSON object of a settings file: ``per_engine`` maps an engine name to its
    settings object (every field written, so the file does not depend on later changes
    of the recommended values)."""
    if mode not in MODES:
        raise ValueError(f"mode {mode!r}: use one of {MODES}")
    doc = {FORMAT_KEY: FORMAT_VERSION, "mode": mode,
           "engines": {e: {k: _json_value(v) for k, v in s.as_dict().items()}
                       for e, s in per_engine.items()}}
    if tuned:
        doc["tuned"] = dict(tuned)
    return doc


def write_settings_file(path: str | Path, per_engine: Mapping[str, object], mode: str,
                        tuned: Mapping | None = None) -> Path:
    """Write a settings file (see :func:`settings_document`); returns the path."""
    p = Path(path)
    p.write_text(json.dumps(settings_document(per_engine, mode, tuned), indent=1,
                            allow_nan=False) + "\n")
    return p


def read_settings_file(path: str | Path, mode: str | None = None) -> SettingsFile:
    """Read and check a settings file; ``mode`` (``run``/``free``): the runs it is for
    (a file of the other mode is refused).  Raises :class:`SettingsFileError`."""
    where = f"settings file {str(path)!r}"
    try:
        doc = json.loads(Path(path).read_text(), parse_constant=_no_constant)
    except FileNotFoundError:
        raise SettingsFileError(f"{where}: no such file") from None
    except IsADirectoryError:
        raise SettingsFileError(f"{where}: is a folder, not a file") from None
    except (OSError, UnicodeDecodeError) as e:
        raise SettingsFileError(f"{where}: cannot be read: {e}") from None
    except ValueError as e:
        raise SettingsFileError(f"{where}: not valid JSON: {e}") from None
    if not isinstance(doc, dict) or doc.get(FORMAT_KEY) != FORMAT_VERSION:
        raise SettingsFileError(f"{where}: not an xval settings file (needs "
                                f"\"{FORMAT_KEY}\": {FORMAT_VERSION}; xval tune --out "
                                "writes one)")
    fmode = doc.get("mode")
    if fmode not in MODES:
        raise SettingsFileError(f"{where}: key 'mode' is {fmode!r}: use one of "
                                f"{', '.join(MODES)}")
    if mode is not None and fmode != mode:
        use = "xval simulate --engine, baseline record --free" if fmode == "free" else \
            "xval compare, baseline record"
        raise SettingsFileError(f"{where}: holds {fmode!r} settings ({use}), not "
                                f"{mode!r} settings")
    engines = doc.get("engines")
    if not isinstance(engines, dict) or not engines:
        raise SettingsFileError(f"{where}: key 'engines' must map engine names to their "
                                "settings")
    return SettingsFile(str(path), fmode, {e: _checked(where, e, fields, fmode)
                                            for e, fields in engines.items()})


def _no_constant(name: str):
    raise ValueError(f"{name} is not a number JSON allows")


def _checked(where: str, engine: str, fields, mode: str) -> dict:
    """``fields`` of ``engine`` through its settings class (ranges, types)."""
    from sim_models.builders.tree import SimModelError
    if not isinstance(fields, dict):
        raise SettingsFileError(f"{where}: engine {engine!r}: its settings must be an "
                                "object of key: value")
    try:
        cls = settings_class(engine, mode)
    except SimModelError as e:
        raise SettingsFileError(f"{where}: {e}") from None
    bad = [k for k, v in fields.items() if isinstance(v, float) and not math.isfinite(v)]
    if bad:
        raise SettingsFileError(f"{where}: engine {engine!r} key {bad[0]!r}: not a finite "
                                "number")
    try:
        s = cls.from_overrides({k: tuple(v) if isinstance(v, list) else v
                                for k, v in fields.items()}, engine)
    except SettingsError as e:
        key = f" key {e.key!r}" if e.key else ""
        raise SettingsFileError(f"{where}: engine {engine!r}{key}: {e.problem}") from None
    return {k: getattr(s, k) for k in fields}


def apply_settings_file(settings: dict, sfile: SettingsFile | None,
                        given: Mapping[str, set[str]] | None = None) -> dict:
    """``settings`` (engine -> settings object, from the flags and ``--set``) with the
    file's values applied to the engines it names; ``given``: engine -> the keys the
    flags and ``--set`` gave, which the file may not also give (no silent precedence).
    Raises :class:`SettingsFileError`."""
    if sfile is None:
        return settings
    out = dict(settings)
    for eng, s in settings.items():
        over = sfile.overrides(eng)
        clash = sorted(set(over) & set((given or {}).get(eng, ())))
        if clash:
            raise SettingsFileError(f"settings file {sfile.path!r} and an option both set "
                                    f"{eng}'s {clash[0]}; give one")
        if over:
            out[eng] = s.with_overrides(over, eng)
    return out


def given_keys(engines, pairs, options: Mapping[str, tuple[str, object]] | None,
               classes=None) -> dict[str, set[str]]:
    """Engine -> the setting keys the ``--set`` items ``pairs`` and the option flags
    ``options`` (``{"--timestep": ("timestep", value or None)}``) give."""
    from sim_models.engines.registry import split_overrides
    per = split_overrides(pairs, engines, classes)
    out = {e: set(per.get(e, {})) for e in engines}
    for _flag, (key, value) in (options or {}).items():
        if value is not None:
            for e in engines:
                out[e].add(key)
    return out


__all__ = ["FORMAT_KEY", "FORMAT_VERSION", "SettingsFile", "SettingsFileError",
           "apply_settings_file", "given_keys", "read_settings_file", "settings_class",
           "settings_document", "write_settings_file"]
