"""The pytest plugin's session run cache (:mod:`reports.regression.pytest_plugin`): runs
kept for the session (per xdist worker), keyed by the mechanism's content, the engine,
the settings object and the run request, so any number of assertions on one run cost one
run.  The project's own engine tests share it (:func:`session_run`).

One :class:`RunCache` per process, :data:`SESSION`; it also counts runs, hits and seconds
and keeps what ``--xval-update`` rewrote, for the terminal summary
(:mod:`xval_pytest_plugin`).
"""

from __future__ import annotations

import copy
import hashlib
import os
import time

from analytic.errors import LinkageError
from reports.comparison import runs as verdict_runs
from reports.comparison.quantities import judged
from reports.comparison.runs import request_of
from reports.regression import own_model as own
from reports.regression.baseline_free import is_free, run_and_compare_free
from reports.regression.baseline_record import request_dict
from sim_models.engines.registry import get_engine


def mech_digest(mech) -> str:
    """A digest of a mechanism's content (its dataclass repr is exact: floats repr
    round-trip), so a file loaded twice, by any path, or a built-in case loaded twice, is
    one key.  The file name (``source``, kept for error messages) is left out."""
    bare = copy.copy(mech)  # no __post_init__: a shallow copy, not a new validation
    if getattr(bare, "source", None) is not None:
        object.__setattr__(bare, "source", None)
    return hashlib.sha256(repr(bare).encode()).hexdigest()


def settings_of(engine: str, settings):
    """A settings object from None (recommended), a dict of overrides, a settings file's
    path (``xval tune --out``: the engine's entry, recommended where it has none), or an
    object."""
    eng = get_engine(engine)
    if settings is None:
        return eng.settings()
    if isinstance(settings, (str, os.PathLike)):
        from reports.comparison.settings_file import read_settings_file
        return eng.settings(read_settings_file(settings, "run").overrides(engine))
    if isinstance(settings, dict):
        return eng.settings(settings)
    return settings


class RunCache:
    """The runs of one pytest session.  ``entries``: (mechanism digest, engine, settings,
    request) -> {"run", "tree", "comparisons"} or {"error": exception} (a free run: its
    ``(FreeEngineRun, [FreeComparison])``); treat the cached runs as read-only.
    ``stats``: engine runs made, requests served from the cache, seconds spent running.
    ``updates``: what ``--xval-update`` rewrote (lines for the terminal summary)."""

    def __init__(self) -> None:
        self.entries: dict[tuple, object] = {}
        self.stats = {"runs": 0, "hits": 0, "seconds": 0.0}
        self.updates: list[str] = []

    def entry(self, mech, engine: str, settings, request: dict) -> dict:
        """A prescribed run and its comparisons (a refusal is cached and raised again)."""
        key = (mech_digest(mech), engine, type(settings).__qualname__, repr(settings),
               tuple(sorted(request.items())))
        hit = self.entries.get(key)
        if hit is not None:
            self.stats["hits"] += 1
        else:
            hit = self.entries[key] = self.make_run(mech, engine, settings, request)
        if "error" in hit:
            raise hit["error"]
        return hit

    def free_entry(self, mech, engine: str, settings, request: dict):
        """A free run and its judged quantities, cached for the session."""
        key = ("free", mech_digest(mech), engine, type(settings).__qualname__,
               repr(settings), tuple(sorted(request.items())))
        hit = self.entries.get(key)
        if hit is not None:
            self.stats["hits"] += 1
            return hit
        t0 = time.perf_counter()
        self.stats["runs"] += 1
        try:
            hit = self.entries[key] = run_and_compare_free(mech, engine, settings, request)
        finally:
            self.stats["seconds"] += time.perf_counter() - t0
        return hit

    def own_entry(self, path, opts, engine: str, request: dict):
        """A run of a user's model file (:mod:`reports.regression.own_model`), driven or
        released as ``request`` asks, read with ``opts`` (its import options), cached
        for the session by the file's bytes: ``(run, judged comparisons)`` of a driven
        run, ``(FreeEngineRun, FreeVerdict)`` of a released one."""
        key = ("own", *own.run_key(path, opts), engine, tuple(sorted(request.items())))
        hit = self.entries.get(key)
        if hit is not None:
            self.stats["hits"] += 1
            return hit
        own.check_engine(path, engine, is_free(request))
        own.check_request(request)  # before the count: no run for an impossible request
        t0 = time.perf_counter()
        self.stats["runs"] += 1
        try:
            hit = self.entries[key] = (
                own.free_own(path, opts, request["duration"], request["samples"])
                if is_free(request) else own.prescribed_own(path, opts, request, engine))
        finally:
            self.stats["seconds"] += time.perf_counter() - t0
        return hit

    def make_run(self, mech, engine, settings, request) -> dict:
        """Run and compare (not cached here: :meth:`entry` keeps it)."""
        t0 = time.perf_counter()
        self.stats["runs"] += 1
        try:
            v = verdict_runs.run_verdict(mech, engine, settings, request_of(request))
        except LinkageError as e:  # a refusal or nothing to compare: cached like a result
            return {"error": e}
        finally:
            self.stats["seconds"] += time.perf_counter() - t0
        return {"run": v.run, "tree": v.tree, "comparisons": list(v.comparisons)}

    def run(self, mech, engine: str, settings=None, revolutions: int | None = None,
            samples: int | None = None, max_violation: float | None = None,
            max_speed_error: float | None = None, chords: str | None = None):
        """:func:`sim_models.runs.driven.run` of a Mechanism, cached (same arguments, same run
        object).  ``settings``: None, overrides or a settings object; a request value left
        None is :class:`sim_models.runs.engine_run.RunRequest`'s default."""
        s = settings_of(engine, settings)
        req = request_dict(revolutions, samples, max_violation, max_speed_error, chords)
        return self.entry(mech, engine, s, req)["run"]

    def runner(self, mech, engine: str, settings, request: dict):
        """:data:`reports.regression.baseline_record.Runner` on the cache (baseline
        checks); a free-motion request (:mod:`reports.regression.baseline_free`) is
        released and judged by the same function ``xval baseline`` uses, cached alike;
        a user's model file is run as it is (:meth:`own_entry`)."""
        if own.is_model_file(getattr(mech, "source", None)):
            r, comps = self.own_entry(mech.source, own.options_of(mech), engine, request)
            return (r, own.free_comparisons(comps)) if is_free(request) else (r, comps)
        if is_free(request):
            return self.free_entry(mech, engine, settings, request)
        e = self.entry(mech, engine, settings, request)
        return e["run"], judged(e["comparisons"])


#: The session's cache (one per process: an xdist worker has its own).
SESSION = RunCache()


def session_run(mech, engine: str, settings=None, revolutions: int | None = None,
                samples: int | None = None, max_violation: float | None = None,
                max_speed_error: float | None = None, chords: str | None = None):
    """:meth:`RunCache.run` on :data:`SESSION`."""
    return SESSION.run(mech, engine, settings, revolutions, samples, max_violation,
                       max_speed_error, chords)


def cached_runner(mech, engine: str, settings, request: dict):
    """:meth:`RunCache.runner` on :data:`SESSION`."""
    return SESSION.runner(mech, engine, settings, request)


__all__ = ["SESSION", "RunCache", "cached_runner", "mech_digest", "session_run", "settings_of"]
