"""Where the command line may write: file names made from a description's ``name``,
and no output that is one of the command's own inputs or another of its outputs.

Every check compares paths by what they are on disk (``os.path.samefile`` for files
that exist, the resolved absolute path otherwise), so ``F``, ``./F``, ``../d/F`` and a
symbolic link to ``F`` are one file.  A refusal is one line (``xval: error: ...``, status
2) before anything is written.
"""

from __future__ import annotations

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


def write_csv(frame, path: str, stdout) -> None:
    """Write a table as CSV to ``path``, or to ``stdout`` when ``path`` is ``-``."""
    if path == "-":
        frame.to_csv(stdout, index=False)
        return
    try:
        frame.to_csv(path, index=False)
    except OSError as e:  # checked at the option; this is a race or a full disk
        raise OutputError(f"cannot write {path!r}: {e.strerror or e}") from None


__all__ = ["check_outputs", "safe_stem", "write_csv"]
