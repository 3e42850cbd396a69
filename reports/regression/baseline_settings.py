"""A baseline run's engine settings: written in full (:func:`settings_json`), checked
when a file is read (:func:`check_settings`: the engine's class, every field present,
typed and in range, as ``--set`` checks them), rebuilt for a check
(:func:`settings_from_json`), and overridden by ``--set`` (:func:`overrides_for`,
:func:`override_classes`).  A free run's settings are its engine's free-motion class
(:mod:`reports.regression.baseline_free`).
"""

from __future__ import annotations

from analytic.errors import LinkageError
from reports.regression.baseline import Baseline, BaselineError, RunRecord, json_value
from reports.regression.baseline_free import free_settings_class, is_free
from sim_models.builders.tree import SimModelError
from sim_models.engines.registry import get_engine, split_overrides
from sim_models.engines.settings import SettingsError


def settings_json(engine: str, settings) -> dict:
    """The settings object in full: engine name, class and every field."""
    fields = {k: list(v) if isinstance(v, tuple) else v for k, v in settings.as_dict().items()}
    return {"engine": engine, "class": type(settings).__name__, "fields": fields}


def settings_line(engine: str, settings) -> str:
    """Every field of a settings object as ``key=value``, after the engine's name."""
    return f"{engine}: " + " ".join(f"{k}={fmt_value(v, True)}"
                                    for k, v in settings.as_dict().items())


def fmt_value(v, paren: bool = False) -> str:
    """A setting as typed after ``--set KEY=`` (floats in %g, tuples comma-separated;
    ``paren``: tuples in parentheses, for reading)."""
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, (tuple, list)):
        inner = ",".join(fmt_value(x) for x in v)
        return f"({inner})" if paren else inner
    return str(v)


def settings_from_json(rec: RunRecord, where: str, overrides: dict | None = None):
    """The settings object a record was run with (:meth:`EngineSettings.from_overrides`),
    with ``overrides`` ({field: value} of this engine, ``--set``) over the recorded
    fields; raises :class:`BaselineError` when the engine no longer accepts a recorded
    field (a bad override is the :class:`SettingsError` of ``--set``: status 2)."""
    if is_free(rec.request):
        cls, name = free_settings_class(rec.engine), rec.engine
    else:
        eng = get_engine(rec.engine)
        cls, name = eng.settings_class, eng.name
    try:
        s = cls.from_overrides(rec.settings["fields"], name)
    except SettingsError as e:
        raise BaselineError(f"{where}: {rec.label}: the recorded settings cannot be "
                            f"rebuilt: {e}") from None
    if overrides:  # a key only the other mode's class has is not this run's
        types = cls.field_types()
        mine = {k: v for k, v in overrides.items() if k in types}
        s = cls.from_overrides({**s.as_dict(), **mine}, name)
    return s


def overrides_for(pairs, engines, classes=None) -> dict:
    """``KEY=VALUE`` / ``ENGINE.KEY=VALUE`` strings (as ``xval compare --set`` takes them)
    as ``{engine: {field: value}}`` for those of ``engines`` that have a field set
    (:func:`sim_models.engines.registry.split_overrides`, ``classes`` its settings classes;
    :class:`SettingsError`: status 2)."""
    if not pairs:
        return {}
    return {e: v for e, v in split_overrides(list(pairs), list(dict.fromkeys(engines)),
                                             classes).items() if v}


def override_classes(baseline: Baseline) -> dict:
    """Per engine of ``baseline``, the settings class ``--set`` is checked against: the
    free-motion one when every run of that engine is a free run, else the prescribed one
    (a key of the other class only is then applied where the class has it)."""
    out = {}
    for e in dict.fromkeys(r.engine for r in baseline.runs):
        free = all(r.free for r in baseline.runs if r.engine == e)
        try:
            out[e] = free_settings_class(e) if free else get_engine(e).settings_class
        except (LinkageError, ImportError):  # an engine gone: the check reports it
            continue
    return out


def check_settings(engine: str, settings: dict, where: str, free: bool = False) -> None:
    """The recorded settings: the engine's class (its free-motion class for a free run),
    every field present (a missing one would silently run at today's default), typed as
    the class declares, and within its range (the settings class checks it, as for
    ``--set``: one definition)."""
    try:
        cls, name = settings_class(engine, free)
    except LinkageError as e:
        if free:  # a registered engine without a free-motion run
            raise BaselineError(f"{where}: {e}") from None
        return
    except ImportError:  # its library is missing: a failed run, later
        return
    if cls is None:
        return
    fields = settings["fields"]
    if settings.get("class", cls.__name__) != cls.__name__:
        raise BaselineError(f"{where}: settings class {settings['class']!r} is not "
                            f"{engine}'s ({cls.__name__})")
    types = cls.field_types()
    unknown = sorted(set(fields) - set(types))
    if unknown:
        raise BaselineError(f"{where}: settings field {unknown[0]!r}: {engine} has no "
                            f"setting {unknown[0]!r} (settings: {', '.join(types)})")
    missing = [k for k in types if k not in fields]
    if missing:
        raise BaselineError(f"{where}: settings field {missing[0]!r} is missing (it would "
                            f"run at today's default {getattr(cls(), missing[0])!r}); "
                            "record the baseline again")
    for k, typ in types.items():
        need = _json_type_problem(fields[k], typ)
        if need:
            raise BaselineError(f"{where}: settings field {k}={json_value(fields[k])}: "
                                f"must be {need}")
    try:
        cls.from_overrides(fields, name)
    except SettingsError as e:
        raise BaselineError(f"{where}: settings field {e.key}={json_value(e.value)}: "
                            f"{e.problem}") from None


def settings_class(engine: str, free: bool):
    """``(settings class, engine name)`` of a prescribed or free run of ``engine``
    (``(None, engine)`` when its library is missing)."""
    if free:
        return free_settings_class(engine), engine
    try:
        eng = get_engine(engine)
    except (SimModelError, ImportError):
        return None, engine
    return eng.settings_class, eng.name


def _json_type_problem(v, typ) -> str | None:
    """What a JSON value of a settings field of type ``typ`` must be, when it is not."""
    def number(x):
        return isinstance(x, (int, float)) and not isinstance(x, bool)
    if typ is bool:
        return None if isinstance(v, bool) else "true or false"
    if typ is int:
        return None if isinstance(v, int) and not isinstance(v, bool) else "a whole number"
    if typ is float:
        return None if number(v) else "a number"
    if typ is str:
        return None if isinstance(v, str) else "a string"
    if isinstance(v, list) and all(number(x) for x in v):
        return None
    return "a list of numbers"



__all__ = ["check_settings", "fmt_value", "override_classes", "overrides_for",
           "settings_class", "settings_from_json", "settings_json", "settings_line"]
