"""The README's two set-up commands are exactly what CI runs."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_ci_runs_the_readme_commands():
    readme = (ROOT / "README.md").read_text()
    block = re.search(r"## Set-up \(two commands\)\s+```sh\n(.*?)```", readme, re.S)
    assert block, "README has a Set-up block"
    commands = [ln for ln in block.group(1).splitlines() if ln.strip()]
    assert len(commands) == 2
    ci = [ln for ln in (ROOT / ".ci" / "run").read_text().splitlines()
          if ln.strip() and not ln.startswith(("#", "set ", "cd ", "command -v ", ".ci/"))]
    # (.ci/ scripts after the two commands are CI-only steps, e.g. .ci/wheel-check)
    assert ci == commands
