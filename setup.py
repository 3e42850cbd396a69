"""The build step that records the commit a wheel is built from (``xval --version``).

Everything else is in pyproject.toml.  ``build_py`` also writes ``reports/_build_info.py``
into the build folder (never into the checkout; the name is git-ignored in case a
``build_py --inplace`` writes it there): the abbreviated hash and committer date of the
checkout's HEAD, or empty when the source is not a git checkout (a source archive).  An
editable install asks git at run time instead (reports/cli/version.py)."""

import os
import subprocess

from setuptools import setup
from setuptools.command.build_py import build_py

#: The generated module, relative to the build folder.
BUILD_INFO = os.path.join("reports", "_build_info.py")


def build_info_source(root: str) -> str:
    """The text of ``reports/_build_info.py`` for the checkout at ``root``."""
    commit = date = ""
    if os.path.exists(os.path.join(root, ".git")):
        try:
            out = subprocess.run(["git", "-C", root, "log", "-1", "--format=%h %cs"],
                                 capture_output=True, text=True, timeout=30,
                                 check=True).stdout.split()
            commit, date = (out + ["", ""])[:2]
        except (OSError, subprocess.SubprocessError):
            pass
    return ('"""Written by setup.py when this copy was built (xval --version)."""\n\n'
            f"COMMIT = {commit!r}\nDATE = {date!r}\n")


def write_build_info(root: str, build_lib: str) -> str:
    """Write the generated module under ``build_lib``; its path."""
    path = os.path.join(build_lib, BUILD_INFO)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w", encoding="utf-8") as f:
        f.write(build_info_source(root))
    return path


class BuildPyWithCommit(build_py):
    """``build_py`` that also writes :data:`BUILD_INFO` (not in editable mode, where the
    checkout itself answers)."""

    def run(self):
        super().run()
        if not getattr(self, "editable_mode", False):
            write_build_info(os.path.dirname(os.path.abspath(__file__)), self.build_lib)


if __name__ == "__main__":
    setup(cmdclass={"build_py": BuildPyWithCommit})
