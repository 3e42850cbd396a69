"""``xval`` imports only what the command it runs needs, and ``analytic`` no table
library (the start-up of issue 23: building the parser had imported every engine,
pandas and pyarrow, 0.45 s before any command started)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

#: libraries none of these commands needs (engines, tables, plots, the compiler)
HEAVY = ("pandas", "pyarrow", "scipy", "numba", "matplotlib", "mujoco", "pybullet",
         "exudyn", "sim_models", "sympy")


def _imported(code: str) -> list[str]:
    """The top-level packages of HEAVY imported by running ``code`` in a fresh process."""
    prog = (code + "\nimport json, sys\n"
            f"print(json.dumps(sorted({{m.split('.')[0] for m in sys.modules}} & {set(HEAVY)!r})))")
    out = subprocess.run([sys.executable, "-c", prog], capture_output=True, text=True,
                         timeout=120, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


@pytest.mark.parametrize("argv", [["--help"], ["cases"], ["solve", "seed-four-bar", "--json"]])
def test_command_imports_only_what_it_runs(argv):
    code = ("import contextlib, io\nfrom reports.cli.xval import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            f"    try:\n        main({argv!r})\n    except SystemExit:\n        pass")
    assert _imported(code) == []


def test_analytic_imports_no_table_library():
    assert _imported("import analytic\nfrom analytic import stream, kinematics") == []


def test_help_lists_every_command_without_importing_it():
    from reports.cli.xval import COMMANDS
    out = subprocess.run([sys.executable, "-m", "reports.cli.xval", "--help"], capture_output=True,
                         text=True, timeout=120, check=True).stdout
    for name, (_, help_) in COMMANDS.items():
        assert name in out and help_.split()[0] in out, name


@pytest.mark.parametrize("argv", [["--help"], ["cases"]])
def test_help_and_cases_start_without_numpy_or_the_solver(argv):
    """``xval --help`` and ``xval cases`` read no array: neither numpy nor the solver's
    modules are imported (``analytic``'s front door loads its names on first use)."""
    code = ("import contextlib, io, json, sys\nfrom reports.cli.xval import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            f"    try:\n        main({argv!r})\n    except SystemExit:\n        pass\n"
            "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] == 'numpy'"
            " or m in ('analytic.kinematics', 'analytic.positions'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True).stdout
    assert json.loads(out.strip().splitlines()[-1]) == []


def test_case_description_is_what_load_case_reads():
    """``xval cases`` reads each description from the file's head; the mechanism that
    :func:`analytic.load_case` builds from the whole file carries the same text."""
    from analytic import load_case
    from analytic.cases import case_description, case_names, free_case_names, hard_case_names
    for name in case_names() + hard_case_names() + free_case_names():
        assert case_description(name) == load_case(name).description, name
