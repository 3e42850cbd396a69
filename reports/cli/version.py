"""``xval --version``: the version and the commit this copy of xval was made from.

The commit comes from, in order:

1. the git checkout this copy runs from (an editable install: ``pip install -e .``),
   asked at run time, so that it follows every later commit and checkout;
2. the module :mod:`reports._build_info` that ``setup.py``'s build step writes into a
   wheel built from a checkout (the installed copy has no ``.git``);
3. otherwise ``commit unknown`` (a wheel built from a source archive).

Only ``xval --version`` imports this module (no other command pays for git)."""

from __future__ import annotations

import importlib
import subprocess
from dataclasses import dataclass
from pathlib import Path

#: The distribution's name, for its version in the installed metadata.
DISTRIBUTION = "linkage-xval"
#: The checkout's root, when this file runs from one: reports/cli/version.py -> root.
ROOT = Path(__file__).resolve().parents[2]
#: Longest wait for ``git`` (a network file system, a huge repository): past it, the
#: commit is reported unknown rather than the command hanging.
GIT_TIMEOUT_S = 5.0


@dataclass(frozen=True)
class Commit:
    """A commit: its abbreviated hash and its committer date (ISO ``YYYY-MM-DD``, or
    ``""`` when only the hash is known)."""

    hash: str
    date: str = ""

    def text(self) -> str:
        return f"commit {self.hash}, {self.date}" if self.date else f"commit {self.hash}"


def version() -> str:
    """The installed distribution's version (``pyproject.toml``'s ``version``)."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as dist_version
    try:
        return dist_version(DISTRIBUTION)
    except PackageNotFoundError:  # run from a checkout that was never installed
        return "unknown version"


def checkout_commit(root: Path) -> Commit | None:
    """HEAD of the git checkout at ``root`` (its own ``.git``, a folder or a worktree's
    file; never a repository around it, such as a project that holds a venv), or
    ``None`` when ``root`` is not a checkout or git cannot answer."""
    if not (root / ".git").exists() or not (root / "pyproject.toml").is_file():
        return None
    try:
        out = subprocess.run(["git", "-C", str(root), "log", "-1", "--format=%h %cs"],
                             capture_output=True, text=True, timeout=GIT_TIMEOUT_S,
                             check=True).stdout.split()
    except (OSError, subprocess.SubprocessError):
        return head_from_files(root)  # no git program: read .git itself
    return Commit(out[0], out[1] if len(out) > 1 else "") if out else None


def head_from_files(root: Path) -> Commit | None:
    """HEAD's hash read from ``root/.git`` without git (a loose ref, a packed ref, or a
    detached HEAD); the date would need the object itself, so it is left out."""
    git = root / ".git"
    try:
        if git.is_file():  # a worktree: "gitdir: PATH"
            git = (root / git.read_text().split(":", 1)[1].strip()).resolve()
        common = git / "commondir"
        common = (git / common.read_text().strip()).resolve() if common.is_file() else git
        head = (git / "HEAD").read_text().strip()
        if not head.startswith("ref: "):
            return Commit(head[:7])
        ref = head[5:]
        for base in (git, common):
            if (base / ref).is_file():
                return Commit((base / ref).read_text().strip()[:7])
        for line in (common / "packed-refs").read_text().splitlines():
            if line.endswith(f" {ref}"):
                return Commit(line.split()[0][:7])
    except (OSError, IndexError):
        pass
    return None


def built_commit(module: str = "reports._build_info") -> Commit | None:
    """The commit recorded when the wheel was built (``setup.py``), or ``None``."""
    try:
        info = importlib.import_module(module)
    except ImportError:
        return None
    return Commit(info.COMMIT, getattr(info, "DATE", "")) if info.COMMIT else None


def version_line(root: Path | None = None, module: str = "reports._build_info") -> str:
    """``xval 0.1.0 (commit 49e6b7c, 2026-11-28)``, or ``(commit unknown)``: the commit of
    the checkout at ``root`` (default: the one this file is in, if any), else the one
    recorded in ``module`` at build time."""
    commit = checkout_commit(ROOT if root is None else root) or built_commit(module)
    return f"xval {version()} ({commit.text() if commit else 'commit unknown'})"
