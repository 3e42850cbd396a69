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
one run (:mod:`reports.regression.run_cache`).  The project's own engine tests share this
cache.
"""

from __future__ import annotations

import os
import warnings
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import pytest

from analytic import load_case
from analytic.cases import case_names, free_case_names
from analytic.errors import LinkageError
from analytic.tolerances import ENGINE_RELATIVE
from reports.comparison.free_cases import command_case, free_case
from reports.comparison.quantities import judged
from reports.comparison.settings_file import read_settings_file
from reports.regression import baseline_check as bc
from reports.regression import baseline_record as br
from reports.regression import baseline_store as bs
from reports.regression import own_model as own
from reports.regression.baseline import DEFAULT_FACTOR, BaselineError, tolerance_problem
from reports.regression.baseline_free import free_request
from reports.regression.baseline_settings import (
    fmt_value,
    override_classes,
    overrides_for,
    settings_from_json,
    settings_line,
)
from reports.regression.messages import disagreement, failure_text
from reports.regression.run_cache import SESSION, RunCache, settings_of
from reports.studies.free_studies import free_verdict
from sim_models.engines.settings import SettingsError
from sim_models.own import DEFAULT_DURATION


@contextmanager
def one_line_errors():
    """A user error (a bad file, a value out of the command line's range) as one line
    failing the test that asked (``xval: error: ...``), as the command line says it."""
    __tracebackhide__ = True
    try:
        yield
    except LinkageError as e:
        pytest.fail(f"xval: error: {e}", pytrace=False)


class XvalLooseWarning(UserWarning):
    """An error shrank by more than the drift factor: the baseline no longer guards it."""


# ============================================================================ the fixture
class Xval:
    """The ``xval`` fixture.  Paths are relative to ``root`` (pytest's rootdir)."""

    def __init__(self, root: Path, factor: float, update: bool = False,
                 fail_loose: bool = False, runs: RunCache | None = None):
        self.root = Path(root)
        self.factor = factor
        self.update = update          # --xval-update: rewrite what changed
        self.fail_loose = fail_loose  # --xval-fail-loose
        self.runs = SESSION if runs is None else runs  # the session's run cache

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
        return self.runs.run(self.mechanism(model), engine, settings, revolutions, samples)

    def compare(self, model, engine: str = "mujoco", tolerance: float | None = None,
                settings=None, *, revolutions: int | None = None,
                samples: int | None = None, quantities=None, **own_read):
        """``(run, comparisons)``: the judged quantities (engine readings left out) at
        ``tolerance`` (relative to peak; default 1e-3), optionally only ``quantities``.
        A user's engine model (``.xml``, ``.urdf``) runs as it is, with its own options
        (``settings`` must be None), read with ``driver=``, ``keyframe=``, ``close=``
        (:class:`sim_models.own.Close` or ``(link_a, (x, y, z), link_b, (x, y, z))``)
        as ``xval import`` reads it."""

        __tracebackhide__ = True
        bad = None if tolerance is None else tolerance_problem(tolerance)
        if bad:  # the range of --tolerance and of a baseline file's tolerance
            pytest.fail(f"xval: error: tolerance={tolerance!r}: {bad}", pytrace=False)
        tol = ENGINE_RELATIVE if tolerance is None else float(tolerance)
        req = br.request_dict(revolutions, samples)
        if own.is_own_file(model):  # a user's engine model, run as it is
            run_, comps = self.runs.own_entry(self.resolve(model),
                                              _own_options(settings, own_read), engine, req)
            name = run_.case
        else:
            _no_own_read(model, own_read)
            mech = self.mechanism(model)
            e = self.runs.entry(mech, engine, settings_of(engine, settings), req)
            run_, comps, name = e["run"], judged(e["comparisons"]), mech.name
        comps = [replace(c, tolerance=tol, passed=bool(c.normalised <= tol)) for c in comps]
        if quantities is not None:
            want = [quantities] if isinstance(quantities, str) else list(quantities)
            have = {c.quantity for c in comps}
            unknown = [q for q in want if q not in have]
            if unknown:
                raise KeyError(f"{name}: no quantity {unknown[0]!r}; compared: "
                               f"{', '.join(sorted(have))}")
            comps = [c for c in comps if c.quantity in want]
        return run_, comps

    def assert_agrees(self, model, engine: str = "mujoco", tolerance: float | None = None,
                      settings=None, *, revolutions: int | None = None,
                      samples: int | None = None, quantities=None, **own_read):
        """Every judged quantity of ``model`` in ``engine`` within ``tolerance`` of its
        peak over the cycle (default 1e-3); returns the comparisons.  The failure message
        names each failing quantity, its error, where in the cycle, and the settings.
        A user's engine model: see :meth:`compare`."""
        __tracebackhide__ = True
        run_, comps = self.compare(model, engine, tolerance, settings,
                                   revolutions=revolutions, samples=samples,
                                   quantities=quantities, **own_read)
        if run_.ok and all(c.accepted for c in comps):  # a precision limit passes
            return comps
        tol = comps[0].tolerance if comps else (tolerance or 0.0)
        src = f" ({os.fspath(model)})" if isinstance(model, (str, os.PathLike)) and \
            os.fspath(model) != run_.case else ""
        text = f"{engine}: {run_.settings_text}" if own.is_own_file(model) else \
            settings_line(engine, run_.settings)
        raise AssertionError(disagreement(f"{run_.case}{src} / {engine}", run_, comps, tol,
                                          text))

    def assert_free_agrees(self, model, engine: str = "mujoco", *,
                           duration: float | None = None, samples: int = 200,
                           settings=None, **own_read):
        """Free motion: ``model`` (a case or file with ``[motion]``, or a driven one,
        released at rest under gravity) released in ``engine`` and judged against the
        exact trajectory (:func:`reports.comparison.free_compare.compare_free`); returns the
        :class:`FreeVerdict`.  ``duration`` (s) and ``samples`` (sample intervals: one
        fewer than ``xval simulate --samples``' sample times) in the command line's
        ranges, and a file without ``[motion]`` refused as ``xval simulate`` refuses it
        (only a built-in driven case is released under gravity): one line otherwise.
        The failure names each failing quantity, its trusted horizon, the nearest
        reference event and the engine's step.  A user's engine model (``.xml``,
        ``.urdf``) is released from its own state (``qpos0``, or ``keyframe=``) with its
        own options; ``samples`` intervals over ``duration`` (default 1 s), as
        ``xval simulate MODEL`` does."""
        __tracebackhide__ = True
        with one_line_errors():
            if own.is_own_file(model):
                req = free_request(DEFAULT_DURATION if duration is None else duration,
                                   int(samples) + 1)
                _, v = self.runs.own_entry(self.resolve(model),
                                           _own_options(settings, own_read), engine, req)
            else:
                _no_own_read(model, own_read)
                mech = self._free_mechanism(model, duration)
                if isinstance(settings, (str, os.PathLike)):  # a free settings file (tune)
                    settings = read_settings_file(settings, "free").overrides(engine)
                _, v = free_verdict(mech, engine, duration, samples, settings)
        if v.passed:
            return v
        lines = [f"{v.case} / {engine}: free motion over {v.duration:g} s disagrees "
                 f"(trusted horizon {v.horizon:.4g} s)"]
        lines += [f"  {c}" for c in v.judged if not c.passed]
        lines += [f"  {x}" for x in (v.near_event, v.step_note) if x]
        lines.append(f"  settings: {engine} {v.settings}")
        raise AssertionError("\n".join(lines))

    def _free_mechanism(self, model, duration):
        """``model`` as ``xval simulate`` takes it (:func:`command_case`): a file as it
        is (no ``[motion]``: refused when run), a built-in case without ``[motion]``
        released under gravity; a Mechanism as given."""
        if not isinstance(model, (str, os.PathLike)):
            return model
        name = os.fspath(model)
        if name in free_case_names():  # the IFToMM problems (A02 written when not shipped)
            return free_case(name, duration)
        return command_case(os.fspath(self.resolve(name)), duration)[0]

    # -- baselines ------------------------------------------------------------------
    def path(self, baseline) -> Path:
        p = Path(baseline)
        return p if p.is_absolute() else self.root / p

    def check_baseline(self, baseline, *, case: str | None = None, engine: str | None = None,
                       factor: float | None = None, settings=None, key=None):
        """``(Baseline, [RunCheck])`` of the recorded runs (those of ``case`` / ``engine``,
        or the one run ``key``); ``settings``: overrides of the recorded settings."""
        base = bs.load(self.path(baseline))
        model = self.resolve(case) if case is not None else None

        def keep(rec):
            same = case is None or case in (rec.case, rec.model.name) or (
                isinstance(model, Path) and rec.model.kind == "file"
                and rec.model.path(base.base_dir).resolve() == model.resolve())
            return (key is None or rec.key == tuple(key)) and same and \
                (engine is None or rec.engine == engine)
        checks = bc.check(base, factor or self.factor, runner=self.runs.runner, select=keep,
                          fail_loose=self.fail_loose,
                          overrides=_overrides(settings, [r.engine for r in base.runs],
                                               override_classes(base)))
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
        except LinkageError as e:  # an unusable file or value: one line, no traceback
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
                why: str, own_options: dict | None = None) -> None:
        """Record one run through the session cache and merge it into ``path``
        (``own_options``: a user's model's driver and keyframe)."""
        __tracebackhide__ = True
        s = settings_of(engine, settings)
        new = br.record([model], [engine], path, {engine: s}, request, tolerance,
                        runner=self.runs.runner, own_options=own_options)
        problems = br.record_problems(new)
        if problems:
            raise AssertionError(f"--xval-update: {problems[0]} (a baseline records a "
                                 "passing state; not written)")
        label = new.runs[0].label
        if path.exists():
            new, _ = br.merge(bs.load(path), new)
        bs.save(new)
        rel = os.path.relpath(path, self.root)
        self.runs.updates.append(f"xval --xval-update: {label} in {rel}: {why}")

    def _rewrite(self, base, changed, settings) -> None:
        """``--xval-update``: record the changed runs again, as they were recorded (model,
        engine, settings with ``settings`` over them, request, tolerance)."""
        for c in changed:
            rec = c.record
            model = rec.model.name if rec.model.kind == "builtin" else \
                str(rec.model.path(base.base_dir))
            s = settings_from_json(rec, str(base.path),
                                      _overrides(settings, [rec.engine]).get(rec.engine))
            # a free run's tolerances are the named ones of each quantity
            tol = rec.quantities[0].tolerance if rec.quantities and not rec.free else None
            why = c.problems[0] if c.problems else (c.failures() or c.loose())[0].message()
            self._record(base.path, model, rec.engine, s, rec.request, tol,
                         f"rewrote ({why})", own.recorded_options(rec.model.content))


def _overrides(settings, engines, classes=None) -> dict:
    """``settings`` ({key: value}, applied to every engine that has the key) as
    per-engine overrides (:func:`sim_models.engines.registry.split_overrides`)."""
    if not settings:
        return {}
    return overrides_for([f"{k}={fmt_value(v)}" for k, v in dict(settings).items()], engines,
                         classes)


def _own_options(settings, read: dict):
    """The import options of a user's model (``driver``, ``keyframe``, ``close``); it
    runs with its own options, so ``settings`` is refused."""
    from sim_models.own import Close
    if settings is not None:
        raise SettingsError("settings: a user's model runs with its own options; change "
                            "them in the file", "settings", settings)
    unknown = sorted(set(read) - {"driver", "keyframe", "close"})
    if unknown:
        raise TypeError(f"unexpected keyword argument {unknown[0]!r} (a user's model "
                        "takes driver=, keyframe=, close=)")
    closes = tuple(c if isinstance(c, Close) else Close(c[0], tuple(c[1]), c[2], tuple(c[3]))
                   for c in read.get("close", ()))
    return own.ImportOptions(read.get("driver"), read.get("keyframe"), closes)


def _no_own_read(model, read: dict) -> None:
    if read:
        raise TypeError(f"{model}: {', '.join(sorted(read))} apply to your own engine "
                        "models (.xml, .urdf) only")


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
        base = bs.load(p)
    except BaselineError as e:
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


def baseline_params(path, root: Path | None = None) -> list:
    """``pytest.param(case, engine, id="case/engine")`` for every run recorded in a
    baseline file (relative to ``root``, pytest's rootdir;
    :func:`xval_pytest_plugin.baseline_params` passes it):
    ``@pytest.mark.parametrize("case, engine", baseline_params(P))``."""
    p = Path(path)
    if root is not None and not p.is_absolute():
        p = Path(root) / p
    return [pytest.param(r.case, r.engine, id=f"{r.case}/{r.engine}") for r in bs.load(p).runs]


__all__ = ["Xval", "XvalLooseWarning", "baseline_checker", "baseline_params", "make_xval",
           "run_params"]
