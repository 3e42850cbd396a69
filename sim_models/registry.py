"""The engine registry: name -> the module holding its :class:`~sim_models.engine_base.Session`.

Engines are found by name, never by ``if``/``elif`` on strings::

    from sim_models.registry import engine_names, get_engine, make_settings
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

from .engine_base import EngineSettings, Session
from .tree import SimModelError


@dataclass(frozen=True)
class EngineEntry:
    """Where an engine lives: ``module`` (dotted path) and its session class's name."""

    name: str
    module: str
    session: str
    description: str = ""


#: The built-in engines, in the order ``--engine all`` runs them.
BUILTIN: tuple[EngineEntry, ...] = (
    EngineEntry("mujoco", "sim_models.mujoco_engine", "MujocoSession",
                "MuJoCo via MjSpec: soft loop equalities, armature drive"),
    EngineEntry("pybullet", "sim_models.pybullet_engine", "PybulletSession",
                "PyBullet via URDF: point-to-point loop constraints, velocity motor"),
    EngineEntry("exudyn", "sim_models.exudyn_engine", "ExudynSession",
                "Exudyn: index-3 DAE, reactions from the Lagrange multipliers"),
)

_REGISTRY: dict[str, EngineEntry] = {e.name: e for e in BUILTIN}


class UnknownEngineError(SimModelError):
    """An engine name that is not registered (the message lists the known ones)."""


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


def register_engine(name: str, module: str, session: str, description: str = "") -> None:
    """Register (or replace) an engine: ``module`` must define the class ``session``."""
    _REGISTRY[name] = EngineEntry(name, module, session, description)


def engine_names() -> tuple[str, ...]:
    """Registered engine names, built-in order first."""
    return tuple(_REGISTRY)


def available_engines() -> tuple[str, ...]:
    """Registered engines whose module is present (found without importing it or its
    engine library), in registry order: what ``--engine all`` runs."""
    return tuple(n for n, e in _REGISTRY.items() if importlib.util.find_spec(e.module))


def get_engine(name: str) -> Engine:
    """The engine called ``name`` (imports its module; a missing engine library raises
    :class:`~sim_models.tree.SimModelError` from the module's own import check)."""
    try:
        entry = _REGISTRY[str(name).lower()]
    except KeyError:
        raise UnknownEngineError(f"unknown engine {name!r}; engines: "
                                 f"{', '.join(engine_names())}") from None
    mod = importlib.import_module(entry.module)
    cls = getattr(mod, entry.session)
    return Engine(entry, cls)


def make_settings(name: str, overrides: Mapping[str, object] | None = None) -> EngineSettings:
    """Settings of engine ``name``: its recommended defaults with ``overrides``."""
    return get_engine(name).settings(overrides)


def split_overrides(pairs, engines) -> dict[str, dict[str, str]]:
    """``KEY=VALUE`` / ``ENGINE.KEY=VALUE`` strings (``--set``) -> per-engine overrides.

    A plain key goes to every engine in ``engines`` that has that setting and must be
    known to at least one; ``ENGINE.KEY`` goes to that engine only.  Raises
    :class:`~sim_models.engine_base.SettingsError` naming the bad item."""
    from .engine_base import SettingsError
    out: dict[str, dict[str, str]] = {e: {} for e in engines}
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
            fields = get_engine(e).settings_class.field_types()
            if key in fields:
                out[e][key] = value
                hits.append(e)
        if not hits:
            known = sorted({k for e in out for k in get_engine(e).settings_class.field_types()})
            raise SettingsError(f"--set {item!r}: no engine here has a setting {key!r}; "
                                f"settings: {', '.join(known)}")
    return out


__all__ = ["BUILTIN", "Engine", "EngineEntry", "UnknownEngineError", "available_engines",
           "engine_names",
           "get_engine", "make_settings", "register_engine", "split_overrides"]
