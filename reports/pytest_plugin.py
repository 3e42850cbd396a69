"""pytest plugin: engine-against-analytic assertions and baseline checks in your own suite.

Installed with linkage-xval and registered through the ``pytest11`` entry point ``xval``
(``pyproject.toml``), so every pytest run in that environment has it; with plugin
autoloading off, load it with ``-p xval`` (or ``-p reports.pytest_plugin``)::

    def test_four_bar(xval):
        xval.assert_agrees("linkages/four_bar.toml", engine="mujoco", tolerance=1e-3)

    def test_no_drift(xval):
        xval.assert_baseline("tests/baselines/engines.json")      # every recorded run

A relative model or baseline path is relative to pytest's rootdir (the folder of your
``pytest.ini`` / ``pyproject.toml``); a name without ``.toml`` is a built-in case.

Runs are cached for the session, keyed by the mechanism's content, the engine, the
settings object and the run request: any number of assertions on one run cost one run
(:func:`session_run`).  The project's own engine tests share this cache.

Fixtures
--------
``xval`` (session): :class:`Xval` -- :meth:`Xval.assert_agrees`, :meth:`Xval.compare`,
:meth:`Xval.run`, :meth:`Xval.assert_baseline`.
``xval_baseline`` (session): checks the baseline file named by the ini option
``xval_baseline``: ``xval_baseline()`` or ``xval_baseline(case="six-bar", engine="mujoco")``.

Parametrise one test per recorded run with :func:`baseline_params`.
Option ``--xval-factor F`` sets the default drift factor (default 10).
"""

from __future__ import annotations

import hashlib
import math
import os
import time
from pathlib import Path

import pytest

#: (mechanism digest, engine, settings, request) -> {"run", "tree", "comparisons"} or
#: {"error": exception}: the session's runs.  Treat the cached runs as read-only.
_CACHE: dict[tuple, dict] = {}
_STATS = {"runs": 0, "hits": 0, "seconds": 0.0}


# ============================================================================ the cache
def _mech_digest(mech) -> str:
    """A digest of a mechanism's content (its dataclass repr is exact: floats repr
    round-trip), so a file loaded twice, by any path, or a built-in case loaded twice, is
    one key.  The file name (``source``, kept for error messages) is left out."""
    import copy
    bare = copy.copy(mech)  # no __post_init__: a shallow copy, not a new validation
    if getattr(bare, "source", None) is not None:
        object.__setattr__(bare, "source", None)
    return hashlib.sha256(repr(bare).encode()).hexdigest()


def _settings_of(engine: str, settings):
    """A settings object from None (recommended), a dict of overrides, or an object."""
    from sim_models.registry import get_engine
    eng = get_engine(engine)
    if settings is None:
        return eng.settings()
    if isinstance(settings, dict):
        return eng.settings(settings)
    return settings


def _request(revolutions=2, samples=36, max_violation=1e-3, max_speed_error=1e-2,
             chords="moving") -> dict:
    from reports.baseline import request_dict
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


def _make_run(mech, engine, settings, request) -> dict:
    from analytic.errors import LinkageError
    from reports.compare import compare_run
    from sim_models import compile_linkage
    from sim_models.engines import run
    t0 = time.perf_counter()
    _STATS["runs"] += 1
    try:
        tree = compile_linkage(mech, chords=request["chords"])
        r = run(tree, engine, settings, revolutions=request["revolutions"],
                samples=request["samples"], max_violation=request["max_violation"],
                max_speed_error=request["max_speed_error"])
        comps = compare_run(r, tree.linkage)
    except LinkageError as e:  # a refusal or nothing to compare: cached like a result
        return {"error": e}
    finally:
        _STATS["seconds"] += time.perf_counter() - t0
    return {"run": r, "tree": tree, "comparisons": comps}


def session_run(mech, engine: str, settings=None, revolutions: int = 2, samples: int = 36,
                max_violation: float = 1e-3, max_speed_error: float = 1e-2,
                chords: str = "moving"):
    """:func:`sim_models.engines.run` of a Mechanism, cached for the session (same
    arguments, same run object).  ``settings``: None, overrides or a settings object."""
    s = _settings_of(engine, settings)
    req = _request(revolutions, samples, max_violation, max_speed_error, chords)
    return _entry(mech, engine, s, req)["run"]


def cached_runner(mech, engine: str, settings, request: dict):
    """:data:`reports.baseline.Runner` on the session cache (baseline checks)."""
    from reports.baseline import judged
    e = _entry(mech, engine, settings, request)
    return e["run"], judged(e["comparisons"])


# ============================================================================ messages
def _at_text(run_, at: float) -> str:
    if not math.isfinite(at):
        return "at an unreached sample"
    unit = "m" if run_.extra.get("prismatic_driver") else "deg"
    return f"at input {at:.6g} {unit}"


def _unit(quantity: str, run_) -> str:
    """SI unit of a compared quantity (see :func:`reports.compare.compare_run`)."""
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
    bad = sorted((c for c in comps if not c.passed),
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

    def __init__(self, root: Path, factor: float):
        self.root = Path(root)
        self.factor = factor

    # -- models -----------------------------------------------------------------
    def resolve(self, model) -> Path | str:
        """A built-in case name as is; a path made absolute against the rootdir."""
        from analytic.cases import case_names
        if not isinstance(model, (str, os.PathLike)):
            return model
        s = os.fspath(model)
        if s in case_names():
            return s
        p = Path(s)
        return p if p.is_absolute() else self.root / p

    def mechanism(self, model):
        """A Mechanism from a case name, a TOML path or a Mechanism."""
        from analytic import load_case
        m = self.resolve(model)
        return m if not isinstance(m, (str, Path)) else load_case(str(m))

    # -- runs ---------------------------------------------------------------------
    def run(self, model, engine: str = "mujoco", settings=None, *, revolutions: int = 2,
            samples: int = 36):
        """The engine run (cached for the session)."""
        return session_run(self.mechanism(model), engine, settings, revolutions, samples)

    def compare(self, model, engine: str = "mujoco", tolerance: float | None = None,
                settings=None, *, revolutions: int = 2, samples: int = 36,
                quantities=None):
        """``(run, comparisons)``: the judged quantities (engine readings left out) at
        ``tolerance`` (relative to peak; default 1e-3), optionally only ``quantities``."""
        from dataclasses import replace

        from analytic.tolerances import ENGINE_RELATIVE
        from reports.baseline import judged
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
                      settings=None, *, revolutions: int = 2, samples: int = 36,
                      quantities=None):
        """Every judged quantity of ``model`` in ``engine`` within ``tolerance`` of its
        peak over the cycle (default 1e-3); returns the comparisons.  The failure message
        names each failing quantity, its error, where in the cycle, and the settings."""
        __tracebackhide__ = True
        from reports.baseline import settings_line
        run_, comps = self.compare(model, engine, tolerance, settings,
                                   revolutions=revolutions, samples=samples,
                                   quantities=quantities)
        if run_.ok and all(c.passed for c in comps):
            return comps
        tol = comps[0].tolerance if comps else (tolerance or 0.0)
        src = f" ({os.fspath(model)})" if isinstance(model, (str, os.PathLike)) and \
            os.fspath(model) != run_.case else ""
        raise AssertionError(disagreement(f"{run_.case}{src} / {engine}", run_, comps, tol,
                                          settings_line(engine, run_.settings)))

    # -- baselines ------------------------------------------------------------------
    def check_baseline(self, baseline, *, case: str | None = None, engine: str | None = None,
                       factor: float | None = None):
        """``(Baseline, [RunCheck])`` of the recorded runs (those of ``case`` / ``engine``)."""
        from reports import baseline as bl
        p = Path(baseline)
        base = bl.load(p if p.is_absolute() else self.root / p)

        def keep(rec):
            return (case is None or case in (rec.case, rec.model.name)) and \
                (engine is None or rec.engine == engine)
        checks = bl.check(base, factor or self.factor, runner=cached_runner, select=keep)
        if not checks:
            raise KeyError(f"{baseline}: no recorded run of case={case!r} engine={engine!r}")
        return base, checks

    def assert_baseline(self, baseline, *, case: str | None = None,
                        engine: str | None = None, factor: float | None = None):
        """Re-run the baseline's runs (cached) and fail on drift beyond ``factor``, a
        quantity over its tolerance, or a run, quantity or model gone or changed."""
        __tracebackhide__ = True
        from reports.baseline_cli import report_lines
        base, checks = self.check_baseline(baseline, case=case, engine=engine,
                                           factor=factor)
        if all(c.passed for c in checks):
            return checks
        from reports.baseline import record_command
        lines = report_lines(base, checks, factor or self.factor)
        keep = [ln for ln in lines if not ln.startswith("pass ")]
        keep.append("if the change is intended, record the baseline again (from "
                    f"{self.root}): {record_command(base, self.root)}")
        raise AssertionError("\n".join(keep))


def baseline_params(path) -> list:
    """``pytest.param((case, engine), id="case/engine")`` for every run recorded in a
    baseline file: ``@pytest.mark.parametrize("case, engine", baseline_params(P))``."""
    from reports.baseline import load
    return [pytest.param(r.case, r.engine, id=f"{r.case}/{r.engine}") for r in load(path).runs]


# ============================================================================ pytest hooks
def _factor_option(text: str) -> float:
    """``--xval-factor``: checked where pytest parses it (a finite number above 1), so a
    bad value is a usage error naming the option, never a silent default."""
    from reports.cli_options import drift_factor  # only when the option is given
    return drift_factor(text)


def pytest_addoption(parser) -> None:
    group = parser.getgroup("xval", "linkage-xval engine checks")
    group.addoption("--xval-factor", type=_factor_option, default=None,
                    help="default drift factor of xval baseline assertions (default 10)")
    parser.addini("xval_baseline", "baseline file checked by the xval_baseline fixture "
                  "(relative to the rootdir)", default="")


@pytest.fixture(scope="session")
def xval(pytestconfig) -> Xval:
    """Engine-against-analytic assertions with a session-wide run cache."""
    from reports.baseline import DEFAULT_FACTOR
    factor = pytestconfig.getoption("--xval-factor")
    factor = DEFAULT_FACTOR if factor is None else factor
    return Xval(pytestconfig.rootpath, factor)


@pytest.fixture(scope="session")
def xval_baseline(xval, pytestconfig):
    """``xval_baseline(case=None, engine=None)`` asserts the ini option ``xval_baseline``'s
    baseline file (all its runs, or those of one case / engine)."""
    path = pytestconfig.getini("xval_baseline")

    def check(case: str | None = None, engine: str | None = None, factor=None):
        __tracebackhide__ = True
        if not path:
            raise pytest.UsageError("xval_baseline: set the ini option xval_baseline = "
                                    "path/to/baseline.json")
        return xval.assert_baseline(path, case=case, engine=engine, factor=factor)
    return check


def pytest_terminal_summary(terminalreporter) -> None:
    if _STATS["runs"]:
        terminalreporter.write_line(
            f"xval: {_STATS['runs']} engine runs ({_STATS['seconds']:.1f} s), "
            f"{_STATS['hits']} served from the session cache")


__all__ = ["Xval", "baseline_params", "cached_runner", "disagreement", "session_run"]
