"""How the worked solutions' expressions print: the notes' LaTeX, plain text and
MathML printers of the printing nodes (:mod:`reports.explain.sym`), and their
evaluation (:func:`value`, :func:`to_plain`)."""

from __future__ import annotations

import sympy as sp
from sympy.printing.latex import LatexPrinter
from sympy.printing.mathml import MathMLPresentationPrinter
from sympy.printing.str import StrPrinter

from reports.explain.sym import (
    _GREEK,
    _TRIG,
    Brace,
    Bracket,
    Deg,
    Frac,
    Neg,
    Paren,
    Trig,
    _mi,
    _mo,
    _mrow,
    _paren_ml,
)

# -- printers -----------------------------------------------------------------

def _negnum(t) -> bool:
    return isinstance(t, sp.Number) and t < 0


def _split_neg(term):
    """``(True, t)`` for an unevaluated ``Mul(-1, t...)`` or a negative number."""
    if isinstance(term, sp.Mul) and term.args and term.args[0] == -1:
        rest = term.args[1:]
        return True, rest[0] if len(rest) == 1 else sp.Mul(*rest, evaluate=False)
    if isinstance(term, sp.Number) and term < 0:
        return True, -term
    return False, term


class NotesLatex(LatexPrinter):
    """SymPy's LaTeX printer, keeping sums in the order built and their minus signs
    without evaluating the negated terms."""

    def _print_Add(self, expr, order=None):
        out = ""
        for i, t in enumerate(expr.args):
            neg, t = _split_neg(t)
            s = self._print(t)
            if isinstance(t, sp.Add) or _negnum(t):
                s = rf"\left({s}\right)"
            out += (("-" if neg else "") + s if i == 0 else (" - " if neg else " + ") + s)
        return out


class NotesStr(StrPrinter):
    """SymPy's string printer with the same treatment of sums."""

    def _print_Add(self, expr, order=None):
        out = ""
        for i, t in enumerate(expr.args):
            neg, t = _split_neg(t)
            s = self._print(t)
            if isinstance(t, sp.Add) or _negnum(t):
                s = f"({s})"
            out += (("-" if neg else "") + s if i == 0 else (" - " if neg else " + ") + s)
        return out


def latex(e) -> str:
    if isinstance(e, str):
        return rf"\text{{{e}}}"
    return NotesLatex({"order": "none"}).doprint(e)


def text(e) -> str:
    """The plain-text (calculator / ``sympy.parse_expr``) form."""
    return NotesStr({"order": "none", "full_prec": False}).doprint(e)


class NotesMathML(MathMLPresentationPrinter):
    """SymPy's presentation-MathML printer with the notes' dotted rates and Greek
    unit-vector names (``thetadot_2`` -> theta with a dot, subscript 2)."""

    def _print_Symbol(self, sym, style="plain"):
        nm = sym.name
        base, _, sub = nm.partition("_")
        sub = sub.strip("{}")
        dots = ""
        for mod, mark in (("ddot", "\u00a8"), ("dot", "\u02d9")):
            if base.endswith(mod) and base != mod:
                base, dots = base[:-len(mod)], mark
                break
        base = _GREEK.get(base, base)
        x = _mi(self, base)
        if dots:
            # no accent="true": without an OpenType MATH font Chromium then sinks the
            # dot into the letter; as a plain over-script it sits visibly above
            over = self.dom.createElement("mover")
            over.appendChild(x)
            over.appendChild(_mo(self, dots))
            x = over
        if sub:
            s = self.dom.createElement("msub")
            s.appendChild(x)
            s.appendChild(_mi(self, sub) if not sub.isdigit() else self._num(sub))
            x = s
        return x

    def _num(self, t):
        m = self.dom.createElement("mn")
        m.appendChild(self.dom.createTextNode(t))
        return m

    def _print_Add(self, expr, order=None):
        row = _mrow(self)
        for i, t in enumerate(expr.args):
            neg, t = _split_neg(t)
            if i or neg:
                row.appendChild(_mo(self, "\u2212" if neg else "+"))
            x = self._print(t)
            row.appendChild(_paren_ml(self, x) if isinstance(t, sp.Add) or _negnum(t) else x)
        return row

    def _print_Mul(self, expr):
        if getattr(expr, "is_commutative", True) and not any(
                isinstance(a, sp.Number | Paren) for a in expr.args) or len(expr.args) < 2:
            return super()._print_Mul(expr)
        row = _mrow(self)
        for i, a in enumerate(expr.args):  # the notes put a dot between numbers
            if i:
                row.appendChild(_mo(self, "\u22c5"))
            row.appendChild(self._print(a))
        return row

    def _print_Function(self, e):
        nm = type(e).__name__
        if nm in _GREEK:
            inner = _mrow(self)
            for i, a in enumerate(e.args):
                if i:
                    inner.appendChild(_mo(self, ","))
                inner.appendChild(self._print(a))
            return _mrow(self, _mi(self, _GREEK[nm]), _paren_ml(self, inner))
        return super()._print_Function(e)


def mathml(e) -> str:
    """Presentation MathML of an expression (an ``<mrow>`` fragment)."""
    if isinstance(e, str):
        return f"<mtext>{_xml_escape(e)}</mtext>"
    p = NotesMathML({"order": "none"})
    return p._print(e).toxml()


def _xml_escape(s: str) -> str:
    return s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


# -- evaluation ---------------------------------------------------------------

_x, _y = sp.symbols("x y")
CHECK_FUNCTIONS = {
    "cosd": sp.Lambda(_x, sp.cos(_x * sp.pi / 180)),
    "sind": sp.Lambda(_x, sp.sin(_x * sp.pi / 180)),
    "asind": sp.Lambda(_x, sp.asin(_x) * 180 / sp.pi),
    "acosd": sp.Lambda(_x, sp.acos(_x) * 180 / sp.pi),
    "atan2d": sp.Lambda((_y, _x), sp.atan2(_y, _x) * 180 / sp.pi),
}
"""Definitions of the degree functions of the plain-text forms, for ``parse_expr``."""


def value(e) -> float:
    """Evaluate an expression built from the printing nodes (floats, degrees)."""
    return float(sp.N(to_plain(e), 30))


def to_plain(e):
    """Replace the printing nodes with ordinary SymPy (evaluable) expressions."""
    if isinstance(e, Trig):
        return CHECK_FUNCTIONS[_TRIG[e.fname][1]](*[to_plain(a) for a in e.args[1:]])
    if isinstance(e, Frac):
        return to_plain(e.args[0]) / to_plain(e.args[1])
    if isinstance(e, Neg):
        return -to_plain(e.args[0])
    if isinstance(e, Deg | Paren | Brace | Bracket):
        return to_plain(e.args[0])
    if e.args:
        return e.func(*[to_plain(a) for a in e.args])
    return e
