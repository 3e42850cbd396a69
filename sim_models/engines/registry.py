"""The engine registry: name -> the module holding its
:class:`~sim_models.engines.protocol.Session`.

Engines are found by name, never by ``if``/``elif`` on strings::

    from sim_models.engines.registry import engine_names, get_engine, make_settings
    engine_names()                                    # ('mujoco', 'pybullet', ...)
    eng = get_engine("mujoco")                        # an Engine: session and settings classes
    s = make_settings("mujoco", {"integrator": "Euler", "timestep": "1e-4"})

Modules are imported only when an engine is asked for (``xval solve`` imports none).
A new engine is one module plus one :class:`EngineEntry` line in :data:`BUILTIN`
(or a call to :func:`register_engine` from outside the package).
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Mapping
from dataclasses import dataclass

from ..builders.tree import SimModelError
from .protocol import EngineSettings, Session


@dataclass(frozen=True)
class EngineEntry:
    """Where an engine lives: ``module`` (dotted path) and its session class's name."""

    name: str
    module: str
    session: str
    description: str = ""
    #: the engine library's top-level module when it is an optional extra ("" when it is
    #: a dependency): found without importing it (:func:`missing_library`)
    requires: str = ""
    #: how to install that library (the message of an explicit ``--engine NAME``)
    install: str = ""


#: The built-in engines, in the order ``--engine all`` runs them.
BUILTIN: tuple[EngineEntry, ...] = (
    EngineEntry("mujoco", "sim_models.engines.mujoco.driven", "MujocoSession",
                "MuJoCo via MjSpec: soft loop equalities, armature drive"),
    EngineEntry("pybullet", "sim_models.engines.pybullet.driven", "PybulletSession",
                "PyBullet via URDF: point-to-point loop constraints, velocity motor"),
    EngineEntry("exudyn", "sim_models.engines.exudyn.driven", "ExudynSession",
                "Exudyn: index-3 DAE, reactions from the Lagrange multipliers"),
    EngineEntry("pinocchio", "sim_models.engines.pinocchio.driven", "PinocchioSession",
                "Pinocchio: constraintDynamics, loops closed by rigid point constraints",
                "pinocchio", "pip install 'linkage-xval[pinocchio]'"),
    EngineEntry("mujoco_warp", "sim_models.engines.mujoco_warp.driven", "MujocoWarpSession",
                "MuJoCo Warp: the MuJoCo model in float32 Warp kernels (CPU or GPU)",
                "mujoco_warp", "pip install 'linkage-xval[warp]'"),
)

_REGISTRY: dict[str, EngineEntry] = {e.name: e for e in BUILTIN}


class UnknownEngineError(SimModelError):
    """An engine name that is not registered (the message lists the known ones)."""


class EngineUnavailableError(SimModelError, ImportError):
    """A registered engine whose optional library is not installed (the message says how
    to install it).  Also an ``ImportError``, as a missing library always was."""


def missing_library(name: str) -> str | None:
    """Why engine ``name`` cannot run here (its optional library is not installed: one
    line with the install command), or None when it can.  Nothing is imported."""
    e = _REGISTRY[name]
    if e.requires and importlib.util.find_spec(e.requires) is None:
        how = f": {e.install}" if e.install else ""
        return f"engine {name!r} needs the {e.requires!r} package, not installed{how}"
    return None


def skipped_engines() -> dict[str, str]:
    """Registered engines ``--engine all`` skips, each with its one-line reason."""
    return {n: why for n in _REGISTRY if (why := missing_library(n)) is not None}


@dataclass(frozen=True)
class Engine:
    """A resolved engine: its entry, session class and settings class."""

    entry: EngineEntry
    session_class: type[Session]

    @property
    def name(self) -> str:
        return self.entry.name

    @property
    def settings_class(self) -> type[EngineSettings]:
        return self.session_class.settings_class

    def settings(self, overrides: Mapping[str, object] | None = None) -> EngineSettings:
        """The recommended settings with ``overrides`` (typed or ``key=value`` strings)."""
        return self.settings_class.from_overrides(overrides, self.name)


def register_engine(name: str, module: str, session: str, description: str = "",
                    requires: str = "", install: str = "") -> None:
    """Register (or replace) an engine: ``module`` must define the class ``session``;
    ``requires`` names an optional library's module (``install``: how to get it)."""
    _REGISTRY[name] = EngineEntry(name, module, session, description, requires, install)


def engine_names() -> tuple[str, ...]:
    """Registered engine names, built-in order first."""
    return tuple(_REGISTRY)


def available_engines() -> tuple[str, ...]:
    """Registered engines whose module is present and whose optional library is
    installed (found without importing either), in registry order: what ``--engine all``
    runs (:func:`skipped_engines` says why the others are left out)."""
    return tuple(n for n, e in _REGISTRY.items()
                 if importlib.util.find_spec(e.module) and missing_library(n) is None)


def get_engine(name: str) -> Engine:
    """The engine called ``name`` (imports its module; a missing optional library raises
    :class:`EngineUnavailableError` saying how to install it, any other missing engine
    library :class:`~sim_models.builders.tree.SimModelError` from the module's own import
    check)."""
    try:
        entry = _REGISTRY[str(name).lower()]
    except KeyError:
        raise UnknownEngineError(f"unknown engine {name!r}; engines: "
                                 f"{', '.join(engine_names())}") from None
    why = missing_library(entry.name)
    if why is not None:
        raise EngineUnavailableError(why)
    mod = importlib.import_module(entry.module)
    cls = getattr(mod, entry.session)
    return Engine(entry, cls)


def make_settings(name: str, overrides: Mapping[str, object] | None = None) -> EngineSettings:
    """Settings of engine ``name``: its recommended defaults with ``overrides``."""
    return get_engine(name).settings(overrides)


def split_overrides(pairs, engines, classes=None) -> dict[str, dict[str, str]]:
    """``KEY=VALUE`` / ``ENGINE.KEY=VALUE`` strings (``--set``) -> per-engine overrides.

    A plain key goes to every engine in ``engines`` that has that setting and must be
    known to at least one; ``ENGINE.KEY`` goes to that engine only, and wins over a plain
    ``KEY`` whatever their order.  The same key given twice with different values is
    refused.  ``classes``: engine -> settings class (default the registered ones; the
    free-motion runs pass theirs).  Raises :class:`~sim_models.engines.protocol.SettingsError`
    naming the bad item."""
    return _split(pairs, engines, classes)[0]


def _split(pairs, engines, classes=None) -> tuple[dict[str, dict[str, str]],
                                                   dict[tuple[str, str], str]]:
    """:func:`split_overrides` and, per ``(engine, key)``, the ``--set`` item it came from
    (``classes``: engine -> settings class, default the registered ones)."""
    from .protocol import SettingsError
    classes = classes or {e: get_engine(e).settings_class for e in engines}
    out: dict[str, dict[str, str]] = {e: {} for e in engines}
    origin: dict[tuple[str, str], str] = {}
    for item in pairs or ():
        if "=" not in item:
            raise SettingsError(f"--set {item!r}: use KEY=VALUE or ENGINE.KEY=VALUE")
        key, value = item.split("=", 1)
        key = key.strip()
        target = None
        if "." in key:
            target, key = key.split(".", 1)
            if target not in out:
                raise SettingsError(f"--set {item!r}: engine {target!r} is not run here "
                                    f"(engines: {', '.join(out)})")
        hits = []
        for e in ([target] if target else list(out)):
            fields = classes[e].field_types()
            if key not in fields:
                continue
            hits.append(e)
            before = origin.get((e, key))
            if before is not None:
                specific_before = "." in before.split("=", 1)[0]
                if specific_before == bool(target) and out[e][key] != value:
                    raise SettingsError(f"--set {before} and --set {item} both set {e}'s "
                                        f"{key}; give one")
                if specific_before and not target:
                    continue  # ENGINE.KEY wins over a plain KEY
            out[e][key] = value
            origin[(e, key)] = item
        if not hits:
            known = sorted({k for e in out for k in classes[e].field_types()})
            raise SettingsError(f"--set {item!r}: no engine here has a setting {key!r}; "
                                f"settings: {', '.join(known)}")
    return out, origin


def settings_from_options(engines, pairs=(), options: Mapping[str, tuple[str, object]]
                          | None = None, classes: Mapping[str, type[EngineSettings]]
                          | None = None) -> dict[str, EngineSettings]:
    """Each engine's settings from the command line: its recommended defaults, the
    option flags ``options`` (``{"--timestep": ("timestep", 1e-4)}``; a ``None`` value
    is an option not given; applied where the engine has the field) and the ``--set``
    items ``pairs``.  One door for every source: each value passes the settings
    class's ranges (:mod:`sim_models.engines.ranges`), and the error names what the user typed
    (``--set mujoco.iterations=-5: ...``, ``argument --timestep: ...``).  A flag and a
    ``--set`` item for the same setting are refused (no silent precedence).
    ``classes``: engine -> settings class where it is not the registered one (the
    free-motion settings, :func:`sim_models.runs.free.free_session_class`)."""
    from .protocol import SettingsError
    classes = dict(classes or {e: get_engine(e).settings_class for e in engines})
    per, origin = _split(pairs, engines, classes)
    for flag, (key, value) in (options or {}).items():
        if value is not None and not any(key in classes[e].field_types()
                                         for e in engines):
            raise SettingsError(f"argument {flag}: no engine run here has a setting {key!r} "
                                f"(engines: {', '.join(engines)})")
    out = {}
    for e in engines:
        cls = classes[e]
        fields = cls.field_types()
        over: dict[str, object] = {}
        said: dict[str, str] = {}
        for flag, (key, value) in (options or {}).items():
            if value is None or key not in fields:
                continue
            if (e, key) in origin:
                raise SettingsError(f"{flag} {value} and --set {origin[(e, key)]} both set "
                                    f"{e}'s {key}; give one")
            over[key] = value
            said[key] = f"argument {flag}"
        over.update(per.get(e, {}))
        said.update({k: f"--set {origin[(e, k)]}" for k in per.get(e, {})})
        try:
            out[e] = cls.from_overrides(over, e)
        except SettingsError as err:
            if err.key in said:
                raise SettingsError(f"{said[err.key]}: {err.problem}", err.key, err.value,
                                    err.problem) from None
            raise
    return out


__all__ = ["BUILTIN", "Engine", "EngineEntry", "EngineUnavailableError", "UnknownEngineError",
           "available_engines", "engine_names", "missing_library", "skipped_engines",
           "get_engine", "make_settings", "register_engine", "settings_from_options",
           "split_overrides"]
