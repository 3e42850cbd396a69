"""Where the command line may write: file names made from a description's ``name``,
and no output that is one of the command's own inputs or another of its outputs.

Every check compares paths by what they are on disk (``os.path.samefile`` for files
that exist, the resolved absolute path otherwise), so ``F``, ``./F``, ``../d/F`` and a
symbolic link to ``F`` are one file.  A refusal is one line (``xval: error: ...``, status
2) before anything is written.
"""

from __future__ import annotations

import argparse
import os
import re
from collections.abc import Iterable
from pathlib import Path

from analytic.errors import OutputError

_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


def safe_stem(name: str) -> str:
    """A file-name stem from a description's ``name``: no folder separators, no
    absolute path, no control or other characters a file name should not carry (runs of
    them become ``_``), no leading dot (a hidden file, or ``..``).  ``../x`` gives
    ``x``; a name with nothing usable gives ``linkage``."""
    return _UNSAFE.sub("_", name).strip("._") or "linkage"


def _same(a: str | Path, b: str | Path) -> bool:
    try:
        if os.path.exists(a) and os.path.exists(b):
            return os.path.samefile(a, b)
        return Path(a).resolve() == Path(b).resolve()
    except OSError:  # unreadable, a loop of links: compare the names as given
        return os.path.abspath(a) == os.path.abspath(b)


def check_outputs(outputs: Iterable[tuple[str, str | Path | None]],
                  inputs: Iterable[tuple[str, str | Path | None]] = ()) -> None:
    """Refuse (one line, :class:`OutputError`) an output that is one of the inputs
    (``explain F --out F``) or that two outputs share (``--junit F --summary F``).

    ``outputs`` and ``inputs`` are ``(what, path)`` pairs, ``what`` as the user wrote it
    (``--out``, ``the case file``); a ``None`` path, ``-`` (standard output) or, among
    the inputs, a name that is not an existing file (a built-in case) is skipped."""
    outs = [(w, p) for w, p in outputs if p not in (None, "", "-")]
    ins = [(w, p) for w, p in inputs if p not in (None, "", "-") and os.path.isfile(p)]
    for i, (w, p) in enumerate(outs):
        for wi, q in ins:
            if _same(p, q):
                raise OutputError(f"{w} {str(p)!r} is {wi} {str(q)!r}: writing it would "
                                  "overwrite the input; give another file name")
        for w2, p2 in outs[i + 1:]:
            if _same(p, p2):
                raise OutputError(f"{w} and {w2} name the same file {str(p)!r}: one would "
                                  "overwrite the other; give two file names")


#: How a positional argument is named in a refusal (``dest`` -> words); others by dest.
_INPUT_NAMES = {"case": "the case file", "models": "the case file",
                "baseline": "the baseline"}


def _chosen_actions(parser, args):
    """Every argparse action of the (sub)command that ran: ``parser``'s own, then those
    of the subparser chosen at each level (``xval baseline check`` is two deep)."""
    for a in parser._actions:  # argparse keeps no public list of them
        if isinstance(a, argparse._SubParsersAction):
            chosen = a.choices.get(getattr(args, a.dest, None) or "")
            if chosen is not None:
                yield from _chosen_actions(chosen, args)
        else:
            yield a


def command_paths(parser, args) -> tuple[list, list]:
    """``(outputs, inputs)`` of a parsed command, as :func:`check_outputs` takes them:
    every option whose type is :func:`reports.cli.options.output_file` (``--out``,
    ``--csv``, ``--parquet``, ``--junit``, ``--summary``, ...) and every positional
    argument (the case file, the models, the baseline).  Read from the parser, so a
    new command or output option is checked without a line of its own."""
    from reports.cli.options import output_file
    outputs, inputs = [], []
    for a in _chosen_actions(parser, args):
        v = getattr(args, a.dest, None)
        if v is None:
            continue
        if a.type is output_file:
            outputs.append((a.option_strings[-1] if a.option_strings else a.dest, v))
        elif not a.option_strings:
            what = _INPUT_NAMES.get(a.dest, a.dest)
            vals = v if isinstance(v, (list, tuple)) else [v]
            inputs += [(what, x) for x in vals if isinstance(x, (str, os.PathLike))]
    return outputs, inputs


def check_command(parser, args) -> None:
    """:func:`check_outputs` on every output and input of a parsed command: called by
    ``xval``'s ``main`` for every command before it runs (one place, every door that
    writes a file)."""
    check_outputs(*command_paths(parser, args))


def write_csv(frame, path: str, stdout) -> None:
    """Write a table as CSV to ``path``, or to ``stdout`` when ``path`` is ``-``."""
    if path == "-":
        frame.to_csv(stdout, index=False)
        return
    try:
        frame.to_csv(path, index=False)
    except OSError as e:  # checked at the option; this is a race or a full disk
        raise OutputError(f"cannot write {path!r}: {e.strerror or e}") from None


__all__ = ["check_command", "check_outputs", "command_paths", "safe_stem", "write_csv"]
