"""The generated command-line reference (docs/_ext/xval_cli.py, the page
docs/reference/cli.md) lists every command, sub-command and option that ``xval``'s parser
has: read from the parser here, independently of the extension's own walk, and looked
for under each command of the extension's model of the page (no Sphinx needed) and in the
text of the nodes it puts on the page (with docutils, from the 'docs' extra)."""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

import pytest

from reports.cli.xval import COMMANDS, build_parser

EXT = Path(__file__).resolve().parents[2] / "docs" / "_ext" / "xval_cli.py"


def _extension():
    spec = importlib.util.spec_from_file_location("xval_cli_under_test", EXT)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # its dataclasses look their module up there
    spec.loader.exec_module(mod)
    return mod


def _page_text(ext) -> str:
    """The text of every node the ``xval-cli`` directive returns, as the page shows it
    (needs docutils, which comes with the 'docs' extra's Sphinx)."""
    pytest.importorskip("docutils")
    from docutils.frontend import get_default_settings
    from docutils.parsers.rst import Parser
    from docutils.utils import new_document

    document = new_document("cli.md", get_default_settings(Parser))
    return "\n".join(n.astext() for n in ext.cli_nodes(document))


def _parser_surface() -> tuple[set[str], set[str]]:
    """Every command path (``xval baseline record``) and every option string
    (``--engine``) of xval's parser, from argparse's own tables."""
    paths, options = set(), set()

    def walk(parser: argparse.ArgumentParser, path: str) -> None:
        paths.add(path)
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    walk(sub, f"{path} {name}")
            elif action.help != argparse.SUPPRESS:
                options.update(action.option_strings)

    for name in COMMANDS:
        top = build_parser(name)
        sub = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction))
        walk(sub.choices[name], f"xval {name}")
    return paths, options


@pytest.fixture(scope="module")
def page() -> str:
    return _page_text(_extension())


def test_every_command_and_subcommand_has_a_section(page):
    paths, _ = _parser_surface()
    assert {"xval solve", "xval baseline record", "xval baseline check"} <= paths
    missing = sorted(p for p in paths if p not in page)
    assert not missing, f"commands missing from the CLI reference: {missing}"


def test_every_option_is_listed(page):
    _, options = _parser_surface()
    assert {"--json", "--engine", "--set"} <= options
    missing = sorted(o for o in options if o not in page)
    assert not missing, f"options missing from the CLI reference: {missing}"


def _missing_per_command(ext) -> list[tuple[str, str]]:
    """(command, option) for each option of a command's parser that the extension does
    not list under that command (a flag listed under another command does not count)."""
    _, commands = ext.cli_model()
    listed = {}

    def index(cmd):
        listed[cmd.name] = {f for o in cmd.options for f in o.flags}
        for child in cmd.children:
            index(child)

    for cmd in commands:
        index(cmd)
    missing = []
    for name in COMMANDS:
        parser = build_parser(name)
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        own = {s for a in sub.choices[name]._actions if a.help != argparse.SUPPRESS
               for s in a.option_strings}
        missing += [(name, o) for o in sorted(own - listed.get(f"xval {name}", set()))]
    return missing


def test_each_command_section_lists_its_own_options():
    assert _missing_per_command(_extension()) == []


def test_the_check_can_fail(monkeypatch):
    """An extension that drops one option of one command is caught, although other
    commands list the same flag: the walk above is not the extension's own."""
    ext = _extension()
    real = ext._command

    def lossy(parser, path):
        cmd = real(parser, path)
        if path != ("solve",):
            return cmd
        return ext.Command(cmd.path, cmd.usage, cmd.description, cmd.epilog,
                           tuple(o for o in cmd.options if "--json" not in o.flags),
                           cmd.children)

    monkeypatch.setattr(ext, "_command", lossy)
    assert _missing_per_command(ext) == [("solve", "--json")]
