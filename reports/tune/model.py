"""``xval tune --write-model``: a tuned copy of an MJCF model, with the changed
attributes and an XML comment before each naming the change and why.

The change is made on the model's text, attribute by attribute
(:data:`FIELD_ATTRIBUTES`: which MJCF attribute carries which MuJoCo setting), so the
same code tunes the harness's own model of a case (:func:`sim_models.builders.viewer_model.
viewer_xml`, what ``xval models`` writes) and a user's own MJCF file: nothing but the
named attributes changes.  The text is edited in place at the byte offsets of the
start tags (``xml.parsers.expat``): quotes, spacing, comments, the XML declaration
and the order of attributes stay as the user wrote them; the file gains only the
comments and, where it has none, an ``<option>``.  A setting MJCF cannot carry
(``invweight_scale``, which the harness applies to the compiled model) is named in the
file's header comment.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass

#: MuJoCo setting -> (elements, attribute) that carry it in MJCF: ``option`` for the
#: solver's, every ``equality`` constraint for the loop's.
FIELD_ATTRIBUTES = {
    "timestep": ("option", "timestep"),
    "integrator": ("option", "integrator"),
    "iterations": ("option", "iterations"),
    "tolerance": ("option", "tolerance"),
    "solref": ("equality/*", "solref"),
    "solimp": ("equality/*", "solimp"),
}
#: The comment prefix (the tests find the changes by it).
MARK = "xval tune:"


class ModelWriteError(ValueError):
    """A model the tuned attributes cannot be written into (one line)."""


@dataclass(frozen=True)
class AttributeChange:
    """One attribute set on one element: ``path`` (e.g. ``equality/connect[B]``),
    ``attribute``, the old text (None: not given, MuJoCo's default) and the new."""

    path: str
    attribute: str
    old: str | None
    new: str
    why: str

    def comment(self) -> str:
        old = self.old if self.old is not None else "(not given: MuJoCo's default)"
        return f" {MARK} {self.path} {self.attribute}: {old} -> {self.new}; {self.why} "


def mjcf_value(v) -> str:
    """A setting's value as MJCF writes it (numbers to 12 figures, tuples spaced)."""
    if isinstance(v, (tuple, list)):
        return " ".join(mjcf_value(x) for x in v)
    if isinstance(v, float):
        return f"{v:.12g}"
    return str(v)


def _label(el: ET.Element, tag_path: str) -> str:
    name = el.get("name")
    return f"{tag_path}[{name}]" if name else tag_path


@dataclass(frozen=True)
class _Tag:
    """A start tag found in the text: its element path, attributes and byte span."""

    path: str
    attrs: dict
    start: int
    end: int          # one past its '>'


def _tags(data: bytes) -> tuple[_Tag, list[_Tag]]:
    """The root's start tag, and those of ``<option>`` (the root's child) and of every
    equality constraint (a child of the root's ``<equality>``), with byte offsets."""
    from xml.parsers import expat
    p = expat.ParserCreate()
    stack: list[str] = []
    found: list[tuple[str, dict, int]] = []

    def start(name, attrs):
        stack.append(name)
        if len(stack) == 1 or (len(stack) == 2 and name == "option") or \
                (len(stack) == 3 and stack[1] == "equality"):
            path = "/".join(stack[1:]) or name
            found.append((path, dict(attrs), p.CurrentByteIndex))

    p.StartElementHandler = start
    p.EndElementHandler = lambda name: stack.pop()
    try:
        p.Parse(data, True)
    except expat.ExpatError as e:
        raise ModelWriteError(f"not well-formed XML: {e}") from None
    tags = [_Tag(path, at, pos, _tag_end(data, pos)) for path, at, pos in found]
    return tags[0], tags[1:]


def _tag_end(data: bytes, pos: int) -> int:
    """One past the ``>`` that closes the start tag at ``pos`` (quotes respected)."""
    quote = None
    for i in range(pos, len(data)):
        c = data[i:i + 1]
        if quote:
            quote = None if c == quote else quote
        elif c in (b'"', b"'"):
            quote = c
        elif c == b">":
            return i + 1
    raise ModelWriteError("a start tag is not closed")


def _set_attribute(tag: bytes, attr: str, value: str) -> bytes:
    """``tag`` (a start tag's bytes) with ``attr`` set to ``value``: its value replaced
    in place, or the attribute added before the tag's end."""
    pat = re.compile(rb'(\s' + re.escape(attr.encode()) + rb'\s*=\s*)(["\'])(.*?)\2', re.S)
    v = value.encode()
    m = pat.search(tag)
    if m:
        return tag[:m.start(3)] + v + tag[m.end(3):]
    close = len(tag) - (2 if tag.endswith(b"/>") else 1)
    body = tag[:close].rstrip()
    return body + b" " + attr.encode() + b'="' + v + b'"' + tag[len(body):]


def _comment_at(data: bytes, pos: int, text: str) -> tuple[int, bytes]:
    """Where and what to insert so that a comment stands before the tag at ``pos``: on
    its own line with the tag's indent when the tag starts its line."""
    c = "<!--" + text.replace("--", "- -") + "-->"
    line = data.rfind(b"\n", 0, pos) + 1
    indent = data[line:pos]
    if indent.strip() == b"":
        return line, indent + c.encode() + b"\n"
    return pos, c.encode() + b" "


def tuned_model_text(xml: str, changed: dict, why: dict, not_in_mjcf: dict | None = None,
                     header: str = "") -> tuple[str, list[AttributeChange]]:
    """``xml`` with each setting of ``changed`` (field -> new value) written into the
    attributes that carry it (:data:`FIELD_ATTRIBUTES`), a comment before each changed
    element (``why``: field -> reason), and a header comment after the root's start tag
    (``header``, plus the ``not_in_mjcf`` settings it cannot carry).  The text is edited
    in place: every other byte of the file is kept.  Returns the text and the changes."""
    data = xml.encode()
    root, tags = _tags(data)
    if root.path != "mujoco":
        raise ModelWriteError(f"not an MJCF model: the root element is <{root.path}>, not "
                              "<mujoco>")
    edits: dict[int, list] = {}   # tag start -> [tag, new tag bytes, comments]
    changes: list[AttributeChange] = []
    add_option: dict[str, str] = {}
    for fld, value in changed.items():
        if fld not in FIELD_ATTRIBUTES:
            continue
        path, attr = FIELD_ATTRIBUTES[fld]
        new = mjcf_value(value)
        mine = [t for t in tags if (t.path == "option" if path == "option"
                                    else t.path.startswith("equality/"))]
        if path == "option" and not mine:  # a model without <option>: add one
            add_option[attr] = new
            changes.append(AttributeChange("option", attr, None, new, why.get(fld, "tuned")))
            continue
        for t in mine:
            old = t.attrs.get(attr)
            if old == new:
                continue
            e = edits.setdefault(t.start, [t, data[t.start:t.end], []])
            e[1] = _set_attribute(e[1], attr, new)
            name = t.attrs.get("name")
            ch = AttributeChange(f"{t.path}[{name}]" if name else t.path, attr, old, new,
                                 why.get(fld, "tuned"))
            changes.append(ch)
            e[2].append(ch.comment())
    out = data
    for start in sorted(edits, reverse=True):
        t, tag, comments = edits[start]
        out = out[:t.start] + tag + out[t.end:]
        for text in reversed(comments):
            at, ins = _comment_at(out, t.start, text)
            out = out[:at] + ins + out[at:]
    lines = [f" {MARK} tuned by xval tune; it differs from the original only in the "
             f"attributes named in the '{MARK}' comments ({len(changes)}). {header}".rstrip()]
    for k, v in (not_in_mjcf or {}).items():
        lines.append(f" {MARK} not expressible in MJCF: {k}={mjcf_value(v)} (the harness "
                     "applies it to the compiled model; a model opened from this file "
                     "runs without it)")
    if add_option:
        lines += [c.comment().rstrip() for c in changes if c.path == "option" and c.old is None
                  and add_option.get(c.attribute) == c.new]
    ins = b"".join(b"\n  <!--" + (x.replace("--", "- -") + " ").encode() + b"-->"
                   for x in lines)
    if add_option:
        ins += b"\n  <option " + b" ".join(f'{k}="{v}"'.encode()
                                            for k, v in add_option.items()) + b"/>"
    out = out[:root.end] + ins + out[root.end:]
    return out.decode(), changes


def attribute_differences(a: str, b: str) -> list[tuple[str, str, str | None, str | None]]:
    """Every attribute that differs between two MJCF texts of the same structure
    (comments ignored): ``(element path, attribute, value in a, value in b)``; raises
    :class:`ModelWriteError` where the elements themselves differ."""
    ra, rb = ET.fromstring(a), ET.fromstring(b)
    out: list = []

    def walk(x, y, path):
        if x.tag != y.tag or len(x) != len(y):
            raise ModelWriteError(f"{path}: the elements differ ({x.tag} / {y.tag})")
        for k in sorted(set(x.attrib) | set(y.attrib)):
            if x.get(k) != y.get(k):
                out.append((path, k, x.get(k), y.get(k)))
        for cx, cy in zip(x, y, strict=True):
            walk(cx, cy, _label(cx, f"{path}/{cx.tag}" if path else cx.tag))

    walk(ra, rb, "")
    return out


__all__ = ["FIELD_ATTRIBUTES", "MARK", "AttributeChange", "ModelWriteError",
           "attribute_differences", "mjcf_value", "tuned_model_text"]
