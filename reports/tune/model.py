"""``xval tune --write-model``: a tuned copy of an MJCF model, with the changed
attributes and an XML comment before each naming the change and why.

The change is made on the model's text, attribute by attribute
(:data:`FIELD_ATTRIBUTES`: which MJCF attribute carries which MuJoCo setting), so the
same code tunes the harness's own model of a case (:func:`sim_models.builders.viewer_model.
viewer_xml`, what ``xval models`` writes) and a user's own MJCF file: nothing but the
named attributes changes.  A setting MJCF cannot carry (``invweight_scale``, which the
harness applies to the compiled model) is named in the file's header comment.
"""

from __future__ import annotations

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


def tuned_model_text(xml: str, changed: dict, why: dict, not_in_mjcf: dict | None = None,
                     header: str = "") -> tuple[str, list[AttributeChange]]:
    """``xml`` with each setting of ``changed`` (field -> new value) written into the
    attributes that carry it (:data:`FIELD_ATTRIBUTES`), a comment before each changed
    element (``why``: field -> reason), and a header comment (``header``, plus the
    ``not_in_mjcf`` settings it cannot carry).  Returns the text and the changes."""
    root = ET.fromstring(xml, parser=ET.XMLParser(target=ET.TreeBuilder(insert_comments=True)))
    if root.tag != "mujoco":
        raise ModelWriteError(f"not an MJCF model: the root element is <{root.tag}>, not "
                              "<mujoco>")
    parents = {c: p for p in root.iter() for c in p}
    changes: list[AttributeChange] = []
    for fld, value in changed.items():
        if fld not in FIELD_ATTRIBUTES:
            continue
        path, attr = FIELD_ATTRIBUTES[fld]
        els = root.findall(path)
        if path == "option" and not els:  # a model without <option>: add one
            el = ET.Element("option")
            el.tail = "\n\n  "
            root.insert(0, el)
            parents[el] = root
            els = [el]
        new = mjcf_value(value)
        for el in els:
            old = el.get(attr)
            if old == new:
                continue
            el.set(attr, new)
            changes.append(AttributeChange(_label(el, path.replace("/*", "/" + el.tag)),
                                           attr, old, new, why.get(fld, "tuned")))
            _comment_before(parents[el], el, changes[-1].comment())
    lines = [f" {MARK} tuned by xval tune; it differs from the original only in the "
             f"attributes named in the '{MARK}' comments ({len(changes)}). {header}".rstrip()]
    for k, v in (not_in_mjcf or {}).items():
        lines.append(f" {MARK} not expressible in MJCF: {k}={mjcf_value(v)} (the harness "
                     "applies it to the compiled model; a model opened from this file "
                     "runs without it) ")
    for i, text in enumerate(lines):
        c = ET.Comment(text + " ")
        c.tail = "\n\n  " if i == len(lines) - 1 else "\n  "
        root.insert(i, c)
    root.text = "\n  "
    return ET.tostring(root, encoding="unicode") + "\n", changes


def _comment_before(parent: ET.Element, el: ET.Element, text: str) -> None:
    i = list(parent).index(el)
    c = ET.Comment(text)
    prev = list(parent)[i - 1] if i > 0 else None
    indent = (prev.tail if prev is not None else parent.text) or "\n"
    c.tail = indent if indent.strip() == "" else "\n"
    parent.insert(i, c)


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
