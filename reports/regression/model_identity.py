"""A mechanism's identity by content: what a baseline compares to tell a changed model.

Not the file's bytes: a comment, a reordered table, CRLF line endings or lengths given
in mm instead of m leave the parsed :class:`analytic.Mechanism` (SI inside) unchanged,
so they are no change.  :func:`content` flattens the mechanism into ``path -> value``
(``bodies.coupler.mass``, ``joints.B.body_a``, ``driver.velocity``, ``gravity``,
``motion.dampers.0.coefficient``, ``motion.motors.0.efforts``, ...),
values in SI as the loader produced them (floats exact: JSON writes ``repr``, which
round-trips); its ``description`` (prose) and ``source`` (where it was read from) are
left out.  :func:`digest` is the SHA-256 of that dict as canonical JSON (keys sorted,
no spaces).  :func:`changes` names what differs between two contents.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math

#: Mechanism fields that are not the model: prose and the file it was read from.
_NOT_MODEL = frozenset({"description", "source"})


def _value(v):
    """A JSON value: tuples as lists, non-finite floats as text (JSON has none).  (A
    tuple of records, a [motion]'s force elements, is flattened by :func:`_flatten`.)"""
    if isinstance(v, (tuple, list)):
        return [_value(x) for x in v]
    if isinstance(v, float) and not math.isfinite(v):
        return repr(v)
    return v


def _is_record(obj) -> bool:
    return dataclasses.is_dataclass(obj) and not isinstance(obj, type)


def _flatten(obj, path: str, out: dict, typed: bool = False) -> None:
    """``out[path...] = value`` for every leaf of ``obj``; ``typed``: ``obj`` is one of
    several kinds that share a place (a joint, a load, a spring, a damper, a motor), so
    its kind is part of its identity (``.type``)."""
    if _is_record(obj):
        if typed or path.startswith("joints.") or path.startswith("loads."):
            out[f"{path}.type"] = type(obj).__name__.lower()
        for f in dataclasses.fields(obj):
            if f.name in _NOT_MODEL or (path.startswith(("bodies.", "joints."))
                                        and f.name == "name"):
                continue
            _flatten(getattr(obj, f.name), f"{path}.{f.name}" if path else f.name, out)
    elif isinstance(obj, (tuple, list)) and any(_is_record(x) for x in obj):
        # force elements (``motion.springs``, ``.dampers``, ``.motors``): each by its
        # position, every field of it, so that a changed coefficient is named
        for i, item in enumerate(obj):
            _flatten(item, f"{path}.{i}", out, typed=True)
    elif isinstance(obj, dict) or hasattr(obj, "keys"):
        if not obj:
            out[path] = {}
        for k in sorted(obj):
            _flatten(obj[k], f"{path}.{k}", out)
    else:
        out[path] = _value(obj)


def content(mech) -> dict:
    """``path -> value`` of everything that defines the mechanism (see module doc);
    bodies and joints are keyed by name, loads by position."""
    out: dict = {}
    for f in dataclasses.fields(mech):
        v = getattr(mech, f.name)
        if f.name in _NOT_MODEL:
            continue
        if f.name in ("bodies", "joints"):
            for item in v:
                _flatten(item, f"{f.name}.{item.name}", out)
        elif f.name == "loads":
            for i, item in enumerate(v):
                _flatten(item, f"loads.{i}", out)
        else:
            _flatten(v, f.name, out)
    return out


def canonical(flat: dict) -> str:
    return json.dumps(flat, sort_keys=True, separators=(",", ":"))


def digest(mech) -> str:
    """SHA-256 (hex) of the mechanism's canonical content."""
    return hashlib.sha256(canonical(content(mech)).encode()).hexdigest()


def digest_of_content(flat: dict) -> str:
    return hashlib.sha256(canonical(flat).encode()).hexdigest()


def changes(before: dict, after: dict, limit: int = 4) -> str:
    """What differs, named: ``bodies.coupler.mass 0.3 -> 0.31; joint 'E' added`` (at
    most ``limit`` items, then how many more)."""
    items = []
    for k in sorted(set(before) | set(after)):
        if k not in after:
            items.append(f"{k} removed (was {_show(before[k])})")
        elif k not in before:
            items.append(f"{k} added ({_show(after[k])})")
        elif before[k] != after[k]:
            items.append(f"{k} {_show(before[k])} -> {_show(after[k])}")
    more = f"; and {len(items) - limit} more" if len(items) > limit else ""
    return "; ".join(items[:limit]) + more


def _show(v) -> str:
    return json.dumps(v) if not isinstance(v, float) else repr(v)


__all__ = ["canonical", "changes", "content", "digest", "digest_of_content"]
