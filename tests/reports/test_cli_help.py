"""Every ``xval`` command's ``--help``: one plain line about the command, plain text (no
docstring markup), 80 columns, and an ``examples:`` block whose every line the real
parser accepts (issue 35: a newcomer reads --help, then copies an example)."""

from __future__ import annotations

import argparse
import contextlib
import io
import shlex

import pytest

from reports.cli.examples import EXAMPLES, TOUR
from reports.cli.xval import COMMANDS, build_parser, main

#: Every command and sub-command with a ``--help`` of its own.
HELPS = [(name,) for name in COMMANDS] + [("baseline", "record"), ("baseline", "check")]
#: Docstring markup that must not reach a terminal (reST roles, literals, emphasis).
MARKUP = ("`", ":func:", ":mod:", ":data:", ":class:", ":meth:", "**")
#: The narrowest terminal a help must fit.
COLUMNS = 80


def _help(*words: str) -> str:
    """``xval WORDS... --help``'s output, run in-process."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit) as end:
        main([*words, "--help"])
    assert end.value.code == 0
    return out.getvalue()


def _examples(text: str) -> list[str]:
    """The lines of the ``examples:`` block that ends ``text``."""
    head, sep, block = text.rpartition("\nexamples:\n")
    assert sep, "no examples: block"
    lines = [ln for ln in block.splitlines() if ln.strip()]
    assert all(ln.startswith("  xval ") for ln in lines), lines
    return [ln.strip() for ln in lines]


@pytest.fixture(autouse=True)
def _terminal(monkeypatch):
    monkeypatch.setenv("COLUMNS", str(COLUMNS))  # argparse wraps to $COLUMNS - 2


@pytest.mark.parametrize("words", [(), *HELPS], ids=lambda w: " ".join(w) or "xval")
def test_help_is_plain_fits_80_columns_and_ends_with_examples(words):
    text = _help(*words)
    for markup in MARKUP:
        assert markup not in text, markup
    wide = [ln for ln in text.splitlines() if len(ln) > COLUMNS]
    assert not wide, f"wider than {COLUMNS} columns: {wide}"
    examples = _examples(text)
    assert 1 <= len(examples) <= 5 if not words else 1 <= len(examples) <= 3, examples


@pytest.mark.parametrize("words", HELPS, ids=" ".join)
def test_command_help_starts_with_its_one_line(words):
    """Below the usage: the command's line, the one ``xval --help`` lists."""
    text = _help(*words)
    line = COMMANDS[words[0]][1] if len(words) == 1 else None
    first = text.split("\n\n")[1]
    assert "\n" not in first and first == (line or first)
    assert first and "`" not in first


@pytest.mark.parametrize("words", [(), *HELPS], ids=lambda w: " ".join(w) or "xval")
def test_every_example_is_accepted_by_the_parser(words, tmp_path, monkeypatch):
    """Each example line parsed by the real parser of its command (the files it names
    are read only when it runs: an example's files come from the ones before it)."""
    monkeypatch.chdir(tmp_path)
    run = []
    for example in _examples(_help(*words)):
        argv = shlex.split(example, comments=True)
        assert argv[0] == "xval" and argv[1] in COMMANDS, example
        args = build_parser(argv[1]).parse_args(argv[1:])
        assert callable(args.func), example
        run.append(argv[1:1 + len(words)])
    # a command's examples run it (one may first make the file it reads)
    assert not words or list(words) in run, f"no example runs xval {' '.join(words)}"


def test_the_tables_are_what_help_prints():
    """Every key of EXAMPLES is a command (or ``baseline record|check``), every command
    has one, and the top level's examples are the tour's."""
    assert set(EXAMPLES) == set(COMMANDS) | {"baseline record", "baseline check"}
    assert _examples(_help()) == list(TOUR)
    for key, lines in EXAMPLES.items():
        assert _examples(_help(*key.split())) == list(lines)


def test_a_rejected_example_fails_the_check():
    """The check can fail: a misspelt option is refused by the same parser."""
    with pytest.raises(Exception) as e:
        build_parser("solve").parse_args(["solve", "seed-four-bar", "--angel", "30"])
    assert isinstance(e.value, (argparse.ArgumentError, SystemExit)) or "--angel" in str(e.value)


@pytest.mark.parametrize("width", [60, 80, 120])
def test_cases_prints_each_description_to_the_end_of_a_sentence(width, monkeypatch):
    """``xval cases``: every case (built-in, hard, free) on its lines, its text read back
    from the output ends a sentence, no line is wider than the terminal, no word cut
    (every word of the output is a word of the case file's description)."""
    import os
    import shutil

    from analytic.cases import case_description, case_names, free_case_names, hard_case_names
    monkeypatch.setattr(shutil, "get_terminal_size", lambda *a, **k: os.terminal_size((width, 24)))
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["cases"]) == 0
    lines = out.getvalue().splitlines()
    assert all(len(ln) <= width for ln in lines)
    entries: dict[str, list[str]] = {}
    for ln in lines:
        if ln.startswith("  ") and not ln.startswith("   "):  # "  name  text"
            name, _, text = ln.strip().partition(" ")
            entries[name] = [text.strip()]
        elif ln.startswith("   "):
            entries[name].append(ln.strip())
    names = case_names() + hard_case_names() + free_case_names()
    assert sorted(entries) == sorted(names)
    for name, parts in entries.items():
        text = " ".join(parts)
        assert text.endswith((".", "!", "?")), f"{name}: {text!r}"
        assert set(text.split()) <= set(case_description(name).split()), name
