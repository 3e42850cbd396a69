"""Baselines: what each engine run's errors were, so a later run can tell when they drift.

A baseline file records, per (case, engine, quantity), the worst error relative to the
quantity's peak over the cycle, where in the cycle it occurs, the tolerance, and what is
needed to re-run the run exactly: the mechanism's source (a built-in case name, or a
TOML file path relative to the baseline file), with the parsed mechanism flattened to its
SI values and their SHA-256 (:mod:`reports.regression.model_identity`: a comment or CRLF is no
change, a real one is named), the run request and the engine's settings object in full.
It also records the versions the run was made with (engine, linkage-xval, Python,
numpy, platform).  :func:`check` re-runs every recorded run and judges each quantity
(:func:`judge`): above its tolerance, grown by more than ``factor`` over its baseline
(with the absolute floor :data:`DRIFT_FLOOR`), or gone.

File format (``schema = "linkage-xval baseline"``, ``schema_version = 1``); plain JSON,
keys sorted, two-space indent, one line per quantity, so that a diff shows what moved::

    {
      "recorded": "2026-11-23T05:00:00Z",
      "runs": [
        {
          "case": "seed-four-bar",                 # the mechanism's name (a label)
          "engine": "mujoco",                      # a registry name
          "model": {"builtin": "seed-four-bar", "sha256": "...", "content": {...}}
                 | {"file": "linkages/four_bar.toml", "sha256": "...",
                    "content": {"bodies.coupler.mass": 0.6, ...}},   # one line
          "quantities": [
            {"at": 165.0, "at_unit": "deg", "error": 1.48e-08, "max_abs": ..., "peak": ...,
             "quantity": "B.force", "tolerance": 0.001},
            ...                                    # sorted by quantity
          ],
          "request": {"chords": "moving", "max_speed_error": 0.01, "max_violation": 0.001,
                      "mode": "run", "revolutions": 2, "samples": 36},
          "settings": {"class": "MujocoSettings", "engine": "mujoco", "fields": {...}},
          "versions": {"engine": "mujoco 3.3.7", "linkage-xval": "0.1.0", "numpy": "2.4.0",
                       "platform": "Linux-...", "python": "3.11.2"}
        }, ...                                     # sorted by case, then engine
      ],
      "schema": "linkage-xval baseline",
      "schema_version": 1
    }

``error`` is ``max |engine - analytic| / peak`` (:func:`reports.comparison.compare.compare`), stored
to :data:`ERROR_DIGITS` significant figures; ``at`` is the input value (deg for a
revolute driver, m for a prismatic one).  The engines' own unjudged readings
(``[engine]`` rows) are not recorded.  A file that cannot be read, is not this schema,
or lacks a key raises :class:`BaselineError` (the command line: one line, status 2).
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import math
import os
import platform
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np

from analytic import load_case
from analytic.cases import case_names, case_path, free_case_names, hard_case_names
from analytic.errors import LinkageError, OutputError
from analytic.input_display import format_input
from analytic.mechanism import Prismatic
from analytic.tolerances import ENGINE_RELATIVE
from reports.comparison import runs as verdict_runs
from reports.comparison.quantities import judged
from reports.comparison.runs import request_of
from reports.regression import model_identity as mid
from reports.regression.baseline_free import (
    FREE_MODE,
    free_request_problem,
    free_settings_class,
    horizon_slack,
    is_free,
    run_and_compare_free,
)
from sim_models.engine_run import RunRequest
from sim_models.engine_settings import SettingsError
from sim_models.registry import engine_names, get_engine, split_overrides
from sim_models.tree import SimModelError

SCHEMA = "linkage-xval baseline"
SCHEMA_VERSION = 1

#: Default drift factor: a quantity fails when its error grows by more than this over
#: its baseline (issue 13: "MuJoCo's error grew from 1e-8 to 5e-4").
DEFAULT_FACTOR = 10.0

#: Absolute floor (relative to peak) under the drift check: a quantity fails for drift
#: only when its error exceeds ``factor * max(baseline, DRIFT_FLOOR)``.  Errors far
#: below the tolerance include pure round-off (a constant-speed crank's alpha reads 0 or
#: 1e-22), and a perturbation the size of round-off moves them.  Measured over every
#: built-in case in every engine, scaling every mass by (1 + 1e-14) changed the errors
#: below 1e-6 of peak by at most 5e-9 of peak (PyBullet six-bar output.alpha; MuJoCo
#: 8e-14, Exudyn 2e-15).  It changed larger errors by at most 7% of themselves (PyBullet
#: six-bar link.alpha; Exudyn six-bar 2%), and the largest growth over max(error, 1e-7)
#: was 1.07x.  With 1e-7 the smallest drift that fails (1e-6 at factor 10) is 200x the
#: largest jitter of a small error, and still a thousandth of the 1e-3 tolerance.
DRIFT_FLOOR = 1e-7

#: Significant figures stored for errors (drift is judged by factors, not digits; fewer
#: digits keep a re-recorded file's diff to the errors that really moved).
ERROR_DIGITS = 4


class BaselineError(LinkageError):
    """A baseline file cannot be used: names the file, the entry and the problem."""


# ============================================================================ records
@dataclass(frozen=True)
class ModelSource:
    """Where a run's mechanism comes from: ``kind`` "builtin" (``name`` a case name) or
    "file" (``name`` a path relative to the baseline file's folder, POSIX separators);
    ``sha256`` of the parsed mechanism's canonical content when recorded
    (:func:`reports.regression.model_identity.digest`; files recorded before that hold the SHA-256
    of the file's bytes, still accepted); ``content`` the mechanism flattened
    (:func:`reports.regression.model_identity.content`), so a change can be named (None in older
    files)."""

    kind: str
    name: str
    sha256: str
    content: dict | None = field(default=None, compare=False)

    def as_json(self) -> dict:
        out = {self.kind: self.name, "sha256": self.sha256}
        return out if self.content is None else {**out, "content": self.content}

    def path(self, base_dir: Path) -> Path:
        """The description file this source names now."""
        if self.kind == "builtin":
            return Path(case_path(self.name))
        return base_dir / self.name

    def describe(self) -> str:
        return f"built-in case {self.name!r}" if self.kind == "builtin" else f"file {self.name}"


@dataclass(frozen=True)
class QuantityRecord:
    """One quantity's recorded diagnostic (see :class:`reports.comparison.compare.Comparison`)."""

    quantity: str
    error: float          # max |error| / peak
    at: float             # input value where it occurs (``at_unit``)
    at_unit: str          # "deg" or "m"
    tolerance: float      # relative to peak
    max_abs: float        # SI units of the quantity
    peak: float
    #: a free run's trusted horizon, s (inf: never exceeded; None: a prescribed run,
    #: whose error is relative to the peak and ``at`` an input value; a free run's is
    #: relative to the range over the run and ``at`` a time, s)
    horizon: float | None = None

    def as_json(self) -> dict:
        out = {"quantity": self.quantity, "error": _sig(self.error, ERROR_DIGITS),
               "at": _sig(self.at, 7), "at_unit": self.at_unit, "tolerance": self.tolerance,
               "max_abs": _sig(self.max_abs, ERROR_DIGITS), "peak": _sig(self.peak, 6)}
        if self.horizon is not None:  # null: never exceeded within the run
            out["horizon_s"] = _sig(self.horizon, 7)
        return out


@dataclass(frozen=True)
class RunRecord:
    """One recorded (case, engine) run: enough to re-run it exactly, and its errors."""

    case: str
    engine: str
    model: ModelSource
    request: dict
    settings: dict        # {"engine", "class", "fields": {name: value}}
    versions: dict
    quantities: tuple[QuantityRecord, ...]
    #: why a free run being recorded stopped early (not written: refused by
    #: :func:`record_problems`)
    stopped: str = field(default="", compare=False)

    @property
    def free(self) -> bool:
        """A free-motion run (:mod:`reports.regression.baseline_free`)."""
        return self.request.get("mode") == "free"

    @property
    def key(self) -> tuple[str, ...]:
        base = (self.model.kind, self.model.name, self.engine)
        return (*base, "free") if self.free else base

    @property
    def label(self) -> str:
        return f"{self.case} / {self.engine}" + (
            f" (free, {self.request['duration']:g} s)" if self.free else "")

    def as_json(self) -> dict:
        return {"case": self.case, "engine": self.engine, "model": self.model.as_json(),
                "request": dict(self.request), "settings": self.settings,
                "versions": dict(self.versions),
                "quantities": [q.as_json() for q in sorted(self.quantities,
                                                           key=lambda q: q.quantity)]}


@dataclass(frozen=True)
class Baseline:
    """A baseline file's content; ``path`` is where it was read from or written to."""

    runs: tuple[RunRecord, ...]
    path: Path
    recorded: str = ""

    @property
    def base_dir(self) -> Path:
        return self.path.resolve().parent

    def as_json(self) -> dict:
        runs = sorted(self.runs, key=lambda r: (r.case, r.engine, r.model.name))
        return {"schema": SCHEMA, "schema_version": SCHEMA_VERSION,
                "recorded": self.recorded, "runs": [r.as_json() for r in runs]}


def _sig(x: float, digits: int) -> float | None:
    """``x`` to ``digits`` significant figures (JSON has no inf/NaN: those become None)."""
    x = float(x)
    return float(f"{x:.{digits}g}") if math.isfinite(x) else None


# ============================================================================ versions
def versions(engine: str) -> dict:
    """The versions a run depends on: the engine's library, this project, Python, numpy
    and the platform (read from package metadata; no engine library is imported)."""

    def ver(dist: str) -> str:
        try:
            return version(dist)
        except PackageNotFoundError:
            return "unknown"

    return {"engine": f"{engine} {ver(engine)}", "linkage-xval": ver("linkage-xval"),
            "python": platform.python_version(), "numpy": np.__version__,
            "platform": platform.platform()}


# ============================================================================ file I/O
def file_sha256(path: str | os.PathLike) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def dumps(baseline: Baseline) -> str:
    """The file text: keys sorted, two-space indent, one line per quantity."""
    return _dump(baseline.as_json(), 0, None) + "\n"


def _dump(obj, level: int, key: str | None) -> str:
    pad, inner = "  " * level, "  " * (level + 1)
    if isinstance(obj, dict):
        if key in ("quantity-line", "content"):  # one line each
            return json.dumps(obj, sort_keys=True)
        if not obj:
            return "{}"
        items = [f"{inner}{json.dumps(k)}: {_dump(obj[k], level + 1, k)}" for k in sorted(obj)]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(obj, list) and obj and isinstance(obj[0], dict):
        sub = "quantity-line" if key == "quantities" else None
        items = [f"{inner}{_dump(v, level + 1, sub)}" for v in obj]
        return "[\n" + ",\n".join(items) + "\n" + pad + "]"
    return json.dumps(obj, sort_keys=True)


def save(baseline: Baseline, path: str | os.PathLike | None = None) -> Path:
    """Write ``baseline`` (to ``path``, default its own); raises :class:`OutputError`."""
    p = Path(path or baseline.path)
    try:
        p.write_text(dumps(baseline), encoding="utf-8")
    except OSError as e:
        raise OutputError(f"cannot write baseline {str(p)!r}: {e.strerror}") from None
    return p


def load(path: str | os.PathLike) -> Baseline:
    """Read and validate a baseline file; :class:`BaselineError` names what is wrong."""
    p = Path(path)
    where = str(path)
    if p.is_dir():
        raise BaselineError(f"baseline {where!r} is a folder; give the JSON file")
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise BaselineError(f"no such baseline file {where!r}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise BaselineError(f"cannot read baseline {where!r}: "
                            f"{getattr(e, 'strerror', None) or e}") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as e:
        raise BaselineError(f"{where}: not JSON: {e.msg} at line {e.lineno} column "
                            f"{e.colno}") from None
    return _parse(doc, p)


def _parse(doc, p: Path) -> Baseline:
    where = str(p)
    if not isinstance(doc, dict) or doc.get("schema") != SCHEMA:
        raise BaselineError(f"{where}: not a linkage-xval baseline (no \"schema\": "
                            f"\"{SCHEMA}\")")
    ver = doc.get("schema_version")
    if ver != SCHEMA_VERSION:
        raise BaselineError(f"{where}: schema_version {ver!r} is not supported (this "
                            f"xval reads {SCHEMA_VERSION})")
    runs = _get(doc, "runs", list, where)
    if not runs:  # a baseline that judges nothing must not pass
        raise BaselineError(f"{where}: 'runs' is empty: a baseline with no runs judges "
                            "nothing; record one with xval baseline record")
    out, seen = [], set()
    for i, r in enumerate(runs):
        rec = _parse_run(r, f"{where}: runs[{i}]")
        if rec.key in seen:
            raise BaselineError(f"{where}: runs[{i}]: {rec.label} is recorded twice")
        seen.add(rec.key)
        out.append(rec)
    return Baseline(tuple(out), p, str(doc.get("recorded", "")))


def _get(d, key: str, typ, where: str):
    if not isinstance(d, dict):
        raise BaselineError(f"{where}: expected an object")
    if key not in d:
        raise BaselineError(f"{where}: missing key {key!r}")
    v = d[key]
    ok = (isinstance(v, (int, float)) and not isinstance(v, bool)) if typ is float \
        else isinstance(v, typ)
    if not ok:
        raise BaselineError(f"{where}: {key!r} must be {_type_name(typ)}, got {v!r:.60}")
    return float(v) if typ is float else v


def _type_name(typ) -> str:
    return {float: "a number", str: "a string", list: "a list", dict: "an object",
            int: "a whole number"}.get(typ, typ.__name__)


def _parse_run(r, where: str) -> RunRecord:
    case = _get(r, "case", str, where)
    engine = _get(r, "engine", str, where)
    where = f"{where} ({case} / {engine})"
    _known_engine(engine, where)
    model = _get(r, "model", dict, where)
    kinds = [k for k in ("builtin", "file") if k in model]
    if len(kinds) != 1:
        raise BaselineError(f"{where}: model needs exactly one of 'builtin' or 'file'")
    content = model.get("content")
    if content is not None and not isinstance(content, dict):
        raise BaselineError(f"{where}: model: 'content' must be an object")
    src = ModelSource(kinds[0], _get(model, kinds[0], str, f"{where}: model"),
                      _get(model, "sha256", str, f"{where}: model"), content)
    request = _get(r, "request", dict, where)
    free = _request_checked(request, where)
    settings = _get(r, "settings", dict, where)
    _get(settings, "fields", dict, f"{where}: settings")
    _settings_in_range(engine, settings, where, free)
    vers = _get(r, "versions", dict, where)
    qs = []
    for j, q in enumerate(_get(r, "quantities", list, where)):
        qw = f"{where}: quantities[{j}]"
        name = _get(q, "quantity", str, qw)
        qw = f"{where}: quantity {name!r}"
        err = q.get("error") if isinstance(q, dict) else None
        if err is None or isinstance(err, bool) or not isinstance(err, (int, float)) \
                or not math.isfinite(err) or err < 0:
            raise BaselineError(f"{qw}: 'error' must be a number >= 0, got {err!r}")
        tol = _get(q, "tolerance", float, qw)
        if not tol > 0:
            raise BaselineError(f"{qw}: 'tolerance' must be > 0, got {tol!r}")
        qs.append(QuantityRecord(name, float(err), _num(q.get("at")),
                                 str(q.get("at_unit", "")), tol, _num(q.get("max_abs")),
                                 _num(q.get("peak")), _horizon(q, qw, free)))
    if len({q.quantity for q in qs}) != len(qs):
        raise BaselineError(f"{where}: a quantity is recorded twice")
    if not qs:  # nothing to judge: the run would pass whatever its errors
        raise BaselineError(f"{where}: 'quantities' is empty: a run with no recorded "
                            "quantity judges nothing; record it again")
    return RunRecord(case, engine, src, dict(request), settings, dict(vers), tuple(qs))


def _request_checked(request: dict, where: str) -> bool:
    """Check a recorded request (prescribed ``run`` or ``free``) against the command
    line's ranges; returns whether it is a free-motion run."""
    mode = _get(request, "mode", str, f"{where}: request")
    if mode == FREE_MODE:
        bad = free_request_problem(request)
        if bad:
            key, value, problem = bad
            raise BaselineError(f"{where}: request {key}" + (
                f"={_json_value(value)}: {problem}" if problem != "missing"
                else ": missing key"))
        return True
    if mode != "run":
        raise BaselineError(f"{where}: request mode {mode!r}: only 'run' (prescribed) and "
                            f"'{FREE_MODE}' (free motion) are supported")
    for k, typ in (("revolutions", int), ("samples", int), ("max_violation", float),
                   ("max_speed_error", float), ("chords", str)):
        _get(request, k, typ, f"{where}: request")
    _request_in_range(request, where)
    return False


def _horizon(q: dict, where: str, free: bool) -> float | None:
    """A free quantity's recorded trusted horizon (s; null: never exceeded -> inf)."""
    if not free:
        return None
    if "horizon_s" not in q:
        raise BaselineError(f"{where}: missing key 'horizon_s' (a free run's trusted "
                            "horizon, s; null: never exceeded)")
    h = q["horizon_s"]
    if h is None:
        return math.inf
    if isinstance(h, bool) or not isinstance(h, (int, float)) or not math.isfinite(h) \
            or h < 0:
        raise BaselineError(f"{where}: 'horizon_s' must be a time >= 0 s or null (never "
                            f"exceeded), got {_json_value(h)}")
    return float(h)


def _known_engine(engine: str, where: str) -> None:
    """A registered engine name (an engine whose library is missing is a failed run at
    check time, not a bad file)."""
    if engine not in engine_names():
        raise BaselineError(f"{where}: 'engine' {engine!r} is not a known engine; engines: "
                            f"{', '.join(engine_names())}")


def _settings_in_range(engine: str, settings: dict, where: str, free: bool = False) -> None:
    """The recorded settings: the engine's class (its free-motion class for a free run),
    every field present (a missing one would silently run at today's default), typed as
    the class declares, and within its range (the settings class checks it, as for
    ``--set``: one definition)."""
    try:
        cls, name = _settings_class(engine, free)
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
            raise BaselineError(f"{where}: settings field {k}={_json_value(fields[k])}: "
                                f"must be {need}")
    try:
        cls.from_overrides(fields, name)
    except SettingsError as e:
        raise BaselineError(f"{where}: settings field {e.key}={_json_value(e.value)}: "
                            f"{e.problem}") from None


def _settings_class(engine: str, free: bool):
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


#: The command-line option that takes each request value, for the message.
_REQUEST_OPTIONS = {"revolutions": "--revolutions", "samples": "--samples"}


def _request_in_range(request: dict, where: str) -> None:
    """The request within the command line's ranges (:class:`sim_models.engine_run.
    RunRequest` checks them: one definition): e.g. revolutions 1 to 1000, samples 2 to
    3600, a finite loop-gap threshold."""
    keys = ("revolutions", "samples", "max_violation", "max_speed_error", "chords", "mode")
    try:
        RunRequest(**{k: request[k] for k in keys})
    except SettingsError as e:
        flag = _REQUEST_OPTIONS.get(e.key)
        raise BaselineError(f"{where}: request {e.key}={_json_value(e.value)}: {e.problem}"
                            + (f"; the range of {flag}" if flag else "")) from None


def _json_value(v) -> str:
    """``v`` as the file spells it (``true``, ``NaN``, ``"bogus"``)."""
    try:
        return json.dumps(v)
    except (TypeError, ValueError):
        return repr(v)


def _num(v) -> float:
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else math.nan


# ============================================================================ running
#: ``runner(mechanism, engine, settings, request) -> (EngineRun, comparisons)``: how a
#: run is made (the command line runs it; the pytest plugin caches it per session).
Runner = Callable[..., tuple]


def run_and_compare(mech, engine: str, settings, request: dict):
    """Run ``engine`` on ``mech`` as ``request`` asks and compare every judged quantity
    with the analytic solution (:func:`reports.comparison.runs.run_verdict`):
    ``(EngineRun, [Comparison])`` (``[engine]`` rows left out).  A free-motion request
    (:mod:`reports.regression.baseline_free`) releases the linkage instead: ``(FreeEngineRun,
    [FreeComparison])``."""
    if is_free(request):
        return run_and_compare_free(mech, engine, settings, request)
    v = verdict_runs.run_verdict(mech, engine, settings, request_of(request))
    return v.run, v.judged()


def request_dict(revolutions: int | None = None, samples: int | None = None,
                 max_violation: float | None = None, max_speed_error: float | None = None,
                 chords: str | None = None) -> dict:
    """A run request as a baseline records it; a value not given (None) is the default of
    :class:`sim_models.engine_run.RunRequest`, the one holder of the run defaults."""

    def given(value, name: str):
        return getattr(RunRequest, name) if value is None else value
    return {"revolutions": int(given(revolutions, "revolutions")),
            "samples": int(given(samples, "samples")),
            "max_violation": float(given(max_violation, "max_violation")),
            "max_speed_error": float(given(max_speed_error, "max_speed_error")),
            "chords": given(chords, "chords"), "mode": "run"}


def settings_json(engine: str, settings) -> dict:
    """The settings object in full: engine name, class and every field."""
    fields = {k: list(v) if isinstance(v, tuple) else v for k, v in settings.as_dict().items()}
    return {"engine": engine, "class": type(settings).__name__, "fields": fields}


def settings_line(engine: str, settings) -> str:
    """Every field of a settings object as ``key=value``, after the engine's name."""
    return f"{engine}: " + " ".join(f"{k}={_fmt_value(v, True)}"
                                    for k, v in settings.as_dict().items())


def _fmt_value(v, paren: bool = False) -> str:
    """A setting as typed after ``--set KEY=`` (floats in %g, tuples comma-separated;
    ``paren``: tuples in parentheses, for reading)."""
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, (tuple, list)):
        inner = ",".join(_fmt_value(x) for x in v)
        return f"({inner})" if paren else inner
    return str(v)


def settings_from_json(rec: RunRecord, where: str, overrides: dict | None = None):
    """The settings object a record was run with (:meth:`EngineSettings.from_overrides`),
    with ``overrides`` ({field: value} of this engine, ``--set``) over the recorded
    fields; raises :class:`BaselineError` when the engine no longer accepts a recorded
    field (a bad override is the :class:`SettingsError` of ``--set``: status 2)."""
    from sim_models.engine_base import SettingsError
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
    (:func:`sim_models.registry.split_overrides`, ``classes`` its settings classes;
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


# ============================================================================ record
def source_of(model: str, base_dir: Path) -> tuple[ModelSource, object]:
    """``(ModelSource, Mechanism)`` of a built-in case name or a TOML path (relative
    paths in the baseline are relative to ``base_dir``, the baseline file's folder)."""
    if model in builtin_names():
        mech = load_case(model)
        return ModelSource("builtin", model, mid.digest(mech), mid.content(mech)), mech
    p = Path(model).resolve()
    mech = load_case(str(p))
    rel = Path(os.path.relpath(p, base_dir)).as_posix()
    return ModelSource("file", rel, mid.digest(mech), mid.content(mech)), mech


def builtin_names() -> list[str]:
    """The names a baseline records as built-in: the cases, the hard cases and the
    free-motion cases."""
    return [*case_names(), *hard_case_names(), *free_case_names()]


def record(models: Sequence[str], engines: Sequence[str], out: str | os.PathLike,
           settings: dict | None = None, request: dict | None = None,
           tolerance: float | None = None, runner: Runner | None = None) -> Baseline:
    """Run every model in every engine and return the baseline (not yet written).

    ``settings``: engine name -> settings object (default: the recommended ones);
    ``request``: :func:`request_dict`; ``tolerance``: relative to peak (default
    :data:`analytic.tolerances.ENGINE_RELATIVE`).  Raises :class:`EngineRefusal` /
    :class:`NothingToCompare` (status 2) as ``xval compare`` does.  A free-motion
    ``request`` (:func:`reports.regression.baseline_free.free_request`) records released runs,
    each quantity with its own tolerance (:mod:`reports.comparison.free_compare`; ``tolerance``
    must be None) and trusted horizon."""
    tol = ENGINE_RELATIVE if tolerance is None else float(tolerance)
    req = request or request_dict()
    runner = runner or run_and_compare
    base_dir = Path(out).resolve().parent
    runs = []
    free = is_free(req)
    for model in models:
        src, mech = source_of(model, base_dir)
        for engine in engines:
            s = (settings or {}).get(engine) or (
                free_settings_class(engine)() if free else get_engine(engine).settings())
            r, comps = runner(mech, engine, s, req)
            runs.append(_record_free(mech, src, engine, s, req, r, comps) if free
                        else _record_run(mech, src, engine, s, req, r, comps, tol))
    now = _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    return Baseline(tuple(runs), Path(out), now)


def _record_run(mech, src, engine, settings, req, r, comps, tol) -> RunRecord:
    unit = "deg" if _revolute(mech) else "m"
    qs = tuple(QuantityRecord(c.quantity, float(c.normalised), float(c.at), unit, tol,
                              float(c.max_abs), float(c.peak)) for c in comps)
    return RunRecord(mech.name, engine, src, dict(req), settings_json(engine, settings),
                     versions(engine), qs)


def _record_free(mech, src, engine, settings, req, r, comps) -> RunRecord:
    """A free run's record: each quantity's error over its range, the time of its
    maximum (s), its tolerance and trusted horizon (a run that stopped: noted as a
    problem by :func:`record_problems`)."""
    qs = tuple(QuantityRecord(c.quantity, float(c.normalised), float(c.at), "s",
                              float(c.tolerance), float(c.max_abs), float(c.scale),
                              float(c.horizon)) for c in comps)
    stopped = "" if r.ok else f"the run stopped at t = {r.t_fail:.4g} s: {r.reason}"
    return RunRecord(r.case, engine, src, dict(req), settings_json(engine, settings),
                     versions(engine), qs, stopped)


def merge(old: Baseline, new: Baseline) -> tuple[Baseline, dict[str, int]]:
    """``new``'s runs recorded into ``old``: a run of the same (model, engine) is
    replaced, the others kept, new ones added.  Returns the merged baseline (``new``'s
    path and time) and the counts ``{"updated", "kept", "added"}``."""
    fresh = {r.key: r for r in new.runs}
    runs, counts = [], {"updated": 0, "kept": 0, "added": 0}
    for r in old.runs:
        hit = fresh.pop(r.key, None)
        runs.append(hit or r)
        counts["updated" if hit else "kept"] += 1
    runs += fresh.values()
    counts["added"] = len(fresh)
    return Baseline(tuple(runs), new.path, new.recorded), counts


def record_problems(baseline: Baseline) -> list[str]:
    """Why a fresh baseline should not be written: quantities that are not finite or
    already above their tolerance (a baseline records a passing state)."""
    out = []
    for r in baseline.runs:
        if r.stopped:  # a free run that stopped judges nothing after it stopped
            out.append(f"{r.label}: {r.stopped}")
            continue
        for q in r.quantities:
            if not math.isfinite(q.error):
                out.append(f"{r.label}: {q.quantity} is not finite (the run failed)")
            elif q.horizon is not None:  # free: over its tolerance is its horizon
                continue
            elif q.error > q.tolerance:
                out.append(f"{r.label}: {q.quantity} error {q.error:.3g} of peak exceeds "
                           f"its tolerance {q.tolerance:g}")
    return out


def record_command(baseline: Baseline, cwd: str | os.PathLike | None = None) -> str:
    """The ``xval baseline record`` command that records ``baseline``'s runs again (file
    paths relative to ``cwd``, default the current folder); settings that differ from
    an engine's defaults are named as ``--set ENGINE.KEY=VALUE``.  Free runs are
    recorded by their own command (``--free --duration S --samples N``, one per
    duration and sample count), joined by ``&&`` (each merges into the file)."""
    groups: dict = {}
    for r in baseline.runs:
        k = (r.request["duration"], r.request["samples"]) if r.free else None
        groups.setdefault(k, []).append(r)
    return " && ".join(_record_words(runs, baseline, cwd, k)
                       for k, runs in sorted(groups.items(), key=lambda kv: kv[0] is not None))


def _record_words(runs, baseline: Baseline, cwd, free) -> str:
    """One ``xval baseline record`` command for ``runs`` (all prescribed, or all free
    with ``free`` = (duration, samples))."""
    models, engines, sets = [], [], []
    for r in runs:
        m = r.model.name if r.model.kind == "builtin" else \
            os.path.relpath(r.model.path(baseline.base_dir), cwd or os.getcwd())
        models += [m] if m not in models else []
        engines += [r.engine] if r.engine not in engines else []
        sets += [s for s in _overrides(r) if s not in sets]
    if free is None and set(case_names()) <= set(models):
        models = ["all"] + [m for m in models if m not in case_names()]
    words = ["xval baseline record", *models, *(f"--engine {e}" for e in engines),
             *(f"--set {s}" for s in sets)]
    out = os.path.relpath(baseline.path.resolve(), cwd or os.getcwd())
    if free is not None:
        return " ".join([*words, f"--free --duration {free[0]:g} --samples {free[1]}",
                         f"--out {out}"])
    req = runs[0].request if runs else request_dict()
    default = request_dict()  # the options' defaults: RunRequest's
    words += [f"--revolutions {req['revolutions']}"] \
        if req["revolutions"] != default["revolutions"] else []
    words += [f"--samples {req['samples']}"] if req["samples"] != default["samples"] else []
    tols = {q.tolerance for r in runs for q in r.quantities}
    if len(tols) == 1 and (t := tols.pop()) != ENGINE_RELATIVE:
        words.append(f"--tolerance {t:g}")
    return " ".join([*words, f"--out {out}"])


def _overrides(rec: RunRecord) -> list[str]:
    """``ENGINE.KEY=VALUE`` for each recorded setting that is not the engine's default."""
    try:
        cls, _ = _settings_class(rec.engine, rec.free)
        default = cls().as_dict()
    except (LinkageError, ImportError, TypeError):  # an engine gone: the check says so
        return []
    out = []
    for k, v in sorted(rec.settings["fields"].items()):
        v = tuple(v) if isinstance(v, list) else v
        if k in default and default[k] != v:
            out.append(f"{rec.engine}.{k}={_fmt_value(v)}")
    return out


def _revolute(mech) -> bool:
    return not isinstance(mech.driver_joint, Prismatic)


# ============================================================================ check
@dataclass(frozen=True)
class QuantityCheck:
    """One quantity against its baseline.  ``status``: "ok", "over-tolerance", "drift",
    "not-finite", "missing" (recorded, no longer compared), "new" (not recorded;
    reported, not judged), "improved" (the error shrank by more than the factor: the
    baseline is loose, a warning) or "loose" (the same, failed: ``fail_loose``)."""

    quantity: str
    status: str
    error: float            # now, relative to peak (NaN when missing)
    base: float             # recorded (NaN when new)
    at: float
    at_unit: str
    tolerance: float
    factor: float
    #: free runs: the trusted horizon now and recorded, s (inf: never exceeded), and how
    #: much earlier it may come (``reports.regression.baseline_free.horizon_slack``)
    horizon: float = math.nan
    base_horizon: float = math.nan
    slack: float = math.nan

    @property
    def scale_word(self) -> str:
        """What the error is relative to: a free run's range, a prescribed run's peak."""
        return "of range" if self.at_unit == "s" else "of peak"

    @property
    def failed(self) -> bool:
        return self.status not in ("ok", "new", "improved")

    @property
    def ratio(self) -> float:
        """Growth over the baseline (inf from a zero baseline)."""
        if not (math.isfinite(self.error) and math.isfinite(self.base)):
            return math.nan
        return self.error / self.base if self.base > 0 else \
            (1.0 if self.error == 0 else math.inf)

    def message(self) -> str:
        """One line naming the quantity, what happened, by how much and where."""
        at = f" at {format_input(self.at, self.at_unit)}" if math.isfinite(self.at) else ""
        of = self.scale_word
        if self.status == "missing":
            return f"{self.quantity}: recorded (error {self.base:.3g} {of}) but no " \
                   "longer compared"
        if self.status == "new":
            return f"{self.quantity}: new, not in the baseline (error {self.error:.3g} {of})"
        if self.status == "not-finite":
            return f"{self.quantity}: error is not finite{at} (the run diverged or failed)"
        if self.status == "horizon":
            return f"{self.quantity}: trusted horizon {self.base_horizon:.4g} s -> " \
                   f"{self.horizon:.4g} s, earlier by more than one sample interval " \
                   f"({self.slack:.3g} s; error {self.error:.3g} {of}, tolerance " \
                   f"{self.tolerance:g})"
        grew = f"{self.base:.3g} -> {self.error:.3g} {of}{at} ({_times(self.ratio)})"
        if self.status in ("improved", "loose"):
            return f"{self.quantity}: improved {grew}, more than the factor " \
                   f"{self.factor:g}: the baseline is loose; re-record"
        if self.status == "over-tolerance":
            return f"{self.quantity}: error {self.error:.3g} {of}{at} exceeds its " \
                   f"tolerance {self.tolerance:g} (baseline {self.base:.3g}, {_times(self.ratio)})"
        if self.status == "drift":
            floor = "" if self.base >= DRIFT_FLOOR else \
                f"; baseline below the floor {DRIFT_FLOOR:g}, so the limit is " \
                f"{self.factor * DRIFT_FLOOR:.3g}"
            return f"{self.quantity}: drifted {grew}, more than the factor " \
                   f"{self.factor:g}{floor}"
        return f"{self.quantity}: {grew}"


def _times(r: float) -> str:
    if not math.isfinite(r):
        return "from zero"
    return f"{r:.3g}x" if r < 1e4 else f"{r:.2g}x"


def judge(q: QuantityRecord, error: float, at: float, factor: float,
          fail_loose: bool = False) -> QuantityCheck:
    """The verdict of one quantity now (``error`` relative to peak) against its record.
    An error that shrank by more than ``factor`` (both floored at :data:`DRIFT_FLOOR`)
    leaves the baseline loose: it would let the error grow back unnoticed."""
    if not math.isfinite(error):
        status = "not-finite"
    elif error > q.tolerance:
        status = "over-tolerance"
    elif error > factor * max(q.error, DRIFT_FLOOR):
        status = "drift"
    elif q.error > factor * max(error, DRIFT_FLOOR):
        status = "loose" if fail_loose else "improved"
    else:
        status = "ok"
    return QuantityCheck(q.quantity, status, error, q.error, at, q.at_unit, q.tolerance,
                         factor)


def judge_free(q, c, factor: float, fail_loose: bool, slack: float):
    """The check of one free quantity ``c`` (a :class:`FreeComparison`) against its
    record ``q``: the prescribed judge on its error (the tolerance only when the record
    was within it), then its trusted horizon (no earlier than recorded minus
    ``slack`` s)."""

    error, h = float(c.normalised), float(c.horizon)
    within = math.isinf(q.horizon)
    ref = q if within else replace(q, tolerance=math.inf)
    out = judge(ref, error, float(c.at), factor, fail_loose)
    out = replace(out, tolerance=q.tolerance, horizon=h, base_horizon=q.horizon)
    if out.status == "ok" and not within and h < q.horizon - slack:
        out = replace(out, status="horizon", slack=slack)
    return out


@dataclass
class RunCheck:
    """One recorded run re-run: its quantities' verdicts and the run-level problems
    (model changed or gone, engine gone, run refused or failed)."""

    record: RunRecord
    quantities: list[QuantityCheck] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    versions_now: dict = field(default_factory=dict)
    settings_text: str = ""
    wall: float = 0.0

    @property
    def passed(self) -> bool:
        return not self.problems and not any(q.failed for q in self.quantities)

    def failures(self) -> list[QuantityCheck]:
        """Failed quantities, worst first (by growth over the limit)."""
        bad = [q for q in self.quantities if q.failed]
        return sorted(bad, key=_severity, reverse=True)

    def worst(self) -> QuantityCheck | None:
        """The failing quantity to name first, else the largest error."""
        bad = self.failures()
        if bad:
            return bad[0]
        done = [q for q in self.quantities if math.isfinite(q.error)]
        return max(done, key=lambda q: q.error, default=None)

    def loose(self) -> list[QuantityCheck]:
        """Quantities whose error shrank by more than the factor (warnings)."""
        return [q for q in self.quantities if q.status == "improved"]

    def versions_changed(self) -> dict[str, tuple[str, str]]:
        return {k: (str(v), str(self.versions_now.get(k, "unknown")))
                for k, v in self.record.versions.items()
                if self.versions_now and str(self.versions_now.get(k, "unknown")) != str(v)}


def _severity(q: QuantityCheck) -> tuple:
    rank = {"not-finite": 4, "over-tolerance": 3, "missing": 2, "horizon": 2,
            "drift": 1}.get(q.status, 0)
    over = q.error / max(q.factor * max(q.base, DRIFT_FLOOR), 1e-300) \
        if math.isfinite(q.error) and math.isfinite(q.base) else math.inf
    return (rank, over)


def check(baseline: Baseline, factor: float = DEFAULT_FACTOR, runner: Runner | None = None,
          select: Callable[[RunRecord], bool] | None = None, fail_loose: bool = False,
          overrides: dict | None = None) -> list[RunCheck]:
    """Re-run every recorded run (those ``select`` keeps) and judge it (see the module
    docstring).  ``fail_loose``: an error that shrank by more than ``factor`` fails
    (default: a warning); ``overrides``: engine name -> {setting: value} applied over
    the recorded settings (``--set``; named in each run's settings text).  Raises
    :class:`BaselineError` only for a file that cannot be applied (e.g. settings the
    engine no longer accepts); everything about the runs themselves is in the returned
    :class:`RunCheck`."""
    if not (factor > 1 and math.isfinite(factor)):
        raise BaselineError(f"the drift factor must be a finite number above 1, got "
                            f"{factor!r}")
    runner = runner or run_and_compare
    return [check_run(rec, baseline, factor, runner, fail_loose, (overrides or {}).get(
        rec.engine)) for rec in baseline.runs if select is None or select(rec)]


def check_run(rec: RunRecord, baseline: Baseline, factor: float, runner: Runner,
              fail_loose: bool = False, overrides: dict | None = None) -> RunCheck:
    """One record: rebuild its mechanism and settings (with ``overrides``), run, judge."""
    out = RunCheck(rec)
    mech = _mechanism_now(rec, baseline, out)
    settings = _settings_now(rec, baseline, out, overrides)
    if mech is None or settings is None:
        return out
    out.settings_text = settings_line(rec.engine, settings) + (
        " (changed for this check: " + " ".join(f"{k}={v}" for k, v in overrides.items())
        + ")" if overrides else "")
    out.versions_now = versions(rec.engine)
    t0 = time.perf_counter()
    try:
        r, comps = runner(mech, rec.engine, settings, rec.request)
    except LinkageError as e:  # a refusal, or nothing left to compare
        out.problems.append(f"the run could not be compared: {e}")
        out.wall = time.perf_counter() - t0
        return out
    out.wall = time.perf_counter() - t0
    if not r.ok:
        out.problems.append(f"the run failed: {r.reason}")
    now = {c.quantity: c for c in comps}
    for q in rec.quantities:
        c = now.get(q.quantity)
        if c is None:
            out.quantities.append(QuantityCheck(q.quantity, "missing", math.nan, q.error,
                                                math.nan, q.at_unit, q.tolerance, factor))
        elif rec.free:
            out.quantities.append(judge_free(q, c, factor, fail_loose,
                                             horizon_slack(rec.request)))
        else:
            out.quantities.append(judge(q, float(c.normalised), float(c.at), factor,
                                        fail_loose))
    recorded = {q.quantity for q in rec.quantities}
    unit = "s" if rec.free else "deg" if _revolute(mech) else "m"
    for c in comps:
        if c.quantity not in recorded:
            out.quantities.append(QuantityCheck(c.quantity, "new", float(c.normalised),
                                                math.nan, float(c.at), unit, c.tolerance,
                                                factor))
    return out


def _mechanism_now(rec: RunRecord, baseline: Baseline, out: RunCheck):
    """The recorded model as it is now (None, with a problem, when it is gone)."""
    src = rec.model
    if src.kind == "builtin" and src.name not in builtin_names():
        out.problems.append(f"the built-in case {src.name!r} no longer exists")
        return None
    p = src.path(baseline.base_dir)
    if not p.is_file():
        out.problems.append(f"the model {src.describe()} is gone (looked for {p})")
        return None
    try:
        mech = load_case(src.name if src.kind == "builtin" else str(p))
    except LinkageError as e:
        out.problems.append(f"the model {src.describe()} changed since the baseline and "
                            f"no longer loads: {e}")
        return None
    # identity by content: the parsed mechanism, not the bytes (a comment or CRLF is no
    # change); a file recorded before content identity holds the bytes' SHA-256
    if mid.digest(mech) != src.sha256 and file_sha256(p) != src.sha256:
        what = mid.changes(src.content, mid.content(mech)) if src.content is not None \
            else f"sha256 {src.sha256[:12]}... (recorded from the file's bytes)"
        out.problems.append(f"the model {src.describe()} changed since the baseline "
                            f"(parsed mechanism): {what}; re-record the baseline if the "
                            "change is intended")
    return mech


def _settings_now(rec: RunRecord, baseline: Baseline, out: RunCheck,
                  overrides: dict | None = None):
    try:
        get_engine(rec.engine)
    except (SimModelError, ImportError) as e:  # not registered, or its library missing
        out.problems.append(f"engine {rec.engine!r} is not available: {e}")
        return None
    # every field is present: a missing one is refused where the file is read
    return settings_from_json(rec, str(baseline.path), overrides)


__all__ = ["DEFAULT_FACTOR", "DRIFT_FLOOR", "ERROR_DIGITS", "SCHEMA", "SCHEMA_VERSION",
           "Baseline", "BaselineError", "ModelSource", "QuantityCheck", "QuantityRecord",
           "RunCheck", "RunRecord", "builtin_names", "check", "check_run", "dumps",
           "file_sha256", "judge", "judge_free", "judged", "load", "merge",
           "override_classes", "record", "record_command", "record_problems",
           "request_dict", "run_and_compare", "save", "settings_from_json", "settings_json",
           "settings_line", "source_of", "versions"]
