"""Run the ``xval`` command in-process and capture what it prints (shared by the tests)."""

from __future__ import annotations

import io
from contextlib import redirect_stdout

from reports.cli.xval import main


def run(*argv) -> tuple[int, str]:
    """``xval ARGV...``: its exit status and standard output."""
    buf = io.StringIO()
    with redirect_stdout(buf):
        code = main(list(argv))
    return code, buf.getvalue()
