"""The ``xval`` command line: the command table, the parser, ``main``.

``xval --help`` lists every command of :data:`COMMANDS`; ``xval COMMAND ...`` imports
only ``COMMAND``'s module (``xval cases``: :mod:`reports.cli.cases`, ``xval solve`` and
``xval sweep``: :mod:`reports.cli.solve`, ...), which adds its options and does the work.

Exit status: 0 done; 1 a failed verdict (``xval compare``); 2 a user error (a bad
file, case, option or input value, an angle where the loops cannot close, a
singular position, an output file that cannot be written), reported as one line
on standard error that names the problem and where it is.  A closed output pipe
(``xval sweep ... | head``) ends quietly with status 141, as for SIGPIPE.  Any
other failure is a bug in xval.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import importlib
import os
import sys
import unicodedata

from analytic.errors import LinkageError
from analytic.perf import tune_allocator
from reports.cli import options as opt
from reports.cli.examples import TOUR, examples_text, help_kw
from reports.cli.paths import check_command

COMMANDS = {
    "cases": ("reports.cli.cases", "list the built-in cases"),
    "solve": ("reports.cli.solve", "solve one configuration (positions, rates, forces)"),
    "sweep": ("reports.cli.solve", "the full-cycle table (--csv or --parquet) and its events"),
    "explain": ("reports.cli.explain",
                "worked solution of one configuration, in the notes' method"),
    "models": ("reports.cli.models", "write the MJCF/URDF files of one case, or of all"),
    "compare": ("reports.cli.compare", "run engines and compare with the analytic solution"),
    "baseline": ("reports.cli.baseline", "record engine errors, later check them for drift"),
    "report": ("reports.cli.report", "the validation report (HTML, Markdown, CSV)"),
    "plot": ("reports.cli.plot", "curves over a cycle (engines optional), or of the free "
             "motion"),
    "animate": ("reports.cli.animate", "the linkage moving over a cycle or in free motion "
                "(GIF, MP4, HTML)"),
    "view": ("reports.cli.view", "MuJoCo's viewer on the linkage (needs a display)"),
    "simulate": ("reports.cli.simulate", "the exact released trajectory, optionally judged "
                 "in the engines"),
    "import": ("reports.cli.own_import", "read your own MJCF or URDF model and write its "
               "description"),
    "tune": ("reports.cli.tune", "the cheapest engine settings that pass a tolerance, "
             "verified"),
}

#: ``xval --help``'s groups of commands, in the order listed; every command of
#: :data:`COMMANDS` is in exactly one (tests/reports/test_hostile_turn5.py checks it).
GROUPS = (
    ("the analytic solver", ("cases", "solve", "sweep", "explain")),
    ("free motion", ("simulate",)),
    ("the engines against the solver", ("compare", "baseline", "report", "tune", "models")),
    ("your own engine model", ("import",)),
    ("figures and viewing", ("plot", "animate", "view")),
)

#: ``xval --help``'s text before the command list (plain text: no markup).
ABOUT = ("xval: cross-validation of planar linkage dynamics: the analytic vector-loop\n"
         "solver and the exact free motion, and the physics engines judged against them.")

#: ``xval --help``'s text after the command list.
EXIT_STATUS = (
    "Run 'xval COMMAND --help' for a command's options.\n\n"
    "Exit status: 0 done; 1 a failed verdict; 2 a user error (a bad file, case,\n"
    "option or input value, an angle where the loops cannot close, a singular\n"
    "position, an output file that cannot be written), reported as one line on\n"
    "standard error that names the problem and where it is; 141 when the reader of\n"
    "the output stops reading (xval sweep ... | head).  Any other failure is a bug\n"
    "in xval.")


def commands_text() -> str:
    """The command list of ``xval --help``: each group of :data:`GROUPS`, one plain line
    per command (its name and its line of :data:`COMMANDS`)."""
    width = max(len(n) for n in COMMANDS) + 2
    lines = []
    for title, names in GROUPS:
        lines.append(f"{title}:")
        lines += [f"  {n:<{width}}{COMMANDS[n][1]}" for n in names]
        lines.append("")
    return "\n".join(lines)


class _OnlyOne:
    """The subparsers as a module's ``register`` sees them: the command that runs gets
    its real parser, any other command the module adds a parser that is dropped."""

    def __init__(self, sub, name: str):
        self.sub, self.name = sub, name

    def add_parser(self, name, **kw):
        if name == self.name:  # its one line above its options, its examples below
            ours = help_kw(name, COMMANDS[name][1])
            if kw.get("epilog"):  # the command's own epilog (tune's JSON keys) before them
                ours["epilog"] = f"{kw['epilog']}\n\n{ours['epilog']}"
            return self.sub.add_parser(name, **{**kw, **ours})
        return argparse.ArgumentParser(prog=f"xval {name}", add_help=False)


class _Version(argparse.Action):
    """``--version``: reads the version and the commit only when asked (a subprocess of
    git in a checkout), so that no other command pays for it."""

    def __init__(self, option_strings, dest, **kw):
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS, **kw)

    def __call__(self, parser, namespace, values, option_string=None):
        from reports.cli.version import version_line
        print(version_line())
        parser.exit()


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """``xval``'s parser: every command listed with its help line (:data:`COMMANDS`, in the
    groups of :data:`GROUPS`);
    ``command``'s own options added by its module, the only one imported."""
    p = opt.OneLineParser(prog="xval", usage="xval [-h] [--version] COMMAND ...",
                          description=f"{ABOUT}\n\n{commands_text()}",
                          epilog=f"{EXIT_STATUS}\n\n{examples_text(TOUR)}",
                          formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--version", action=_Version, help="print the version and the commit "
                   "of this copy of xval, and exit")
    # the commands are listed in the description, grouped (commands_text); argparse's own
    # list of them (a brace of every name, then each again) is left out
    sub = p.add_subparsers(dest="cmd", required=True, metavar="COMMAND", prog="xval",
                           help=argparse.SUPPRESS)
    for name, (module, _help) in COMMANDS.items():
        if name != command:
            sub.add_parser(name, add_help=False)
            continue
        importlib.import_module(module).register(_OnlyOne(sub, name))
    return p


def _command(argv: list[str]) -> str | None:
    """The command ``argv`` runs (the first word; ``xval`` has no options of its own
    besides ``--help`` and ``--version``), or ``None``."""
    word = next((a for a in argv if not a.startswith("-")), None)
    return word if word in COMMANDS else None


def main(argv: list[str] | None = None) -> int:
    _setup_once()
    opt.forget_created_folders()
    try:
        argv = sys.argv[1:] if argv is None else list(argv)
        parser = _parser(_command(argv))
        args = parser.parse_args(argv)
        check_command(parser, args)  # no output on an input or on another output
        args.stdout = sys.stdout
        # with the table on standard output, the summary goes to standard error
        to_err = getattr(args, "csv", None) == "-"
        # numpy's floating-point warnings are not messages for a user: a non-finite
        # result is caught where it is written (JSON refuses NaN) or by the solver's checks
        with contextlib.redirect_stdout(sys.stderr) if to_err else contextlib.nullcontext(), \
                _quiet_numpy():
            code = args.func(args)
        sys.stdout.flush()  # a closed pipe shows here, inside the handler
        return code
    except LinkageError as e:  # every user error: one line, status 2
        opt.remove_created_folders()  # a refused command leaves no folder behind
        print(f"xval: error: {one_line(str(e))}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # the reader stopped reading (| head): end quietly
        _stdout_to_devnull()
        return 141


def one_line(text: str) -> str:
    """``text`` with every control character (a newline, a tab, an escape sequence in a
    file name or ``--set`` value the user typed) written as its Python escape (``\\n``,
    ``\\x1b``): an error message stays one line on any terminal, and shows what was typed.
    The one place every message of ``xval`` passes through before it is printed."""
    return "".join(ch.encode("unicode_escape").decode("ascii")
                   if unicodedata.category(ch) in ("Cc", "Cf", "Zl", "Zp") else ch
                   for ch in text)


def _quiet_numpy():
    """``numpy.errstate(all="ignore")`` when numpy is loaded (a command computing with
    arrays imports it with its module, before it runs); a command that does not load
    numpy (``xval cases``) cannot raise its warnings, and does not pay its import."""
    np = sys.modules.get("numpy")
    return np.errstate(all="ignore") if np is not None else contextlib.nullcontext()


@functools.cache
def _setup_once() -> None:
    """Once per process (``main`` may run many times in one, as in the tests)."""
    tune_allocator()  # large temporaries recycled, not re-mapped (see analytic/perf.py)


@functools.cache
def _parser(command: str | None) -> argparse.ArgumentParser:
    """The parser for ``command``, built once (parsing leaves no state in it)."""
    return build_parser(command)


def _stdout_to_devnull() -> None:
    """Point standard output at /dev/null so that the interpreter's final flush
    does not report the closed pipe again (the recipe of Python's signal docs)."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):  # replaced by a capture: nothing to do
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)


if __name__ == "__main__":
    sys.exit(main())
