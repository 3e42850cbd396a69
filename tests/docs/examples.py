"""The executed-example convention of README.md and docs/**/*.md (DOCS_CONVENTIONS, issue 35).

A page's fenced blocks become steps, run in page order in one temporary folder per page:

- ```` ```console ````: a line starting with ``$ `` is a command (bash; a line ending in
  ``\\`` continues on the next); the lines after it, up to the next ``$ ``, are its expected
  output, standard output and error merged. A command line ending in ``  # exit N``
  expects status N, else 0.
- ```` ```toml ```` / ```` ```xml ```` (and any other block) whose first line is
  ``# file: NAME`` (``<!-- file: NAME -->`` in XML) is written, as shown, to NAME in the
  page's folder before the next step; such a block is never executed.
- ```` ```python ````: starting with ``>>> ``, a doctest (ELLIPSIS, NORMALIZE_WHITESPACE);
  otherwise executed, and it must not raise. One namespace per page, cwd = the folder.
- ``<!-- example: skip -->`` on the line before a block: shown, never run (installs,
  clones, windows; the set-up commands and the CI recipe have their own tests).
  ``<!-- example: slow -->``: run only under the ``slow`` marker.
- Other languages (sh, text, json, ini, yaml, ...) are shown only.

Matching ignores trailing spaces and blank lines at both ends; a line ``...`` matches any
number of lines (none included), and ``...`` inside a line any text on that line.
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: environment of every documented command (the convention's: a plain 80-column terminal)
COMMAND_ENV = {"COLUMNS": "80", "NO_COLOR": "1", "TERM": "dumb"}

_FENCE = re.compile(r"^(?P<indent> {0,3})(?P<fence>`{3,}|~{3,})(?P<info>[^`]*)$")
_MARKER = re.compile(r"^\s*<!--\s*example:\s*(?P<kind>skip|slow)\s*-->\s*$")
_FILE = re.compile(r"^\s*(?:#|<!--)\s*file:\s*(?P<name>\S+)\s*(?:-->)?\s*$")
_EXIT = re.compile(r"\s+#\s*exit\s+(?P<status>\d+)\s*$")


@dataclass(frozen=True)
class Command:
    """One ``$ `` command of a console block and the output the page shows for it."""

    line: int           # 1-based line of the ``$ `` in the page
    command: str        # as bash runs it (continuations joined, the exit comment removed)
    expected: str       # the lines the page shows after it
    status: int         # the exit status the page expects
    slow: bool


@dataclass(frozen=True)
class FileWrite:
    """A block written as a file into the page's folder."""

    line: int
    name: str
    text: str
    slow: bool


@dataclass(frozen=True)
class PythonBlock:
    """A Python block: a doctest when it starts with ``>>> ``, else a script."""

    line: int
    source: str
    slow: bool

    @property
    def doctest(self) -> bool:
        return self.source.lstrip().startswith(">>> ")


Step = Command | FileWrite | PythonBlock


@dataclass(frozen=True)
class Fenced:
    """A fenced block of a page: its language, its text, the marker before it."""

    line: int           # 1-based line of the block's first content line
    lang: str
    text: str
    marker: str | None  # "skip", "slow" or None


def fenced_blocks(text: str) -> list[Fenced]:
    """Every fenced block of a Markdown page, nested indentation included (list items)."""
    lines = text.splitlines()
    blocks: list[Fenced] = []
    i = 0
    while i < len(lines):
        m = _FENCE.match(lines[i].rstrip()) or _FENCE.match(lines[i].strip())
        if not m:
            i += 1
            continue
        indent = len(lines[i]) - len(lines[i].lstrip())
        fence = m.group("fence")
        lang = m.group("info").strip().split(" ")[0] if m.group("info").strip() else ""
        prev = next((ln for ln in reversed(lines[:i]) if ln.strip()), "")
        mk = _MARKER.match(prev)
        body: list[str] = []
        j = i + 1
        while j < len(lines) and not (lines[j].strip().startswith(fence)
                                      and set(lines[j].strip()) == {fence[0]}):
            body.append(lines[j][indent:] if lines[j][:indent].strip() == "" else lines[j])
            j += 1
        blocks.append(Fenced(i + 2, lang, "\n".join(body), mk.group("kind") if mk else None))
        i = j + 1
    return blocks


def console_steps(block: Fenced, slow: bool) -> list[Command]:
    """The commands of a console block, each with the output lines that follow it."""
    steps: list[Command] = []
    lines = block.text.splitlines()
    i = 0
    while i < len(lines):
        if not lines[i].startswith("$ "):
            i += 1          # text before the first command: shown only
            continue
        start = i
        cmd = [lines[i][2:]]
        while cmd[-1].endswith("\\") and i + 1 < len(lines):
            i += 1
            cmd.append(lines[i])
        i += 1
        out: list[str] = []
        while i < len(lines) and not lines[i].startswith("$ "):
            out.append(lines[i])
            i += 1
        command = "\n".join(cmd)
        status = 0
        m = _EXIT.search(command)
        if m:
            status = int(m.group("status"))
            command = command[:m.start()]
        steps.append(Command(block.line + start, command, "\n".join(out), status, slow))
    return steps


def file_target(block: Fenced) -> str | None:
    """The NAME of a block whose first line is ``# file: NAME`` (``<!-- file: NAME -->``)."""
    first = block.text.splitlines()[0] if block.text else ""
    named = _FILE.match(first)
    return named.group("name") if named else None


def page_steps(path: Path) -> list[Step]:
    """The steps of one page, in page order (skipped blocks left out)."""
    steps: list[Step] = []
    for block in fenced_blocks(path.read_text(encoding="utf-8")):
        if block.marker == "skip":
            continue
        slow = block.marker == "slow"
        name = file_target(block)
        if name:
            steps.append(FileWrite(block.line, name, block.text + "\n", slow))
        elif block.lang == "console":
            steps.extend(console_steps(block, slow))
        elif block.lang in ("python", "py", "pycon"):
            steps.append(PythonBlock(block.line, block.text + "\n", slow))
    return steps


def documented_pages() -> list[Path]:
    """README.md and every Markdown page under docs/ (build output left out)."""
    docs = ROOT / "docs"
    pages = [ROOT / "README.md"]
    pages += sorted(p for p in docs.rglob("*.md")
                    if not {"_build", "auto_examples"} & set(p.relative_to(docs).parts))
    return pages


def _normalise(text: str) -> list[str]:
    lines = [ln.rstrip() for ln in text.replace("\r\n", "\n").split("\n")]
    while lines and not lines[0]:
        lines.pop(0)
    while lines and not lines[-1]:
        lines.pop()
    return lines


def _pattern(expected: list[str]) -> re.Pattern[str]:
    parts = []
    for ln in expected:
        if ln.strip() == "...":
            parts.append(r"(?:[^\n]*\n)*?")
        else:
            parts.append("[^\n]*".join(re.escape(piece) for piece in ln.split("...")) + r"\n")
    return re.compile("".join(parts))


def output_matches(expected: str, actual: str) -> bool:
    """Whether a command's output is what the page shows (the convention's ``...`` rules)."""
    want, got = _normalise(expected), _normalise(actual)
    return _pattern(want).fullmatch("".join(ln + "\n" for ln in got)) is not None


def _line_matches(expected: str, actual: str) -> bool:
    return _pattern([expected]).fullmatch(actual + "\n") is not None


def _next_match(line: str, got: list[str], start: int) -> int:
    """Where `line` matches in got[start:], else the most similar line (for the diff)."""
    for j in range(start, len(got)):
        if _line_matches(line, got[j]):
            return j
    ratios = [difflib.SequenceMatcher(None, line, g).ratio() for g in got[start:]]
    return start + ratios.index(max(ratios)) if ratios and max(ratios) > 0.6 else start


def _seen_through(want: list[str], got: list[str]) -> list[str]:
    """The output as the page's pattern sees it: the lines a `...` line stands for become
    that `...`, and a line that matches its pattern line becomes that line, so the diff
    shows only the lines that drifted."""
    out: list[str] = []
    i = 0
    for k, line in enumerate(want):
        if line.strip() == "...":
            following = next((w for w in want[k + 1:] if w.strip() != "..."), None)
            i = len(got) if following is None else _next_match(following, got, i)
            out.append(line)
        elif i < len(got):
            out.append(line if _line_matches(line, got[i]) else got[i])
            i += 1
    return out + got[i:]


def drift_message(page: str, step: Command, actual: str, status: int) -> str:
    """A readable failure: where, the command, the status, and a diff page -> actual (the
    lines the page's `...` stands for shown as `...`; the whole output follows)."""
    want, full = _normalise(step.expected), _normalise(actual)
    got = _seen_through(want, full)
    diff = difflib.unified_diff(want, got, f"{page}:{step.line} (the page)",
                                "the command's output", lineterm="", n=2)
    head = f"{page}:{step.line}: `$ {step.command}`"
    if status != step.status:
        head += f" exited with status {status}, the page expects {step.status}"
    else:
        head += " printed other output than the page shows"
    body = [*diff] if want != got else []
    return "\n".join([head, *body, "the whole output:", *full])
