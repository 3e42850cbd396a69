"""The work behind linkage-xval's pytest plugin: engine-against-analytic assertions and
baseline checks in your own suite.

The plugin itself (fixtures, options, marker, hooks) is the top-level module
:mod:`xval_pytest_plugin`, registered through the ``pytest11`` entry point ``xval``
(``pyproject.toml``); it imports this module on first use, so a pytest run that uses no
xval fixture imports nothing of the tool.  With plugin autoloading off, load it with
``-p xval``::

    def test_four_bar(xval):
        xval.assert_agrees("linkages/four_bar.toml", engine="mujoco", tolerance=1e-3)

    def test_no_drift(xval_baseline):      # one test per run recorded in the ini's file
        xval_baseline()

A relative model or baseline path is relative to pytest's rootdir (the folder of your
``pytest.ini`` / ``pyproject.toml``); a name without ``.toml`` is a built-in case.

Runs are cached for the session (per xdist worker), keyed by the mechanism's content, the
engine, the settings object and the run request: any number of assertions on one run cost
one run (:func:`session_run`).  The project's own engine tests share this cache.
"""

from __future__ import annotations

import copy
import hashlib
import math
import os
import time
import warnings
from dataclasses import replace
from pathlib import Path

import pytest

from analytic import load_case
from analytic.cases import case_names, free_case_names
from analytic.errors import LinkageError
from analytic.input_display import format_input  # the one input convention
from analytic.tolerances import ENGINE_RELATIVE
from reports.comparison import runs as verdict_runs
from reports.comparison.free_cases import free_case
from reports.comparison.runs import request_of
from reports.regression import baseline as bl
from reports.regression.baseline import (
    DEFAULT_FACTOR,
    Baseline,
    _fmt_value,
    _severity,
    judged,
    load,
    overrides_for,
    record_command,
    request_dict,
    settings_line,
)
from reports.regression.baseline_free import is_free, run_and_compare_free
from reports.regression.messages import report_lines
from reports.studies.free_studies import free_verdict
from sim_models.registry import get_engine

#: (mechanism digest, engine, settings, request) -> {"run", "tree", "comparisons"} or
#: {"error": exception}: the session's runs.  Treat the cached runs as read-only.
_CACHE: dict[tuple, dict] = {}
_STATS = {"runs": 0, "hits": 0, "seconds": 0.0}
#: What ``--xval-update`` rewrote this session (lines for the terminal summary).
_UPDATES: list[str] = []


class XvalLooseWarning(UserWarning):
    """An error shrank by more than the drift factor: the baseline no longer guards it."""


# ============================================================================ the cache
def _mech_digest(mech) -> str:
    """A digest of a mechanism's content (its dataclass repr is exact: floats repr
    round-trip), so a file loaded twice, by any path, or a built-in case loaded twice, is
    one key.  The file name (``source``, kept for error messages) is left out."""
    bare = copy.copy(mech)  # no __post_init__: a shallow copy, not a new validation
    if getattr(bare, "source", None) is not None:
        object.__setattr__(bare, "source", None)
    return hashlib.sha256(repr(bare).encode()).hexdigest()


def _settings_of(engine: str, settings):
    """A settings object from None (recommended), a dict of overrides, or an object."""
    eng = get_engine(engine)
    if settings is None:
        return eng.settings()
    if isinstance(settings, dict):
        return eng.settings(settings)
    return settings


def _request(revolutions=None, samples=None, max_violation=None, max_speed_error=None,
             chords=None) -> dict:
    """:func:`reports.regression.baseline.request_dict`: None takes ``RunRequest``'s default."""
    return request_dict(revolutions, samples, max_violation, max_speed_error, chords)


def _entry(mech, engine: str, settings, request: dict) -> dict:
    key = (_mech_digest(mech), engine, type(settings).__qualname__, repr(settings),
           tuple(sorted(request.items())))
    hit = _CACHE.get(key)
    if hit is not None:
        _STATS["hits"] += 1
    else:
        hit = _CACHE[key] = _make_run(mech, engine, settings, request)
    if "error" in hit:
        raise hit["error"]
    return hit


def _free_entry(mech, engine: str, settings, request: dict):
    """A free run and its judged quantities, cached for the session."""
    key = ("free", _mech_digest(mech), engine, type(settings).__qualname__,
           repr(settings), tuple(sorted(request.items())))
    hit = _CACHE.get(key)
    if hit is not None:
        _STATS["hits"] += 1
        return hit
    t0 = time.perf_counter()
    _STATS["runs"] += 1
    try:
        hit = _CACHE[key] = run_and_compare_free(mech, engine, settings, request)
    finally:
        _STATS["seconds"] += time.perf_counter() - t0
    return hit


def _make_run(mech, engine, settings, request) -> dict:
    t0 = time.perf_counter()
    _STATS["runs"] += 1
    try:
        v = verdict_runs.run_verdict(mech, engine, settings, request_of(request))
    except LinkageError as e:  # a refusal or nothing to compare: cached like a result
        return {"error": e}
    finally:
        _STATS["seconds"] += time.perf_counter() - t0
    return {"run": v.run, "tree": v.tree, "comparisons": list(v.comparisons)}


def session_run(mech, engine: str, settings=None, revolutions: int | None = None,
                samples: int | None = None, max_violation: float | None = None,
                max_speed_error: float | None = None, chords: str | None = None):
    """:func:`sim_models.engines.run` of a Mechanism, cached for the session (same
    arguments, same run object).  ``settings``: None, overrides or a settings object; a
    request value left None is :class:`sim_models.engine_run.RunRequest`'s default."""
    s = _settings_of(engine, settings)
    req = _request(revolutions, samples, max_violation, max_speed_error, chords)
    return _entry(mech, engine, s, req)["run"]


def cached_runner(mech, engine: str, settings, request: dict):
    """:data:`reports.regression.baseline.Runner` on the session cache (baseline checks); a
    free-motion request (:mod:`reports.regression.baseline_free`) is released and judged by the
    same function ``xval baseline`` uses, cached alike."""
    if is_free(request):
        return _free_entry(mech, engine, settings, request)
    e = _entry(mech, engine, settings, request)
    return e["run"], judged(e["comparisons"])


# ============================================================================ messages
def _at_text(run_, at: float) -> str:
    if not math.isfinite(at):
        return "at an unreached sample"
    return f"at input {format_input(at, 'm' if run_.extra.get('prismatic_driver') else 'deg')}"


def _unit(quantity: str, run_) -> str:
    """SI unit of a compared quantity (see :func:`reports.comparison.compare.compare_run`)."""
    kind = quantity.rsplit(".", 1)[-1]
    if kind == "alpha":
        return "rad/s^2"
    if kind == "a":
        return "m/s^2"
    if kind == "effort":
        return "N" if run_.extra.get("prismatic_driver") else "N m"
    return "N"


def disagreement(label: str, run_, comps, tolerance: float, settings_text: str) -> str:
    """The failure message of :meth:`Xval.assert_agrees`: every failing quantity with its
    error (relative to peak and absolute), where in the cycle, then the settings."""
    bad = sorted((c for c in comps if not c.accepted),
                 key=lambda c: c.normalised if math.isfinite(c.normalised) else math.inf,
                 reverse=True)
    lines = [f"{label}: {len(bad)} of {len(comps)} quantities disagree with the analytic "
             f"solution by more than {tolerance:g} of peak"]
    if not run_.ok:
        lines.append(f"  the run failed: {run_.reason}")
    for c in bad:
        unit = _unit(c.quantity, run_)
        lines.append(f"  {c.quantity}: error {c.normalised:.3g} of peak {_at_text(run_, c.at)}"
                     f" (max |error| {c.max_abs:.4g} {unit}, peak {c.peak:.4g} {unit})")
    lines.append(f"  settings: {settings_text}")
    req = run_.request
    lines.append(f"  run: {req.revolutions} revolutions, {req.samples} samples"
                 + (" by time" if run_.by_time else " of the last revolution"))
    return "\n".join(lines)


# ============================================================================ the fixture
class Xval:
    """The ``xval`` fixture.  Paths are relative to ``root`` (pytest's rootdir)."""

    def __init__(self, root: Path, factor: float, update: bool = False,
                 fail_loose: bool = False):
        self.root = Path(root)
        self.factor = factor
        self.update = update          # --xval-update: rewrite what changed
        self.fail_loose = fail_loose  # --xval-fail-loose

    # -- models -----------------------------------------------------------------
    def resolve(self, model) -> Path | str:
        """A built-in case name as is; a path made absolute against the rootdir."""
        if not isinstance(model, (str, os.PathLike)):
            return model
        s = os.fspath(model)
        if s in case_names():
            return s
        p = Path(s)
        return p if p.is_absolute() else self.root / p

    def mechanism(self, model):
        """A Mechanism from a case name, a TOML path or a Mechanism."""
        m = self.resolve(model)
        return m if not isinstance(m, (str, Path)) else load_case(str(m))

    # -- runs ---------------------------------------------------------------------
    def run(self, model, engine: str = "mujoco", settings=None, *,
            revolutions: int | None = None, samples: int | None = None):
        """The engine run (cached for the session)."""
        return session_run(self.mechanism(model), engine, settings, revolutions, samples)

    def compare(self, model, engine: str = "mujoco", tolerance: float | None = None,
                settings=None, *, revolutions: int | None = None,
                samples: int | None = None, quantities=None):
        """``(run, comparisons)``: the judged quantities (engine readings left out) at
        ``tolerance`` (relative to peak; default 1e-3), optionally only ``quantities``."""

        tol = ENGINE_RELATIVE if tolerance is None else float(tolerance)
        mech = self.mechanism(model)
        s = _settings_of(engine, settings)
        e = _entry(mech, engine, s, _request(revolutions, samples))
        comps = [replace(c, tolerance=tol, passed=bool(c.normalised <= tol))
                 for c in judged(e["comparisons"])]
        if quantities is not None:
            want = [quantities] if isinstance(quantities, str) else list(quantities)
            have = {c.quantity for c in comps}
            unknown = [q for q in want if q not in have]
            if unknown:
                raise KeyError(f"{mech.name}: no quantity {unknown[0]!r}; compared: "
                               f"{', '.join(sorted(have))}")
            comps = [c for c in comps if c.quantity in want]
        return e["run"], comps

    def assert_agrees(self, model, engine: str = "mujoco", tolerance: float | None = None,
                      settings=None, *, revolutions: int | None = None,
                      samples: int | None = None, quantities=None):
        """Every judged quantity of ``model`` in ``engine`` within ``tolerance`` of its
        peak over the cycle (default 1e-3); returns the comparisons.  The failure message
        names each failing quantity, its error, where in the cycle, and the settings."""
        __tracebackhide__ = True
        run_, comps = self.compare(model, engine, tolerance, settings,
                                   revolutions=revolutions, samples=samples,
                                   quantities=quantities)
        if run_.ok and all(c.accepted for c in comps):  # a precision limit passes
            return comps
        tol = comps[0].tolerance if comps else (tolerance or 0.0)
        src = f" ({os.fspath(model)})" if isinstance(model, (str, os.PathLike)) and \
            os.fspath(model) != run_.case else ""
        raise AssertionError(disagreement(f"{run_.case}{src} / {engine}", run_, comps, tol,
                                          settings_line(engine, run_.settings)))

    def assert_free_agrees(self, model, engine: str = "mujoco", *,
                           duration: float | None = None, samples: int = 200,
                           settings=None):
        """Free motion: ``model`` (a case or file with ``[motion]``, or a driven one,
        released at rest under gravity) released in ``engine`` and judged against the
        exact trajectory (:func:`reports.comparison.free_compare.compare_free`); returns the
        :class:`FreeVerdict`.  The failure names each failing quantity, its trusted
        horizon, the nearest reference event and the engine's step."""
        __tracebackhide__ = True
        name = os.fspath(model) if isinstance(model, (str, os.PathLike)) else None
        mech = model if name is None else free_case(
            name if name in free_case_names() else os.fspath(self.resolve(name)))
        _, v = free_verdict(mech, engine, duration, samples, settings)
        if v.passed:
            return v
        lines = [f"{v.case} / {engine}: free motion over {v.duration:g} s disagrees "
                 f"(trusted horizon {v.horizon:.4g} s)"]
        lines += [f"  {c}" for c in v.judged if not c.passed]
        lines += [f"  {x}" for x in (v.near_event, v.step_note) if x]
        lines.append(f"  settings: {engine} {v.settings}")
        raise AssertionError("\n".join(lines))

    # -- baselines ------------------------------------------------------------------
    def path(self, baseline) -> Path:
        p = Path(baseline)
        return p if p.is_absolute() else self.root / p

    def check_baseline(self, baseline, *, case: str | None = None, engine: str | None = None,
                       factor: float | None = None, settings=None, key=None):
        """``(Baseline, [RunCheck])`` of the recorded runs (those of ``case`` / ``engine``,
        or the one run ``key``); ``settings``: overrides of the recorded settings."""
        base = bl.load(self.path(baseline))
        model = self.resolve(case) if case is not None else None

        def keep(rec):
            same = case is None or case in (rec.case, rec.model.name) or (
                isinstance(model, Path) and rec.model.kind == "file"
                and rec.model.path(base.base_dir).resolve() == model.resolve())
            return (key is None or rec.key == tuple(key)) and same and \
                (engine is None or rec.engine == engine)
        checks = bl.check(base, factor or self.factor, runner=cached_runner, select=keep,
                          fail_loose=self.fail_loose,
                          overrides=_overrides(settings, [r.engine for r in base.runs],
                                               bl.override_classes(base)))
        if not checks:
            raise KeyError(f"{baseline}: no recorded run of case={case!r} engine={engine!r}")
        return base, checks

    def assert_baseline(self, baseline, *, case: str | None = None,
                        engine: str | None = None, factor: float | None = None,
                        settings=None, key=None):
        """Re-run the baseline's runs (cached) and fail on drift beyond ``factor``, a
        quantity over its tolerance, or a run, quantity or model gone or changed.  The
        failure's first line is the worst quantity, its growth and where.  A loose
        baseline (an error shrank by more than the factor) warns, or fails with
        ``--xval-fail-loose``.  With ``--xval-update`` the changed runs are recorded
        again instead (and a missing file is created when ``case`` and ``engine`` name
        the run), and the summary says so."""
        __tracebackhide__ = True
        path = self.path(baseline)
        if not path.exists():
            return self._missing(path, case, engine, settings)
        try:
            base, checks = self.check_baseline(baseline, case=case, engine=engine,
                                               factor=factor, settings=settings, key=key)
        except bl.BaselineError as e:  # an unusable file: one line, no traceback
            pytest.fail(f"xval: error: {e}", pytrace=False)
        except KeyError as e:  # no such run recorded: as a missing file, for that run
            return self._missing(path, case, engine, settings, e.args[0])
        changed = [c for c in checks if not c.passed or c.loose()]
        if self.update and changed:
            self._rewrite(base, changed, settings)
            return checks
        for c in checks:
            for q in c.loose():
                warnings.warn(XvalLooseWarning(f"xval: {c.record.label}: {q.message()} "
                                               "(pytest --xval-update)"), stacklevel=2)
        if all(c.passed for c in checks):
            return checks
        raise AssertionError(failure_text(base, checks, factor or self.factor, self.root))

    def _missing(self, path: Path, case, engine, settings, what: str = ""):
        """A baseline file, or the run of ``case`` in ``engine``, not recorded yet:
        fail with the command that records it, or record it (``--xval-update``)."""
        __tracebackhide__ = True
        rel = os.path.relpath(path, self.root)
        what = what or f"no baseline file {rel} (under {self.root})"
        if case is None or engine is None:
            pytest.fail(f"xval: error: {what}; create it with: xval baseline record "
                        f"CASES_OR_FILES --engine ENGINE --out {rel}", pytrace=False)
        model = self.resolve(case)
        model_arg = os.path.relpath(model, self.root) if isinstance(model, Path) else model
        cmd = f"xval baseline record {model_arg} --engine {engine} --out {rel}"
        if not self.update:
            pytest.fail(f"xval: error: {what}; create it with pytest --xval-update, or: "
                        f"{cmd}", pytrace=False)
        self._record(path, str(model), engine, settings, None, None,
                     "added" if path.exists() else "created")
        return []

    def _record(self, path: Path, model: str, engine: str, settings, request, tolerance,
                why: str) -> None:
        """Record one run through the session cache and merge it into ``path``."""
        __tracebackhide__ = True
        s = _settings_of(engine, settings)
        new = bl.record([model], [engine], path, {engine: s}, request, tolerance,
                        runner=cached_runner)
        problems = bl.record_problems(new)
        if problems:
            raise AssertionError(f"--xval-update: {problems[0]} (a baseline records a "
                                 "passing state; not written)")
        label = new.runs[0].label
        if path.exists():
            new, _ = bl.merge(bl.load(path), new)
        bl.save(new)
        _UPDATES.append(f"xval --xval-update: {label} in {os.path.relpath(path, self.root)}:"
                        f" {why}")

    def _rewrite(self, base, changed, settings) -> None:
        """``--xval-update``: record the changed runs again, as they were recorded (model,
        engine, settings with ``settings`` over them, request, tolerance)."""
        for c in changed:
            rec = c.record
            model = rec.model.name if rec.model.kind == "builtin" else \
                str(rec.model.path(base.base_dir))
            s = bl.settings_from_json(rec, str(base.path),
                                      _overrides(settings, [rec.engine]).get(rec.engine))
            # a free run's tolerances are the named ones of each quantity
            tol = rec.quantities[0].tolerance if rec.quantities and not rec.free else None
            why = c.problems[0] if c.problems else (c.failures() or c.loose())[0].message()
            self._record(base.path, model, rec.engine, s, rec.request, tol,
                         f"rewrote ({why})")


def _overrides(settings, engines, classes=None) -> dict:
    """``settings`` ({key: value}, applied to every engine that has the key) as
    per-engine overrides (:func:`sim_models.registry.split_overrides`)."""
    if not settings:
        return {}
    return overrides_for([f"{k}={_fmt_value(v)}" for k, v in dict(settings).items()], engines,
                         classes)


def failure_text(base, checks, factor: float, root: Path) -> str:
    """An ``assert_baseline`` failure: first line the worst failing quantity (its growth,
    the factor and where) or the run's problem, then the check's report of the failed
    runs, then how to record them again."""
    failed = [c for c in checks if not c.passed]
    worst = max(failed, key=lambda c: (not c.problems, *(_sev(c))))
    first = worst.problems[0] if worst.problems else worst.failures()[0].message()
    lines = report_lines(base, checks, factor)
    keep = [ln for ln in lines if not ln.startswith("pass ")]
    again = Baseline(tuple(c.record for c in failed), base.path, base.recorded)
    return "\n".join([f"{worst.record.label}: {first}", *keep,
                      "if the change is intended, record again: pytest --xval-update, or "
                      f"(from {root}): {record_command(again, root)}"])


def _sev(c) -> tuple:
    f = c.failures()
    return _severity(f[0]) if f else (0, 0.0)


def make_xval(config) -> Xval:
    """The ``xval`` fixture's object for a pytest config (its rootdir and options)."""
    return Xval(config.rootpath, config.getoption("--xval-factor") or DEFAULT_FACTOR,
                update=config.getoption("--xval-update"),
                fail_loose=config.getoption("--xval-fail-loose"))


def run_params(path, root: Path) -> list:
    """The ``xval_baseline`` fixture's parameters: one per recorded run (id
    ``case/engine``), or one carrying why the file cannot be used."""
    p = Path(path) if Path(path).is_absolute() else Path(root) / path
    if not p.exists():
        return [pytest.param(("error", f"xval: error: no baseline file {path} (ini option "
                             f"xval_baseline, under {root}); create it with: xval baseline "
                             f"record CASES_OR_FILES --engine ENGINE --out {path}"),
                             id="xval_baseline")]
    try:
        base = bl.load(p)
    except bl.BaselineError as e:
        return [pytest.param(("error", f"xval: error: {e}"), id="xval_baseline")]
    return [pytest.param(("run", r.key), id=f"{r.case}/{r.engine}" + ("/free" if r.free
                                                                        else ""))
            for r in base.runs]


def baseline_checker(xval: Xval, path: str, param):
    """``xval_baseline(case=None, engine=None, factor=None, settings=None)``: checks
    ``path`` (the ini option): the parametrised run, or the runs of ``case``/``engine``."""
    def check(case: str | None = None, engine: str | None = None, factor=None,
              settings=None):
        __tracebackhide__ = True
        if not path:
            raise pytest.UsageError("xval_baseline: set the ini option xval_baseline = "
                                    "path/to/baseline.json")
        key = None
        if param is not None:
            if param[0] == "error":
                pytest.fail(param[1], pytrace=False)
            if case is None and engine is None:
                key = param[1]
        return xval.assert_baseline(path, case=case, engine=engine, factor=factor,
                                    settings=settings, key=key)
    return check


def update_lines() -> list[str]:
    return list(_UPDATES)


def baseline_params(path, root: Path | None = None) -> list:
    """``pytest.param(case, engine, id="case/engine")`` for every run recorded in a
    baseline file (relative to ``root``, pytest's rootdir;
    :func:`xval_pytest_plugin.baseline_params` passes it):
    ``@pytest.mark.parametrize("case, engine", baseline_params(P))``."""
    p = Path(path)
    if root is not None and not p.is_absolute():
        p = Path(root) / p
    return [pytest.param(r.case, r.engine, id=f"{r.case}/{r.engine}") for r in load(p).runs]


__all__ = ["Xval", "XvalLooseWarning", "baseline_checker", "baseline_params", "cached_runner",
           "disagreement", "failure_text", "make_xval", "run_params", "session_run",
           "update_lines"]
