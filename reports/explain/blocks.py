"""The pieces a worked solution is made of, independent of the output format.

A document is a list of blocks; :mod:`reports.explain.render` writes it as
Markdown, HTML (MathML) or LaTeX.  Mathematics is held as SymPy expressions
(:mod:`reports.explain.sym`), never as format-specific strings.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass
class Heading:
    level: int
    text: str


@dataclass
class Para:
    """Running text; ``parts`` are strings and SymPy expressions (inline maths)."""

    parts: list[Any]


@dataclass
class Math:
    """A displayed equation ``parts[0] = parts[1] = ...``.

    ``value`` and ``unit``, when given, end the chain (``= value unit``), and
    ``check`` is the plain-text form of the substituted expression (degrees in
    ``cosd``, ``sind``, ...), printed so that it can be evaluated: it must give
    ``value``.  ``note`` is a short remark printed after the equation.
    """

    parts: list[Any]
    value: str | None = None
    unit: str = ""
    check: str | None = None
    note: Any = ""   # a string, or parts as in Para


@dataclass
class Table:
    """``key`` identifies the table for readers and tests (e.g. ``velocity-1``)."""

    key: str
    caption: str
    header: list[Any]
    rows: list[list[Any]]


@dataclass
class Figure:
    caption: str
    svg: str
    tikz: str
    name: str


@dataclass
class Document:
    title: str
    blocks: list[Any] = field(default_factory=list)

    def add(self, *blocks) -> None:
        self.blocks.extend(blocks)
