"""The README is a short front door whose two set-up commands are exactly what CI runs, and
neither it nor the docs point at files a user of the repository does not have."""

from __future__ import annotations

import re
from pathlib import Path

from tests.docs.examples import documented_pages

ROOT = Path(__file__).resolve().parents[1]

#: issue 35: the README is a front door; the material lives in docs/
README_MAX_LINES = 300

#: files outside the repository (the project's private notes); a user has none of them
OUTSIDE_FILES = ("../shared", "shared/seeds", "REFERENCE.md", "ENGINE_NOTES.md")


def set_up_commands(readme: str) -> list[str]:
    block = re.search(r"## Set-up \(two commands\)\s+```sh\n(.*?)```", readme, re.S)
    assert block, "README has a Set-up block"
    return [ln for ln in block.group(1).splitlines() if ln.strip()]


def test_ci_runs_the_readme_commands():
    commands = set_up_commands((ROOT / "README.md").read_text())
    assert len(commands) == 2
    ci = [ln for ln in (ROOT / ".ci" / "run").read_text().splitlines()
          if ln.strip() and not ln.startswith(("#", "set ", "cd ", "command -v ", ".ci/"))]
    # (.ci/ scripts after the two commands are CI-only steps, e.g. .ci/wheel-check)
    assert ci == commands


def test_the_tests_run_on_every_core():
    # DOCS_CONVENTIONS: the second set-up command is the parallel test command
    assert set_up_commands((ROOT / "README.md").read_text())[1] == (
        ". .venv/bin/activate && pytest -n auto")


def test_readme_is_short_and_has_contents():
    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) <= README_MAX_LINES
    assert "## Contents" in readme
    # the contributor's fast subset is stated
    assert 'pytest -n auto -m "not slow"' in readme


def test_no_reference_to_files_outside_the_repository():
    hits = [f"{page.relative_to(ROOT)}:{n}: {word}"
            for page in documented_pages()
            for n, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1)
            for word in OUTSIDE_FILES if word in line]
    assert not hits, "\n".join(hits)


#: pages written by another part of issue 35 (DOCS_CONVENTIONS' fixed file names); the
#: docs build, with warnings as errors, checks that they exist after the merge
OTHER_PAGES = {"CHANGELOG.md"} | {f"docs/reference/{n}.md" for n in (
    "index", "cli", "toml", "json", "engines", "api", "cases", "exit-status")} | {
    f"docs/explanation/{n}.md" for n in (
        "index", "method", "tolerances", "engine-findings", "iftomm-results", "free-motion",
        "speed", "architecture")}


def test_readme_links_resolve():
    # relative links in the README are repository paths, which GitHub renders
    readme = (ROOT / "README.md").read_text()
    targets = {t for t in re.findall(r"\]\(([^)#]+?)\)", readme) if not t.startswith("http")}
    missing = sorted(t for t in targets if not (ROOT / t).exists() and t not in OTHER_PAGES)
    assert not missing, missing
