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

from analytic.errors import LinkageError
from analytic.perf import tune_allocator
from reports.cli import options as opt

COMMANDS = {
    "cases": ("reports.cli.cases", "list the built-in cases"),
    "solve": ("reports.cli.solve", "solve one configuration"),
    "sweep": ("reports.cli.solve", "full-cycle table"),
    "explain": ("reports.cli.explain",
                "worked solution of one configuration, in the notes' method"),
    "models": ("reports.cli.models", "write the MJCF/URDF files of one case, or of all"),
    "compare": ("reports.cli.compare", "run engines and compare with the analytic solution"),
    "baseline": ("reports.cli.baseline", "record engine errors, later check them for drift"),
    "report": ("reports.cli.report", "the validation report (HTML, Markdown, CSV)"),
    "plot": ("reports.cli.plot", "full-cycle curves of one linkage (engines optional), or "
             "its free motion against time"),
    "animate": ("reports.cli.animate", "the linkage moving through a cycle, or its free motion "
                "(GIF, MP4, HTML)"),
    "view": ("reports.cli.view", "MuJoCo's viewer on the linkage (needs a display)"),
    "simulate": ("reports.cli.simulate", "free motion: the exact released trajectory"),
    "tune": ("reports.cli.tune", "the cheapest engine settings that pass a tolerance, "
             "verified (writes settings files and tuned MJCF)"),
}



class _OnlyOne:
    """The subparsers as a module's ``register`` sees them: the command that runs gets
    its real parser, any other command the module adds a parser that is dropped."""

    def __init__(self, sub, name: str):
        self.sub, self.name = sub, name

    def add_parser(self, name, **kw):
        if name == self.name:
            return self.sub.add_parser(name, **kw)
        return argparse.ArgumentParser(prog=f"xval {name}", add_help=False)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """``xval``'s parser: every command listed with its help line (:data:`COMMANDS`);
    ``command``'s own options added by its module, the only one imported."""
    p = opt.OneLineParser(prog="xval", description=__doc__,
                          formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    for name, (module, help_) in COMMANDS.items():
        if name != command:
            sub.add_parser(name, help=help_, add_help=False)
            continue
        importlib.import_module(module).register(_OnlyOne(sub, name))
    return p


def _command(argv: list[str]) -> str | None:
    """The command ``argv`` runs (the first word; ``xval`` has no options of its own
    besides ``--help``), or ``None``."""
    word = next((a for a in argv if not a.startswith("-")), None)
    return word if word in COMMANDS else None


def main(argv: list[str] | None = None) -> int:
    _setup_once()
    try:
        argv = sys.argv[1:] if argv is None else list(argv)
        args = _parser(_command(argv)).parse_args(argv)
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
        print(f"xval: error: {e}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # the reader stopped reading (| head): end quietly
        _stdout_to_devnull()
        return 141


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
