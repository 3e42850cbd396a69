"""Sphinx extension: the command-line reference, generated from ``xval``'s own parser.

The directive ``xval-cli`` (used by ``docs/reference/cli.md``) builds the parser of every
command of :data:`reports.cli.xval.COMMANDS` exactly as ``xval COMMAND`` builds it
(:func:`reports.cli.xval.build_parser`), walks its actions (sub-commands such as
``xval baseline record`` included) and writes, per command, its usage, its description,
its epilog (the examples) and one row per option.  Nothing is copied by hand, so the page
cannot drift from the parser; ``tests/docs/test_cli_reference.py`` checks that every
sub-command and option the parser has is on the page.
"""

from __future__ import annotations

import argparse
import contextlib
import os
from dataclasses import dataclass, field

# docutils and Sphinx are imported where the page is built (the 'docs' extra), so that
# the model of the parser (cli_model) and its test run without them


@dataclass(frozen=True)
class Option:
    """One argument of a command: its flags (or its name, for a positional one), the
    metavar it takes, its help line and its default."""

    flags: tuple[str, ...]
    metavar: str
    help: str
    default: str


@dataclass(frozen=True)
class Command:
    """One command or sub-command (``("baseline", "record")``) and what its parser says."""

    path: tuple[str, ...]
    usage: str
    description: str
    epilog: str
    options: tuple[Option, ...]
    children: tuple[Command, ...] = field(default=())

    @property
    def name(self) -> str:
        return " ".join(("xval",) + self.path)


def _help_text(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    """``action``'s help with argparse's ``%(default)s``-style fields filled in."""
    if not action.help:
        return ""
    try:
        return parser._get_formatter()._expand_help(action)  # argparse's own expansion
    except (KeyError, TypeError, ValueError):
        return action.help


def _metavar(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    if action.nargs == 0:
        return ""
    fmt = parser._get_formatter()
    if action.option_strings:
        return fmt._format_args(action, action.dest.upper())
    return fmt._format_args(action, action.dest)


def _default(action: argparse.Action) -> str:
    d = action.default
    if action.nargs == 0 or d is None or d is argparse.SUPPRESS or d == []:
        return ""
    return str(d)


def _command(parser: argparse.ArgumentParser, path: tuple[str, ...]) -> Command:
    """The command ``path`` as ``parser`` (its own parser) describes it, recursively."""
    options, children = [], []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                children.append(_command(sub, path + (name,)))
            continue
        if action.help == argparse.SUPPRESS:
            continue
        flags = tuple(action.option_strings) or (action.metavar or action.dest,)
        options.append(Option(flags, _metavar(parser, action), _help_text(parser, action),
                              _default(action)))
    return Command(path, parser.format_usage().strip(), parser.description or "",
                   parser.epilog or "", tuple(options), tuple(children))


def _subparser(parser: argparse.ArgumentParser, name: str) -> argparse.ArgumentParser:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action.choices[name]
    raise LookupError(f"xval's parser has no sub-command {name!r}")


def cli_model() -> tuple[Command, list[Command]]:
    """``xval`` itself and each command of ``COMMANDS``, each from its own parser."""
    from reports.cli.xval import COMMANDS, build_parser

    # argparse wraps usage lines at the terminal's width: the page is 80 columns wide
    # whatever terminal builds it, as xval's help is in an 80-column terminal
    with _columns(80):
        return _model(COMMANDS, build_parser)


@contextlib.contextmanager
def _columns(width: int):
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = str(width)
    try:
        yield
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old


def _model(COMMANDS, build_parser) -> tuple[Command, list[Command]]:  # noqa: N803
    top = build_parser(None)
    root = Command((), top.format_usage().strip(), top.description or "", top.epilog or "",
                   ())
    commands = [_command(_subparser(build_parser(name), name), (name,)) for name in COMMANDS]
    return root, commands


# ------------------------------------------------------------------------------ nodes
def _section(title: str, document):
    from docutils import nodes

    sec = nodes.section()
    sec["ids"].append(nodes.make_id(title))
    sec["names"].append(nodes.fully_normalize_name(title))
    sec += nodes.title(title, "", nodes.literal(title, title))
    document.note_implicit_target(sec, sec)
    return sec


def _text_block(text: str):
    from docutils import nodes

    block = nodes.literal_block(text, text)
    block["language"] = "text"
    return block


def _options_table(cmd: Command):
    from docutils import nodes

    table = nodes.table()
    group = nodes.tgroup(cols=3)
    table += group
    for width in (30, 15, 55):
        group += nodes.colspec(colwidth=width)
    head = nodes.thead()
    group += head
    row = nodes.row()
    for text in ("option", "default", "what it does"):
        row += nodes.entry("", nodes.paragraph(text=text))
    head += row
    body = nodes.tbody()
    group += body
    for opt in cmd.options:
        row = nodes.row()
        usage = ", ".join(f + (f" {opt.metavar}" if opt.metavar and f.startswith("-") else "")
                          for f in opt.flags)
        row += nodes.entry("", nodes.paragraph("", "", nodes.literal(usage, usage)))
        row += nodes.entry("", nodes.paragraph(text=opt.default))
        row += nodes.entry("", nodes.paragraph(text=opt.help))
        body += row
    return table


def command_nodes(cmd: Command, document):
    """One command's section: usage, description, examples (the epilog), options table,
    then a section per sub-command."""
    sec = _section(cmd.name, document)
    sec += _text_block(cmd.usage)
    if cmd.description:
        sec += _text_block(cmd.description)
    if cmd.options:
        sec += _options_table(cmd)
    if cmd.epilog:
        sec += _text_block(cmd.epilog)
    for child in cmd.children:
        sec += command_nodes(child, document)
    return sec


def cli_nodes(document) -> list:
    """The whole reference: ``xval --help``'s text, then a section per command."""
    root, commands = cli_model()
    out: list = [_text_block("\n\n".join(
        t for t in (root.usage, root.description, root.epilog) if t))]
    out += [command_nodes(c, document) for c in commands]
    return out


def setup(app):
    from sphinx.util.docutils import SphinxDirective

    class XvalCliDirective(SphinxDirective):
        """``xval-cli``: the command-line reference, from the parser."""

        has_content = False

        def run(self) -> list:
            self.env.note_dependency(__file__)
            return cli_nodes(self.state.document)

    app.add_directive("xval-cli", XvalCliDirective)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
