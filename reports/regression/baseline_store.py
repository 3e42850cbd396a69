"""A baseline file read and written (:mod:`reports.regression.baseline` describes the
format): :func:`dumps` / :func:`save` write it keys sorted, one line per quantity;
:func:`load` reads it and checks every value against the ranges of the command line
(the run request as :class:`sim_models.runs.engine_run.RunRequest` checks it, the settings as
the engine's settings class does, a free run's request as
:mod:`reports.regression.baseline_free` does): :class:`BaselineError` names the file,
the run and the key.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

from analytic.errors import OutputError
from reports.regression.baseline import (
    SCHEMA,
    SCHEMA_VERSION,
    Baseline,
    BaselineError,
    ModelSource,
    QuantityRecord,
    RunRecord,
    json_value,
    tolerance_problem,
)
from reports.regression.baseline_free import FREE_MODE, free_request_problem
from reports.regression.baseline_settings import check_settings
from sim_models.engines.registry import engine_names
from sim_models.engines.settings import SettingsError
from sim_models.runs.engine_run import RunRequest


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
    except RecursionError:  # [[[[... deeper than Python's decoder recurses
        raise BaselineError(f"{where}: not JSON: nested too deeply (a baseline is at "
                            "most a few levels deep)") from None
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
    check_settings(engine, settings, where, free)
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
        bad = tolerance_problem(tol)
        if bad:
            raise BaselineError(f"{qw}: 'tolerance' {bad}")
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
                f"={json_value(value)}: {problem}" if problem != "missing"
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
                            f"exceeded), got {json_value(h)}")
    return float(h)


def _known_engine(engine: str, where: str) -> None:
    """A registered engine name (an engine whose library is missing is a failed run at
    check time, not a bad file)."""
    if engine not in engine_names():
        raise BaselineError(f"{where}: 'engine' {engine!r} is not a known engine; engines: "
                            f"{', '.join(engine_names())}")


#: The command-line option that takes each request value, for the message.
_REQUEST_OPTIONS = {"revolutions": "--revolutions", "samples": "--samples"}


def _request_in_range(request: dict, where: str) -> None:
    """The request within the command line's ranges (:class:`sim_models.runs.engine_run.
    RunRequest` checks them: one definition): e.g. revolutions 1 to 1000, samples 2 to
    3600, a finite loop-gap threshold."""
    keys = ("revolutions", "samples", "max_violation", "max_speed_error", "chords", "mode")
    try:
        RunRequest(**{k: request[k] for k in keys})
    except SettingsError as e:
        flag = _REQUEST_OPTIONS.get(e.key)
        raise BaselineError(f"{where}: request {e.key}={json_value(e.value)}: {e.problem}"
                            + (f"; the range of {flag}" if flag else "")) from None


def _num(v) -> float:
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else math.nan



__all__ = ["dumps", "load", "save"]
