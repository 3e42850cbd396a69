"""Recording a baseline (``xval baseline record``): every model run in every engine
(:func:`record`), what keeps a fresh record from being written (:func:`record_problems`),
merged into an existing file (:func:`merge`), and the command that records a file again
(:func:`record_command`).  :func:`run_and_compare` is how a run is made, here and in
:func:`reports.regression.baseline_check.check`.
"""

from __future__ import annotations

import datetime as _dt
import math
import os
from collections.abc import Callable, Sequence
from pathlib import Path

from analytic import load_case
from analytic.cases import case_names
from analytic.errors import LinkageError
from analytic.tolerances import ENGINE_RELATIVE
from reports.comparison import runs as verdict_runs
from reports.comparison.runs import request_of
from reports.regression import model_identity as mid
from reports.regression import own_model as own
from reports.regression.baseline import (
    Baseline,
    ModelSource,
    QuantityRecord,
    RunRecord,
    builtin_names,
    input_unit,
    versions,
)
from reports.regression.baseline_free import (
    free_settings_class,
    is_free,
    run_and_compare_free,
)
from reports.regression.baseline_settings import fmt_value, settings_class, settings_json
from sim_models.engines.registry import get_engine
from sim_models.runs.engine_run import RunRequest

#: ``runner(mechanism, engine, settings, request) -> (EngineRun, comparisons)``: how a
#: run is made (the command line runs it; the pytest plugin caches it per session).
Runner = Callable[..., tuple]


def run_and_compare(mech, engine: str, settings, request: dict):
    """Run ``engine`` on ``mech`` as ``request`` asks and compare every judged quantity
    with the analytic solution (:func:`reports.comparison.runs.run_verdict`):
    ``(EngineRun, [Comparison])`` (``[engine]`` rows left out).  A free-motion request
    (:mod:`reports.regression.baseline_free`) releases the linkage instead: ``(FreeEngineRun,
    [FreeComparison])``."""
    if own.is_model_file(getattr(mech, "source", None)):  # a user's MJCF model
        return own.run_and_compare_own(mech, engine, settings, request)
    if is_free(request):
        return run_and_compare_free(mech, engine, settings, request)
    v = verdict_runs.run_verdict(mech, engine, settings, request_of(request))
    return v.run, v.judged()


def request_dict(revolutions: int | None = None, samples: int | None = None,
                 max_violation: float | None = None, max_speed_error: float | None = None,
                 chords: str | None = None) -> dict:
    """A run request as a baseline records it; a value not given (None) is the default of
    :class:`sim_models.runs.engine_run.RunRequest`, the one holder of the run defaults."""

    def given(value, name: str):
        return getattr(RunRequest, name) if value is None else value
    return {"revolutions": int(given(revolutions, "revolutions")),
            "samples": int(given(samples, "samples")),
            "max_violation": float(given(max_violation, "max_violation")),
            "max_speed_error": float(given(max_speed_error, "max_speed_error")),
            "chords": given(chords, "chords"), "mode": "run"}


def source_of(model: str, base_dir: Path, own_options: dict | None = None
              ) -> tuple[ModelSource, object]:
    """``(ModelSource, Mechanism)`` of a built-in case name or a TOML path (relative
    paths in the baseline are relative to ``base_dir``, the baseline file's folder); a
    user's MJCF file (:mod:`reports.regression.own_model`)."""
    if own.is_model_file(model):
        return own.own_source(model, base_dir, **(own_options or {}))
    if model in builtin_names():
        mech = load_case(model)
        return ModelSource("builtin", model, mid.digest(mech), mid.content(mech)), mech
    p = Path(model).resolve()
    mech = load_case(str(p))
    rel = Path(os.path.relpath(p, base_dir)).as_posix()
    return ModelSource("file", rel, mid.digest(mech), mid.content(mech)), mech


def record(models: Sequence[str], engines: Sequence[str], out: str | os.PathLike,
           settings: dict | None = None, request: dict | None = None,
           tolerance: float | None = None, runner: Runner | None = None,
           own_options: dict | None = None) -> Baseline:
    """Run every model in every engine and return the baseline (not yet written).

    ``settings``: engine name -> settings object (default: the recommended ones);
    ``request``: :func:`request_dict`; ``tolerance``: relative to peak (default
    :data:`analytic.tolerances.ENGINE_RELATIVE`).  Raises :class:`EngineRefusal` /
    :class:`NothingToCompare` (status 2) as ``xval compare`` does.  A free-motion
    ``request`` (:func:`reports.regression.baseline_free.free_request`) records released runs,
    each quantity with its own tolerance (:mod:`reports.comparison.free_compare`; ``tolerance``
    must be None) and trusted horizon.  ``own_options``: ``driver`` and ``keyframe`` of the
    users' model files (:func:`reports.regression.own_model.own_source`)."""
    tol = ENGINE_RELATIVE if tolerance is None else float(tolerance)
    req = request or request_dict()
    runner = runner or run_and_compare
    base_dir = Path(out).resolve().parent
    runs = []
    free = is_free(req)
    for model in models:
        src, mech = source_of(model, base_dir, own_options)
        for engine in engines:
            s = (settings or {}).get(engine) or (
                free_settings_class(engine)() if free else get_engine(engine).settings())
            r, comps = runner(mech, engine, s, req)
            runs.append(_record_free(mech, src, engine, s, req, r, comps) if free
                        else _record_run(mech, src, engine, s, req, r, comps, tol))
    now = _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    return Baseline(tuple(runs), Path(out), now)


def _record_run(mech, src, engine, settings, req, r, comps, tol) -> RunRecord:
    unit = input_unit(mech)
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
        sets += [f"{k}" for k in _own_words(r) if k not in sets]
    if free is None and set(case_names()) <= set(models):
        models = ["all"] + [m for m in models if m not in case_names()]
    words = ["xval baseline record", *models, *(f"--engine {e}" for e in engines),
             *(s if s.startswith("--") else f"--set {s}" for s in sets)]
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


def _own_words(rec: RunRecord) -> list[str]:
    """``--driver J`` / ``--keyframe K`` a user's model was recorded with."""
    return [f"--{k} {v}" for k, v in own.recorded_options(rec.model.content).items()]


def _overrides(rec: RunRecord) -> list[str]:
    """``ENGINE.KEY=VALUE`` for each recorded setting that is not the engine's default."""
    try:
        cls, _ = settings_class(rec.engine, rec.free)
        default = cls().as_dict()
    except (LinkageError, ImportError, TypeError):  # an engine gone: the check says so
        return []
    out = []
    for k, v in sorted(rec.settings["fields"].items()):
        v = tuple(v) if isinstance(v, list) else v
        if k in default and default[k] != v:
            out.append(f"{rec.engine}.{k}={fmt_value(v)}")
    return out



__all__ = ["Runner", "merge", "record", "record_command", "record_problems", "request_dict",
           "run_and_compare", "source_of"]
