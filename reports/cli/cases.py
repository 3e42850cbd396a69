"""``xval cases``: the built-in cases, the hard ones and the free-motion ones, each with
the first line of its description.  Reads the case files' heads only (no solver, no numpy)."""

from __future__ import annotations

import shutil

from analytic.cases import case_description, case_names, free_case_names, hard_case_names


def cmd_cases(args) -> int:
    width = shutil.get_terminal_size().columns
    for title, names in (("built-in cases", case_names()),
                         ("hard cases (numerical stability studies)", hard_case_names()),
                         ("free-motion cases (xval simulate)", free_case_names())):
        print(f"{title}:")
        for n in names:
            description = case_description(n).strip()
            first = description.splitlines()[0] if description else ""
            line = f"  {n:24s} {first}"
            # the description's first line, cut to the terminal (the name stays whole)
            print(line if len(line) <= width else line[:max(width - 3, 27)].rstrip() + "...")
    return 0


def register(sub) -> None:
    """Add ``cases`` to ``xval``'s subparsers."""
    s = sub.add_parser("cases", help="list the built-in cases")
    s.set_defaults(func=cmd_cases)
