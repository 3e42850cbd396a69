"""``xval cases``: the built-in cases, the hard ones and the free-motion ones, each with
the first sentence of its description, whole, wrapped to the terminal.  Reads the case
files' heads only (no solver, no numpy)."""

from __future__ import annotations

import re
import shutil
import textwrap

from analytic.cases import case_description, case_names, free_case_names, hard_case_names

#: Width of the name column (the longest built-in name is 22 characters).
NAME_WIDTH = 24
#: The narrowest description column: a terminal narrower than the names plus this
#: wraps the description at this width anyway (a word is never cut).
MIN_TEXT_WIDTH = 30
#: A sentence ends at '.', '!' or '?' followed by white space (so 'lim.ii.udc.es' does
#: not end one), except after an abbreviation ('et al. 2006', 'e.g. x'), or at the end.
_SENTENCE_END = re.compile(r"(?<!\bal\.)(?<!\be\.g\.)(?<!\bi\.e\.)(?<!\bcf\.)(?<=[.!?])\s+")


def first_sentence(description: str) -> str:
    """The first sentence of ``description`` on one line (its line breaks as spaces)."""
    text = " ".join(description.split())
    return _SENTENCE_END.split(text, maxsplit=1)[0] if text else ""


def case_lines(name: str, description: str, width: int) -> list[str]:
    """``name`` and the first sentence of ``description``, wrapped to ``width`` columns
    under the description column; never a word cut."""
    text_width = max(width - NAME_WIDTH - 3, MIN_TEXT_WIDTH)
    body = textwrap.wrap(first_sentence(description), text_width,
                         break_long_words=False, break_on_hyphens=False) or [""]
    pad = " " * (NAME_WIDTH + 3)
    return [f"  {name:{NAME_WIDTH}s} {body[0]}"] + [pad + line for line in body[1:]]


def cmd_cases(args) -> int:
    width = shutil.get_terminal_size().columns
    for title, names in (("built-in cases", case_names()),
                         ("hard cases (numerical stability studies)", hard_case_names()),
                         ("free-motion cases (xval simulate)", free_case_names())):
        print(f"{title}:")
        for n in names:
            print("\n".join(case_lines(n, case_description(n), width)))
    return 0


def register(sub) -> None:
    """Add ``cases`` to ``xval``'s subparsers."""
    s = sub.add_parser("cases", help="list the built-in cases")
    s.set_defaults(func=cmd_cases)
