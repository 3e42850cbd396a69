"""``xval --version``: the version and the commit, from the git checkout at run time (an
editable install) or from the module setup.py writes into a wheel, else ``commit
unknown`` (issue 35).  The expected hashes come from git itself."""

from __future__ import annotations

import contextlib
import io
import re
import runpy
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from reports.cli import version as v
from reports.cli.xval import main

ROOT = Path(__file__).resolve().parents[2]
HAS_GIT = shutil.which("git") is not None
needs_checkout = pytest.mark.skipif(not (HAS_GIT and (ROOT / ".git").exists()),
                                    reason="not run from a git checkout")


def _git(repo: Path, *args: str) -> str:
    return subprocess.run(["git", "-C", str(repo), *args], capture_output=True, text=True,
                          check=True).stdout.strip()


def _version() -> str:
    from importlib.metadata import version
    return version("linkage-xval")


@needs_checkout
def test_version_in_a_checkout_names_its_head():
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit) as end:
        main(["--version"])
    assert end.value.code == 0
    head = _git(ROOT, "log", "-1", "--format=%h %cs").split()
    assert out.getvalue().strip() == f"xval {_version()} (commit {head[0]}, {head[1]})"


@needs_checkout
def test_head_read_from_the_files_without_git():
    """The fallback when no git program runs: a worktree's ``.git`` file, a loose ref."""
    commit = v.head_from_files(ROOT)
    assert commit is not None and _git(ROOT, "rev-parse", "HEAD").startswith(commit.hash)


@pytest.mark.skipif(not HAS_GIT, reason="needs git")
def test_head_from_packed_and_detached_refs(tmp_path):
    repo = tmp_path / "repo"
    repo.mkdir()
    for args in (("init", "-q"), ("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q",
                                  "--allow-empty", "-m", "one")):
        _git(repo, *args)
    full = _git(repo, "rev-parse", "HEAD")
    _git(repo, "pack-refs", "--all")  # the branch now only in packed-refs
    assert v.head_from_files(repo).hash == full[:7]
    _git(repo, "checkout", "-q", "--detach")
    assert v.head_from_files(repo).hash == full[:7]


def test_a_repository_around_the_install_is_not_its_commit(tmp_path):
    """A wheel installed in a venv inside the user's own repository: that repository's
    HEAD is not xval's commit (only a checkout of xval itself, with its pyproject)."""
    (tmp_path / ".git").mkdir()
    assert v.checkout_commit(tmp_path) is None


def _built(tmp_path: Path, source: Path) -> str:
    """Write the build module as setup.py's build step does, for the checkout at
    ``source``, into a build folder under ``tmp_path``; the name to import it by."""
    hook = runpy.run_path(str(ROOT / "setup.py"), run_name="setup_under_test")
    path = Path(hook["write_build_info"](str(source), str(tmp_path / "build")))
    assert path == tmp_path / "build" / "reports" / "_build_info.py"
    name = f"xval_build_info_{abs(hash(str(tmp_path)))}"
    shutil.copy(path, tmp_path / f"{name}.py")
    return name


@needs_checkout
def test_a_wheel_reports_the_commit_it_was_built_from(tmp_path, monkeypatch):
    name = _built(tmp_path, ROOT)
    monkeypatch.syspath_prepend(str(tmp_path))
    head = _git(ROOT, "log", "-1", "--format=%h %cs").split()
    # installed: no checkout around the package (tmp_path has no .git)
    line = v.version_line(root=tmp_path, module=name)
    assert line == f"xval {_version()} (commit {head[0]}, {head[1]})"
    sys.modules.pop(name, None)


def test_a_wheel_built_from_a_source_archive_says_commit_unknown(tmp_path, monkeypatch):
    archive = tmp_path / "linkage-xval-0.1.0"  # no .git
    archive.mkdir()
    name = _built(tmp_path, archive)
    monkeypatch.syspath_prepend(str(tmp_path))
    assert v.built_commit(name) is None
    assert re.fullmatch(r"xval \S+ \(commit unknown\)", v.version_line(root=archive,
                                                                       module=name))
    sys.modules.pop(name, None)


def test_other_commands_do_not_load_the_version_module():
    code = ("import contextlib, io, sys\nfrom reports.cli.xval import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    for argv in (['--help'], ['cases']):\n"
            "        try:\n            main(argv)\n        except SystemExit:\n            pass\n"
            "print('reports.cli.version' in sys.modules, 'importlib.metadata' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True).stdout.split()
    assert out[-2] == "False"
