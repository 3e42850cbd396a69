"""Every example of README.md and docs/**/*.md runs, and prints what its page shows.

One test per page (its blocks in page order, in one temporary folder); a page with
``<!-- example: slow -->`` blocks gets a second test, marked ``slow``, that runs them all.
The convention is in tests/docs/examples.py (and DOCS_CONVENTIONS of issue 35).
"""

from __future__ import annotations

import doctest
import io
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.docs.examples import (
    COMMAND_ENV,
    ROOT,
    Command,
    FileWrite,
    PythonBlock,
    Step,
    documented_pages,
    drift_message,
    output_matches,
    page_steps,
)

#: a documented command that runs longer is a hang, not an example (the slow ones take ~1 min)
COMMAND_TIMEOUT_S = 600


def _cases() -> list:
    cases = []
    for page in documented_pages():
        steps = page_steps(page)
        if not steps:
            continue
        name = page.relative_to(ROOT).as_posix()
        if any(not s.slow for s in steps):
            cases.append(pytest.param(page, False, id=name))
        if any(s.slow for s in steps):
            cases.append(pytest.param(page, True, id=name + "[slow]", marks=pytest.mark.slow))
    return cases


def _env() -> dict[str, str]:
    """The test interpreter's xval first on PATH, a plain 80-column terminal."""
    env = dict(os.environ)
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    env.update(COMMAND_ENV)
    for key in ("FORCE_COLOR", "CLICOLOR_FORCE", "PYTEST_ADDOPTS", "PYTEST_XDIST_WORKER"):
        env.pop(key, None)
    return env


def _run_command(page: str, step: Command, folder: Path) -> None:
    try:
        done = subprocess.run(["bash", "-c", step.command], cwd=folder, env=_env(),
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                              timeout=COMMAND_TIMEOUT_S, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        pytest.fail(f"{page}:{step.line}: `$ {step.command}` ran past {COMMAND_TIMEOUT_S} s",
                    pytrace=False)
    if done.returncode != step.status or not output_matches(step.expected, done.stdout):
        pytest.fail(drift_message(page, step, done.stdout, done.returncode), pytrace=False)


def _run_python(page: str, step: PythonBlock, namespace: dict) -> None:
    if step.doctest:
        test = doctest.DocTestParser().get_doctest(step.source, namespace, page, page,
                                                   step.line - 1)
        test.globs = namespace          # the page's one namespace, kept between blocks
        report = io.StringIO()
        runner = doctest.DocTestRunner(
            optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
        result = runner.run(test, out=report.write, clear_globs=False)
        if result.failed:
            pytest.fail(f"{page}:{step.line}: doctest drifted from the page\n"
                        + report.getvalue(), pytrace=False)
        return
    try:
        exec(compile(step.source, f"{page}:{step.line}", "exec"), namespace)
    except Exception as exc:  # noqa: BLE001 - any failure of a documented snippet is a test failure
        pytest.fail(f"{page}:{step.line}: the Python block raised "
                    f"{type(exc).__name__}: {exc}", pytrace=False)


def run_page(page: Path, steps: list[Step], folder: Path, monkeypatch) -> None:
    """Run the steps in page order in `folder`."""
    name = page.relative_to(ROOT).as_posix()
    namespace: dict = {"__name__": "__docs__"}
    monkeypatch.chdir(folder)
    for step in steps:
        if isinstance(step, FileWrite):
            target = folder / step.name
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(step.text, encoding="utf-8")
        elif isinstance(step, Command):
            _run_command(name, step, folder)
        else:
            _run_python(name, step, namespace)


@pytest.mark.parametrize(("page", "with_slow"), _cases())
def test_page_examples(page: Path, with_slow: bool, tmp_path: Path, monkeypatch):
    steps = [s for s in page_steps(page) if with_slow or not s.slow]
    run_page(page, steps, tmp_path, monkeypatch)
