"""The CI recipe of docs/tutorials/regression-ci.md works verbatim from a fresh clone.

The section "The recipe" is copied as it stands into a new git repository outside the
checkout: each ``# file:`` block written, each ``$ `` command run in page order with the
page's expected status and output, beside a fresh clone of this repository at
``../linkage-xval`` (the committed HEAD, as a user's clone). The install resolves every
dependency into a fresh venv, as a user's job does: minutes, so the test is ``slow``.
"""

from __future__ import annotations

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
    console_steps,
    drift_message,
    fenced_blocks,
    file_target,
    output_matches,
)

PAGE = ROOT / "docs" / "tutorials" / "regression-ci.md"
SECTION = "## The recipe"

#: one recipe command (the install resolves MuJoCo, PyBullet, Exudyn, numba, ... into a fresh
#: venv: 3-5 min on a loaded 2-core machine)
RECIPE_COMMAND_TIMEOUT_S = 1200


def recipe_steps() -> list[FileWrite | Command]:
    """The files and commands of the page's recipe section, skip markers ignored."""
    text = PAGE.read_text(encoding="utf-8")
    start = text.index(SECTION)
    end = text.find("\n## ", start + len(SECTION))
    offset = text[:start].count("\n")
    steps: list[FileWrite | Command] = []
    for block in fenced_blocks(text[start:end if end >= 0 else None]):
        name = file_target(block)
        if name:
            steps.append(FileWrite(block.line + offset, name, block.text + "\n", False))
        elif block.lang == "console":
            steps.extend(console_steps(block, False))
    return steps


def test_the_recipe_section_has_files_and_commands():
    steps = recipe_steps()
    names = {s.name for s in steps if isinstance(s, FileWrite)}
    assert {"ci.sh", "requirements-ci.txt", "pytest.ini", "tests/test_linkages.py"} <= names
    commands = [s.command for s in steps if isinstance(s, Command)]
    assert commands and commands[-1] == "sh ci.sh"
    # issue 35: the recipe's first step used to check out a tag that does not exist
    assert not any("checkout v" in c or "@v0" in c for c in commands)


def _env() -> dict[str, str]:
    env = dict(os.environ)
    # the recipe makes its own venv; the test's venv is not put first on PATH, nor active
    venv = str(Path(sys.executable).parent)
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep)
                                  if p != venv)
    env.pop("VIRTUAL_ENV", None)
    env.pop("PYTHONPATH", None)
    env.update(COMMAND_ENV)
    env.update({"GIT_AUTHOR_NAME": "ci", "GIT_AUTHOR_EMAIL": "ci@example.org",
                "GIT_COMMITTER_NAME": "ci", "GIT_COMMITTER_EMAIL": "ci@example.org"})
    return env


def _fresh_clone(dest: Path) -> None:
    head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], check=True,
                          capture_output=True, text=True).stdout.strip()
    subprocess.run(["git", "clone", "-q", "--no-checkout", str(ROOT), str(dest)], check=True)
    subprocess.run(["git", "-C", str(dest), "checkout", "-q", head], check=True)


@pytest.mark.slow
def test_the_ci_recipe_runs_verbatim(tmp_path: Path):
    _fresh_clone(tmp_path / "linkage-xval")
    repo = tmp_path / "myproject"
    repo.mkdir()
    env = _env()
    subprocess.run(["git", "init", "-q"], cwd=repo, check=True, env=env)
    page = PAGE.relative_to(ROOT).as_posix()
    for step in recipe_steps():
        if isinstance(step, FileWrite):
            (repo / step.name).parent.mkdir(parents=True, exist_ok=True)
            (repo / step.name).write_text(step.text, encoding="utf-8")
            continue
        done = subprocess.run(["bash", "-c", step.command], cwd=repo, env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                              timeout=RECIPE_COMMAND_TIMEOUT_S, stdin=subprocess.DEVNULL)
        print(f"$ {step.command}\n{done.stdout}")
        if done.returncode != step.status or not output_matches(step.expected, done.stdout):
            pytest.fail(drift_message(page, step, done.stdout, done.returncode),
                        pytrace=False)
    assert (repo / "ci-out" / "xval-baseline.xml").is_file()
    assert (repo / "ci-out" / "pytest.xml").is_file()
