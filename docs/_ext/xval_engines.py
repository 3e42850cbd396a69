"""Sphinx extension: every engine's settings and their accepted ranges, from the code.

The directive ``xval-engine-settings`` (used by ``docs/reference/engines.md``) lists, for
each engine of :data:`sim_models.engines.registry.BUILTIN` and for its free-motion session
(:data:`sim_models.runs.free.FREE_SESSIONS`), every field of its settings dataclass with
its recommended default and the accepted range of ``RANGES``
(:mod:`sim_models.engines.ranges`), the very objects that ``--set``, the option flags,
settings and baseline files check.  An engine whose optional library is missing is
listed with the line that says how to install it.
"""

from __future__ import annotations

import dataclasses
import importlib

# docutils and Sphinx are imported where the page is built (the 'docs' extra), so that
# the reference's tests run in CI's pytest before the docs extra is installed.


def _range_text(rng) -> tuple[str, str]:
    """(accepted values, why) of one ``RANGES`` entry (a range, a choice, a flag, or a
    tuple of ranges for a setting of several numbers)."""
    parts = rng if isinstance(rng, tuple) else (rng,)
    texts, whys = [], []
    for i, part in enumerate(parts):
        name = getattr(part, "name", "") or (f"number {i + 1}" if len(parts) > 1 else "")
        texts.append(f"{name}: {part.text()}" if name else part.text())
        why = getattr(part, "why", "")
        if why and why not in whys:
            whys.append(why)
    return "; ".join(texts), "; ".join(whys)


def _default(value) -> str:
    if isinstance(value, tuple):
        return ", ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in value)
    if isinstance(value, float):
        return f"{value:g}"
    return str(value).lower() if isinstance(value, bool) else str(value)


def settings_rows(cls) -> list[tuple[str, str, str, str]]:
    """``(setting, default, accepted, why)`` for each field of a settings dataclass."""
    defaults = cls()
    rows = []
    for f in dataclasses.fields(cls):
        accepted, why = _range_text(cls.RANGES[f.name])
        rows.append((f.name, _default(getattr(defaults, f.name)), accepted, why))
    return rows


def engine_settings() -> list[tuple[str, str, object, object, str]]:
    """``(name, description, prescribed settings class, free settings class, install)``
    per registered engine; ``install`` says how to install an optional engine's library.
    The settings live in the engine's own modules, which import the library only when a
    session starts, so an optional engine is listed whether or not it is installed."""
    from sim_models.engines.registry import BUILTIN
    from sim_models.runs.free import FREE_SESSIONS

    out = []
    for entry in BUILTIN:
        driven = getattr(importlib.import_module(entry.module), entry.session).settings_class
        free = None
        if entry.name in FREE_SESSIONS:
            module, session = FREE_SESSIONS[entry.name]
            free = getattr(importlib.import_module(module), session).settings_class
        out.append((entry.name, entry.description, driven, free, entry.install))
    return out


def _table(rows, header):
    from docutils import nodes
    table = nodes.table()
    group = nodes.tgroup(cols=len(header))
    table += group
    for width in (18, 14, 38, 30)[:len(header)]:
        group += nodes.colspec(colwidth=width)
    head = nodes.thead()
    group += head
    row = nodes.row()
    for text in header:
        row += nodes.entry("", nodes.paragraph(text=text))
    head += row
    body = nodes.tbody()
    group += body
    for cells in rows:
        row = nodes.row()
        row += nodes.entry("", nodes.paragraph("", "", nodes.literal(cells[0], cells[0])))
        for text in cells[1:]:
            row += nodes.entry("", nodes.paragraph(text=text))
        body += row
    return table


def _section(title: str, document):
    from docutils import nodes
    sec = nodes.section()
    sec["ids"].append(nodes.make_id("engine-" + title))
    sec["names"].append(nodes.fully_normalize_name("engine " + title))
    sec += nodes.title(title, "", nodes.literal(title, title))
    document.note_implicit_target(sec, sec)
    return sec


HEADER = ("setting", "recommended", "accepted", "why")


def engine_nodes(document) -> list:
    from docutils import nodes
    out = []
    for name, description, driven, free, install in engine_settings():
        sec = _section(name, document)
        sec += nodes.paragraph(text=description)
        if install:
            sec += nodes.paragraph("", "", nodes.Text("Optional: "),
                                   nodes.literal(install, install))
        sec += nodes.paragraph("", "", nodes.Text("Prescribed (driven) runs: "),
                               nodes.literal(driven.__name__, driven.__name__))
        sec += _table(settings_rows(driven), HEADER)
        if free is not None:
            sec += nodes.paragraph("", "", nodes.Text("Free (released) runs: "),
                                   nodes.literal(free.__name__, free.__name__))
            sec += _table(settings_rows(free), HEADER)
        out.append(sec)
    return out


def setup(app):
    from sphinx.util.docutils import SphinxDirective

    class XvalEngineSettingsDirective(SphinxDirective):
        """``xval-engine-settings``: every engine's settings and ranges, from the code."""

        has_content = False

        def run(self) -> list:
            self.env.note_dependency(__file__)
            return engine_nodes(self.state.document)

    app.add_directive("xval-engine-settings", XvalEngineSettingsDirective)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
