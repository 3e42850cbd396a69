"""linkage-xval's pytest plugin: the ``pytest11`` entry point ``xval`` (README, "Engine
regressions in your CI").

Every pytest run in an environment where linkage-xval is installed loads this module, so
it imports nothing of the tool (no ``analytic``, ``sim_models``, ``reports``, numpy or
engine) until a fixture is used or a baseline is parametrised.  Its uniquely named
top-level module keeps a user's own ``reports``/``analytic``/``sim_models`` package from
breaking pytest's start-up: their tests run as before, and a test that uses an xval
fixture fails with one line naming the package that collides (:func:`collision`).

The fixtures, options, marker and hooks are here; the work is in
:mod:`reports.regression.pytest_plugin` (imported on first use).  Fixtures: ``xval`` (session)
and ``xval_baseline`` (one test per run recorded in the ini option ``xval_baseline``'s
file, ids ``case/engine``).  Options: ``--xval-factor F``, ``--xval-update``,
``--xval-fail-loose``, ``--xval-skip-engines``; marker ``xval_engine`` (added to every
test that uses an xval fixture).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

#: Where linkage-xval's packages sit beside this module (site-packages, or the checkout of
#: an editable install).
_HERE = Path(__file__).resolve().parent
_PACKAGES = ("analytic", "sim_models", "reports")
_FIXTURES = frozenset({"xval", "xval_baseline"})
#: The pytest config of this run (set at configure; rootdir-relative paths need it).
_CONFIG: list = []
#: Runs and seconds reported by xdist workers (summed into the summary line).
_WORKER_STATS: list[dict] = []


# ============================================================================ collisions
def collision() -> str | None:
    """One line naming the first of linkage-xval's top-level packages that would not be
    imported from linkage-xval (a user's package of that name earlier on ``sys.path``,
    or already imported), else None.  Looks up, does not import."""
    for name in _PACKAGES:
        ours = _HERE / name / "__init__.py"
        mod = sys.modules.get(name)
        if mod is not None:
            where = getattr(mod, "__file__", None)
        else:
            try:
                spec = importlib.util.find_spec(name)
            except (ImportError, ValueError):
                spec = None
            where = spec.origin if spec is not None else None
        if where is None or Path(where).resolve() != ours.resolve():
            return (f"xval: error: package name collision: {name!r} is imported from "
                    f"{where or 'a namespace package'}, not from linkage-xval "
                    f"({ours.parent}); the xval fixtures need linkage-xval's {name!r}, so "
                    f"run them where your own {name!r} is not on sys.path (tests that do "
                    "not use xval are unaffected)")
    return None


def impl():
    """:mod:`reports.regression.pytest_plugin`, imported on first use (one-line failure on a
    collision, never an import error deep in the tool)."""
    msg = collision()
    if msg:
        pytest.fail(msg, pytrace=False)
    from reports.regression import pytest_plugin
    return pytest_plugin


def rootdir() -> Path:
    """pytest's rootdir in this run (the current folder outside a pytest run)."""
    return Path(_CONFIG[0].rootpath) if _CONFIG else Path.cwd()


def baseline_params(path) -> list:
    """``pytest.param(case, engine, id="case/engine")`` for every run recorded in a
    baseline file (a relative path is relative to pytest's rootdir):
    ``@pytest.mark.parametrize("case, engine", baseline_params(P))``."""
    return impl().baseline_params(path, rootdir())


# ============================================================================ options
def _factor(text: str) -> float:
    """``--xval-factor``: a finite number above 1 (an error may grow by this factor)."""
    import argparse
    import math
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (math.isfinite(v) and v > 1):
        raise argparse.ArgumentTypeError(f"{text} is out of range: the drift factor must "
                                         "be a finite number above 1")
    return v


def pytest_addoption(parser) -> None:
    group = parser.getgroup("xval", "linkage-xval engine checks")
    group.addoption("--xval-factor", type=_factor, default=None, metavar="F",
                    help="default drift factor of xval baseline assertions (above 1; "
                         "default 10)")
    group.addoption("--xval-update", action="store_true", default=False,
                    help="rewrite the recorded runs that changed (drift, a changed model, a "
                         "loose baseline) and create missing baseline files, instead of "
                         "failing; the summary names each rewritten run")
    group.addoption("--xval-fail-loose", action="store_true", default=False,
                    help="fail, not warn, when an error improved by more than the drift "
                         "factor (the baseline is loose; re-record)")
    group.addoption("--xval-skip-engines", action="store_true", default=False,
                    help="skip every test that uses an xval fixture (marker xval_engine)")
    parser.addini("xval_baseline", "baseline file checked by the xval_baseline fixture "
                  "(relative to the rootdir)", default="")
    parser.addini("xval_per_run", "xval_baseline: one test per recorded run, ids "
                  "case/engine (default true)", type="bool", default=True)


def pytest_configure(config) -> None:
    _CONFIG[:] = [config]
    config.addinivalue_line("markers", "xval_engine: runs engines through an xval fixture "
                            "(select with -m xval_engine, skip with --xval-skip-engines)")


# ============================================================================ collection
def pytest_generate_tests(metafunc) -> None:
    """One test per recorded run of the ini option's baseline (``xval_per_run``)."""
    if "xval_baseline" not in metafunc.fixturenames:
        return
    cfg = metafunc.config
    path = cfg.getini("xval_baseline")
    if not path or not cfg.getini("xval_per_run"):
        return
    msg = collision()
    if msg:
        params = [pytest.param(("error", msg), id="xval")]
    else:
        params = impl().run_params(path, Path(cfg.rootpath))
    metafunc.parametrize("xval_baseline", params, indirect=True)


@pytest.hookimpl(tryfirst=True)  # before -m deselects by marker
def pytest_collection_modifyitems(config, items) -> None:
    skip = config.getoption("--xval-skip-engines")
    for item in items:
        if _FIXTURES & set(getattr(item, "fixturenames", ())):
            item.add_marker("xval_engine")
        if skip and item.get_closest_marker("xval_engine"):
            item.add_marker(pytest.mark.skip(reason="--xval-skip-engines"))


# ============================================================================ fixtures
@pytest.fixture(scope="session")
def xval(pytestconfig):
    """Engine-against-analytic assertions with a session-wide run cache
    (:class:`reports.regression.pytest_plugin.Xval`,
    :mod:`reports.regression.run_cache`)."""
    return impl().make_xval(pytestconfig)


@pytest.fixture
def xval_baseline(xval, pytestconfig, request):
    """``xval_baseline(case=None, engine=None, factor=None, settings=None)`` checks the
    ini option ``xval_baseline``'s file: the run this test was generated for (one test
    per recorded run), or the runs of ``case`` / ``engine``."""
    return impl().baseline_checker(xval, pytestconfig.getini("xval_baseline"),
                                   getattr(request, "param", None))


# ============================================================================ summary
def _session_runs():
    """The session's run cache (:data:`reports.regression.run_cache.SESSION`), None when
    nothing of the tool was used (then there is nothing to report, and nothing imported)."""
    mod = sys.modules.get("reports.regression.run_cache")
    return mod.SESSION if mod is not None else None


def pytest_sessionfinish(session) -> None:
    """An xdist worker hands its run count to the controller (``workeroutput``)."""
    out = getattr(session.config, "workeroutput", None)
    runs = _session_runs()
    if out is not None and runs is not None:
        out["xval_stats"] = dict(runs.stats)


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node, error) -> None:
    """xdist: collect each worker's run count for the summary."""
    stats = getattr(node, "workeroutput", {}).get("xval_stats")
    if stats:
        _WORKER_STATS.append(stats)


def pytest_terminal_summary(terminalreporter) -> None:
    runs_ = _session_runs()
    stats = [dict(runs_.stats)] if runs_ is not None else []
    stats += _WORKER_STATS
    runs = sum(s["runs"] for s in stats)
    if runs:
        per = f" in {len(_WORKER_STATS)} xdist workers, each with its own cache" \
            if _WORKER_STATS else ""
        terminalreporter.write_line(
            f"xval: {runs} engine runs ({sum(s['seconds'] for s in stats):.1f} s){per}, "
            f"{sum(s['hits'] for s in stats)} served from the session cache")
    for line in (list(runs_.updates) if runs_ is not None else []):
        terminalreporter.write_line(line)
