"""Engine settings (the base every engine's settings dataclass subclasses) and the typed
errors of the engine layer.  See :mod:`sim_models.engines.protocol` for the protocol."""

from __future__ import annotations

import dataclasses
import math
import typing
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

from ..builders.tree import SimModelError
from ..runs.precision import FLOAT64, Arithmetic
from . import ranges


# ============================================================================ errors
class EngineRefusal(SimModelError):
    """An engine cannot run this mechanism or motion; the message says why (one line).

    The command line prints it and exits with status 2 (never the failed-verdict 1)."""


class SettingsError(SimModelError):
    """A setting key or value is not accepted (names the engine, key and value).

    ``key``, ``value`` and ``problem`` (why, with the accepted range) are kept apart so
    that each door can say it in the user's own terms (``--set mujoco.iterations=-5:
    ...``, ``argument --timestep: ...``, a baseline file's run and key)."""

    def __init__(self, message: str, key: str | None = None, value=None,
                 problem: str | None = None):
        super().__init__(message)
        self.key, self.value, self.problem = key, value, problem or message


# ============================================================================ settings
@dataclass(frozen=True)
class EngineSettings:
    """Base of every engine's settings (frozen dataclass; subclass it).

    ``timestep`` is the largest step, s; the run shortens it so that every sample
    falls on a step.  Subclasses redefine it with their recommended default.
    """

    timestep: float = 1e-3

    #: The accepted range of each field (:mod:`sim_models.engines.ranges`): a
    #: :class:`~sim_models.engines.ranges.Range`, a :class:`~sim_models.engines.ranges.Choice`, or a
    #: tuple of ranges for a tuple field.  Subclasses extend it (``{**EngineSettings.
    #: RANGES, ...}``); every field must have one (:meth:`validate`).
    RANGES: ClassVar[Mapping[str, object]] = {"timestep": ranges.TIMESTEP}
    #: The registry name, for messages (``engine 'mujoco' setting ...``).
    engine_name: ClassVar[str] = ""
    #: The arithmetic the engine's solver computes in (:mod:`sim_models.runs.precision`):
    #: float64 claims no error floor; a float32 engine sets
    #: :data:`~sim_models.runs.precision.FLOAT32`.
    arithmetic: ClassVar[Arithmetic] = FLOAT64

    def __post_init__(self):
        # a word setting in any letter case is kept in its listed spelling (ranges.Choice),
        # so that the engines compare it with one spelling
        for f in dataclasses.fields(self):
            rng = self.RANGES.get(f.name)
            if isinstance(rng, ranges.Choice):
                object.__setattr__(self, f.name, rng.canonical(getattr(self, f.name)))
        self.validate()

    def validate(self) -> None:
        """Raise :class:`SettingsError` for the first field outside its range
        (:attr:`RANGES`), then for the cross-field rules of :meth:`extra_problem`."""
        who = getattr(type(self), "engine_name", "") or type(self).__name__
        for f in dataclasses.fields(self):
            rng = self.RANGES.get(f.name)
            if rng is None:
                raise SettingsError(f"{type(self).__name__}.{f.name} has no accepted range "
                                    "(add it to RANGES)", f.name)
            value = getattr(self, f.name)
            problem = ranges.first_problem(rng, value)
            if problem:
                raise SettingsError(f"engine {who!r} setting {f.name}={_fmt_setting(value)}: "
                                    f"{problem}", f.name, value, problem)
        bad = self.extra_problem()
        if bad:
            key, problem = bad
            value = getattr(self, key)
            raise SettingsError(f"engine {who!r} setting {key}={_fmt_setting(value)}: "
                                f"{problem}", key, value, problem)

    def extra_problem(self) -> tuple[str, str] | None:
        """``(key, why)`` for a rule that one range per field cannot say (e.g. two signs
        that must agree); ``None`` when there is none."""
        return None

    @classmethod
    def ranges_text(cls) -> dict[str, str]:
        """Each field's accepted range in words (for the README and ``--help``)."""
        out = {}
        for k, r in cls.RANGES.items():
            out[k] = "; ".join(x.text() for x in r) if isinstance(r, tuple) else r.text()
        return out

    # -- construction ----------------------------------------------------------
    @classmethod
    def field_types(cls) -> dict[str, type]:
        hints = typing.get_type_hints(cls)
        return {f.name: hints[f.name] for f in dataclasses.fields(cls)}

    @classmethod
    def from_overrides(cls, overrides: Mapping[str, object] | None = None,
                       engine: str = ""):
        """The recommended settings with ``overrides`` applied.

        Values may be typed (``{"timestep": 1e-4}``) or strings as typed on the command
        line (``{"timestep": "1e-4", "integrator": "Euler", "solref": "-1e4,-200"}``).
        An unknown key or an unparsable value raises :class:`SettingsError` naming it
        and the accepted keys."""
        return cls().with_overrides(overrides, engine)

    def with_overrides(self, overrides: Mapping[str, object] | None, engine: str = ""):
        """A copy with ``overrides`` applied (see :meth:`from_overrides`)."""
        if not overrides:
            return self
        types = self.field_types()
        who = engine or type(self).__name__
        kw = {}
        for key, raw in overrides.items():
            if key not in types:
                problem = f"no setting {key!r}; settings: {', '.join(sorted(types))}"
                raise SettingsError(f"engine {who!r} has {problem}", key, raw, problem)
            kw[key] = _convert(who, key, raw, types[key], getattr(self, key))
        return dataclasses.replace(self, **kw)

    # -- use --------------------------------------------------------------------
    def max_step(self, plan) -> float:
        """Largest step (s) for ``plan`` (a :class:`sim_models.runs.sampling.Plan`: e.g.
        ``plan.rev_time / steps_per_rev``); default :attr:`timestep`."""
        return float(self.timestep)

    def error_floor(self, steps: int, condition: float) -> float:
        """The error (normalised by the quantity's peak) this engine's arithmetic cannot
        go below in a run of ``steps`` steps (0: one solve) at a sample of loop
        condition number ``condition`` (:meth:`sim_models.runs.precision.Arithmetic.floor`;
        0.0 for float64).  The comparison reads an error above the tolerance but within
        this floor as a precision limit, not a failure."""
        return self.arithmetic.floor(steps, condition)

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)

    def describe(self) -> str:
        """One line: every field as ``key=value``."""
        return " ".join(f"{k}={_fmt_setting(v)}" for k, v in self.as_dict().items())


def _fmt_setting(v) -> str:
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, tuple):
        return "(" + ",".join(_fmt_setting(x) for x in v) + ")"
    return str(v)


def _convert(who: str, key: str, raw, typ, current):
    """``raw`` (typed or a string) as a value of field type ``typ``."""
    origin = typing.get_origin(typ)
    where = f"engine {who!r} setting {key}={raw!r}"
    try:
        if origin is tuple or isinstance(current, tuple):
            parts = raw if isinstance(raw, (tuple, list)) else \
                [x for x in str(raw).strip("()[] ").split(",") if x.strip()]
            val = tuple(float(x) for x in parts)
            if current is not None and len(val) != len(current):
                raise ValueError(f"needs {len(current)} numbers")
            bad = [x for x in val if not math.isfinite(x)]
            if bad:
                raise ValueError("numbers must be finite")
            return val
        if typ is bool or isinstance(current, bool):
            if isinstance(raw, bool):
                return raw
            s = str(raw).strip().lower()
            if s in ("1", "true", "yes", "on"):
                return True
            if s in ("0", "false", "no", "off"):
                return False
            raise ValueError("use true or false")
        if typ is int or (isinstance(current, int) and not isinstance(current, bool)):
            f = float(raw)
            if not math.isfinite(f) or f != int(f):
                raise ValueError("needs a whole number")
            return int(f)
        if typ is float or isinstance(current, float):
            f = float(raw)
            if not math.isfinite(f):
                raise ValueError("needs a finite number")
            return f
        return str(raw)
    except (TypeError, ValueError) as e:
        raise SettingsError(f"{where}: {e}", key, raw, str(e)) from None


__all__ = ["EngineRefusal", "EngineSettings", "SettingsError"]
