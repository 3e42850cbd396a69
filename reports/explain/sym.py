"""SymPy vocabulary of the worked solutions: the notes' symbols and how they print.

The notes write every vector as ``r_k mu(theta_k)`` with the unit vectors
``mu(theta) = (cos, sin)`` and ``sigma(theta) = (-sin, cos)``, rates with dots
(``thetadot_k``, ``rdot_k``), and substitute numbers with the angles in degrees:
``cos(30 - 180)``.  This module builds those expressions as SymPy objects and
prints them with SymPy's LaTeX, MathML (presentation) and string printers.

SymPy reorders and evaluates numbers as soon as they meet, and its string printer
misplaces parentheses in unevaluated quotients, so a substituted expression is
built from a few small nodes that print exactly as written:

* :class:`Frac` (a quotient), :class:`Neg` (a leading minus), :class:`Deg` (a
  number of degrees), :class:`Trig` (cos/sin/asin/acos of degrees, atan2 in
  degrees), :class:`Brace` (an under-brace with a label, the notes' S/D marks).

Every node evaluates with :func:`value`; its string form uses ``cosd``, ``sind``,
``asind``, ``acosd``, ``atan2d`` (degrees), which :data:`CHECK_FUNCTIONS` defines for
``sympy.parse_expr``, so a reader (and the tests) can evaluate the plain-text line
printed under each substituted equation.
"""

from __future__ import annotations

import contextlib
import contextvars
import math

import sympy as sp
from sympy.printing.latex import LatexPrinter
from sympy.printing.mathml import MathMLPresentationPrinter
from sympy.printing.str import StrPrinter

from analytic import LinkageError

MU = sp.Function("mu")
SIGMA = sp.Function("sigma")

_GREEK = {"theta": "\u03b8", "mu": "\u03bc", "sigma": "\u03c3", "omega": "\u03c9",
          "alpha": "\u03b1", "delta": "\u03b4", "gamma": "\u03b3", "beta": "\u03b2",
          "phi": "\u03c6", "psi": "\u03c8", "tau": "\u03c4", "rho": "\u03c1",
          "lambda": "\u03bb", "epsilon": "\u03b5", "Sigma": "\u03a3"}


def r(k: str, dots: int = 0) -> sp.Symbol:
    """``r_k``, ``rdot_k`` or ``rddot_k`` (length of loop vector k and its rates)."""
    return sp.Symbol(f"r{['', 'dot', 'ddot'][dots]}_{k}")


def th(k: str, dots: int = 0) -> sp.Symbol:
    """``theta_k`` and its rates."""
    return sp.Symbol(f"theta{['', 'dot', 'ddot'][dots]}_{k}")


def name(base: str, sub: str) -> sp.Symbol:
    """A plain subscripted symbol, e.g. ``name('F', '23x')``."""
    return sp.Symbol(f"{base}_{sub}")


# -- numbers ------------------------------------------------------------------

_SIG: contextvars.ContextVar[int] = contextvars.ContextVar("explain_digits", default=9)
DIGITS_TRIED = (9, 12, 15, 17)
"""Significant digits of the numbers in a substituted expression: 9 unless the
expression is ill-conditioned there (near a limit position, or a small result of
large terms) and needs more to evaluate to the 6-figure value printed beside it."""


@contextlib.contextmanager
def digits(n: int):
    token = _SIG.set(n)
    try:
        yield
    finally:
        _SIG.reset(token)


def num(v: float, sig: int | None = None):
    """A number as printed in a substituted expression: integers stay integers,
    others carry ``sig`` significant digits (default: the current :func:`digits`)."""
    sig = sig or _SIG.get()
    v = float(v)
    s = f"{v:.{sig}g}"
    if float(s) == round(float(s)) and abs(v) < 1e9:
        return sp.Integer(int(round(float(s))))
    if "e" in s:
        m, e = s.split("e")
        s = f"{float(m) * 10 ** int(e):.{max(0, sig - 1 - int(e))}f}"
    return sp.Float(s, max(sig, 15))


ROUNDOFF = 1e-12
"""A value at most this fraction of the scale it was computed from (the largest of
the terms that cancelled to give it) is round-off of a zero: about 4500 double
ulps, the error a few dozen rounded operations can leave."""


def fmt(v: float, sig: int = 6, scale: float | None = None) -> str:
    """The value printed beside an expression or in a table: 6 significant figures at
    its own scale (exponent form below 1e-4 and from 1e6, never a false 0).  Only an
    exact zero, or a value within :data:`ROUNDOFF` of ``scale`` (the magnitude of the
    terms that gave it, when the caller knows them), prints as ``0``."""
    v = float(v)
    if not math.isfinite(v):
        return str(v)
    if v == 0 or (scale is not None and abs(v) <= ROUNDOFF * abs(scale)):
        return "0"
    return f"{v:.{sig}g}"


def ulp_half(printed: str) -> float:
    """Half a unit in the last digit of a number printed by :func:`fmt`."""
    mant, _, exp = printed.partition("e")
    dec = len(mant.split(".")[1]) if "." in mant else 0
    return 0.5 * 10.0 ** (int(exp or 0) - dec)


ZERO_CHECK = 1e-8
"""A printed ``0`` is reproduced by a 'calc:' line that evaluates to at most this
fraction of its terms' magnitude (:func:`abs_scale`): the 9-figure numbers in the
line carry 5e-10 relative each, and a few dozen of them add up to about 1e-8.  A
line that gives more than this is a value that the ``0`` hides."""


_TRIG_SCALE = {"cosd": 1.0, "sind": 1.0, "asind": 90.0, "acosd": 180.0, "atan2d": 180.0}
_OPAQUE = {k: sp.Function(k) for k in _TRIG_SCALE}


def abs_scale(e) -> float:
    """The magnitude a plain-text expression's value is computed from, SymPy parsed
    with the degree functions left unevaluated: sums add the magnitudes of their terms
    (a cancelling sum keeps the size of what cancelled), products multiply them, a
    cos/sin counts 1 and an inverse one its range in degrees; a quotient or any other
    function counts by its value."""
    if isinstance(e, sp.Add):
        return sum(abs_scale(a) for a in e.args)
    if isinstance(e, sp.Mul):
        out = 1.0
        for a in e.args:
            out *= abs_scale(a)
        return out
    if isinstance(e, sp.Pow) and e.exp.is_number and e.exp > 0:
        return abs_scale(e.base) ** float(e.exp)
    if type(e).__name__ in _TRIG_SCALE:
        return _TRIG_SCALE[type(e).__name__]
    try:
        return abs(complex(sp.N(to_plain_text(e), 20)))
    except (TypeError, ValueError):
        return math.inf


def to_plain_text(e):
    """An expression with unevaluated degree functions made evaluable."""
    return e.replace(lambda x: type(x).__name__ in _TRIG_SCALE,
                     lambda x: CHECK_FUNCTIONS[type(x).__name__](*x.args))


def _parse(check: str):
    return sp.parse_expr(check, local_dict=dict(CHECK_FUNCTIONS))


def text_scale(check: str) -> float:
    """:func:`abs_scale` of a plain-text ('calc:') expression."""
    return abs_scale(sp.parse_expr(check, local_dict=dict(_OPAQUE), evaluate=False))


def fmt_of(v: float, expr) -> str:
    """:func:`fmt` of a value computed from the substituted expression ``expr``: 0 only
    where it is round-off of the terms the expression adds up."""
    return fmt(v, scale=text_scale(text(expr)))


def reproduces(check: str, printed: str, rel: float = 1e-9) -> bool:
    """Does the plain-text expression ``check`` evaluate to ``printed`` (to half a unit
    of its last digit)?  A printed ``0`` must be a zero of the expression to within
    :data:`ZERO_CHECK` of its terms, and an expression that leaves the real numbers
    (an arccos of a rounded argument just above 1, near a toggle position) does not
    reproduce anything."""
    try:
        z = complex(sp.N(_parse(check), 30))
    except (TypeError, ValueError):
        return False
    if z.imag != 0 or not math.isfinite(z.real):
        return False
    v, p = z.real, float(printed)
    if p == 0.0:
        return abs(v) <= ZERO_CHECK * text_scale(check)
    return abs(v - p) <= ulp_half(printed) + rel * abs(v)


class CheckError(LinkageError):
    """A worked solution whose 'calc:' lines do not give the values printed beside
    them, even with 17 significant digits: within round-off of a singular
    configuration, where the substituted expressions lose every digit."""


def build_checked(build, *args):
    """``build(*args)`` -> blocks, rebuilt with more digits until every 'calc:' line in
    them evaluates to the value printed beside it (see :data:`DIGITS_TRIED`).  A
    document that still fails is not printed: :class:`CheckError`, one line."""
    for n in DIGITS_TRIED:
        with digits(n):
            blocks = build(*args)
        bad = [b for b in blocks if getattr(b, "check", None) is not None
               and b.value is not None and not reproduces(b.check, b.value)]
        if not bad:
            return blocks
    b = bad[0]
    raise CheckError(f"the worked solution cannot be shown to its printed digits here: its "
                     f"line {b.check} does not give the printed {b.value} even with "
                     f"{DIGITS_TRIED[-1]} significant digits (the input is within round-off "
                     "of a singular configuration); `xval solve` gives the values")


# -- printing nodes -----------------------------------------------------------

def _mrow(p, *children):
    m = p.dom.createElement("mrow")
    for c in children:
        m.appendChild(c)
    return m


def _mo(p, text: str):
    m = p.dom.createElement("mo")
    m.appendChild(p.dom.createTextNode(text))
    return m


def _mi(p, text: str):
    m = p.dom.createElement("mi")
    m.appendChild(p.dom.createTextNode(text))
    return m


def _paren_ml(p, inner):
    return _mrow(p, _mo(p, "("), inner, _mo(p, ")"))


def _needs_paren(e) -> bool:
    return isinstance(e, sp.Add | Neg) or (isinstance(e, sp.Number) and e < 0)


class Node(sp.Function):
    """Base of the printing nodes (an unevaluated function application)."""

    @classmethod
    def eval(cls, *args):  # never evaluates: the nodes exist to be printed
        return None


class Deg(Node):
    """A number of degrees: prints ``30^circ``; its string form is the bare number."""
    nargs = 1

    def _latex(self, p):
        return p._print(self.args[0]) + r"^{\circ}"

    def _sympystr(self, p):
        return p._print(self.args[0])

    def _mathml_presentation(self, p):
        return _mrow(p, p._print(self.args[0]), _mo(p, "\u00b0"))


class Frac(Node):
    """A quotient ``n / d``."""
    nargs = 2

    def _latex(self, p):
        return rf"\frac{{{p._print(self.args[0])}}}{{{p._print(self.args[1])}}}"

    def _sympystr(self, p):
        return f"({p._print(self.args[0])})/({p._print(self.args[1])})"

    def _mathml_presentation(self, p):
        m = p.dom.createElement("mfrac")
        m.appendChild(p._print(self.args[0]))
        m.appendChild(p._print(self.args[1]))
        return m


class Neg(Node):
    """``-x``."""
    nargs = 1

    def _latex(self, p):
        a = self.args[0]
        s = p._print(a)
        return "-" + (rf"\left({s}\right)" if _needs_paren(a) else s)

    def _sympystr(self, p):
        return f"-({p._print(self.args[0])})"

    def _mathml_presentation(self, p):
        a = self.args[0]
        inner = p._print(a)
        return _mrow(p, _mo(p, "\u2212"), _paren_ml(p, inner) if _needs_paren(a) else inner)


class Paren(Node):
    """``(x)``: a negative number inside a product."""
    nargs = 1

    def _latex(self, p):
        return rf"\left({p._print(self.args[0])}\right)"

    def _sympystr(self, p):
        return f"({p._print(self.args[0])})"

    def _mathml_presentation(self, p):
        return _paren_ml(p, p._print(self.args[0]))


_TRIG = {"cos": (r"\cos", "cosd"), "sin": (r"\sin", "sind"), "asin": (r"\arcsin", "asind"),
         "acos": (r"\arccos", "acosd"), "atan2": (r"\operatorname{atan2}", "atan2d")}


class Trig(Node):
    """``cos``/``sin`` of an angle in degrees, or ``asin``/``acos``/``atan2`` giving
    degrees.  ``Trig(sp.Symbol('cos'), arg)``; atan2 takes ``(y, x)``."""

    @property
    def fname(self) -> str:
        return str(self.args[0])

    def _latex(self, p):
        tex = _TRIG[self.fname][0]
        return tex + r"\left(" + ", ".join(p._print(a) for a in self.args[1:]) + r"\right)"

    def _sympystr(self, p):
        return _TRIG[self.fname][1] + "(" + ", ".join(p._print(a) for a in self.args[1:]) + ")"

    def _mathml_presentation(self, p):
        inner = _mrow(p)
        for i, a in enumerate(self.args[1:]):
            if i:
                inner.appendChild(_mo(p, ","))
            inner.appendChild(p._print(a))
        name = {"asin": "arcsin", "acos": "arccos"}.get(self.fname, self.fname)
        return _mrow(p, _mi(p, name), _paren_ml(p, inner))


def cos(a):
    return Trig(sp.Symbol("cos"), a)


def sin(a):
    return Trig(sp.Symbol("sin"), a)


def asin(a):
    return Trig(sp.Symbol("asin"), a)


def acos(a):
    return Trig(sp.Symbol("acos"), a)


def atan2(y, x):
    return Trig(sp.Symbol("atan2"), y, x)


class Brace(Node):
    """An under-brace carrying a label: the notes' S/S*/D marks over each factor and
    the value of each dot product under each term.  ``Brace(expr, label)`` where the
    label is an expression or a string symbol."""
    nargs = 2

    def _latex(self, p):
        return rf"\underbrace{{{p._print(self.args[0])}}}_{{{p._print(self.args[1])}}}"

    def _sympystr(self, p):
        return p._print(self.args[0])

    def _mathml_presentation(self, p):
        # a rule under the term (a CSS border: a stretched brace needs a MATH font,
        # which an offline page cannot count on), the label in script size below it
        body = _mrow(p, p._print(self.args[0]))
        body.setAttribute("style", "border-bottom: 1px solid #777; padding-bottom: 1px")
        outer = p.dom.createElement("munder")
        outer.appendChild(body)
        outer.appendChild(p._print(self.args[1]))
        return outer


class Dot(Node):
    """The scalar product of two expressions, printed ``a . b``."""
    nargs = 2

    def _latex(self, p):
        return r"{} \cdot {}".format(*tuple(p._print(a) for a in self.args))

    def _sympystr(self, p):
        return "{}.{}".format(*tuple(p._print(a) for a in self.args))

    def _mathml_presentation(self, p):
        return _paren_ml(p, _mrow(p, p._print(self.args[0]), _mo(p, "\u22c5"),
                                  p._print(self.args[1])))


class DDt(Node):
    """The time derivative ``d/dt (x)``."""
    nargs = 1

    def _op(self):
        return Frac(sp.Symbol("d"), sp.Symbol("dt"))

    def _latex(self, p):
        return rf"{p._print(self._op())}\left({p._print(self.args[0])}\right)"

    def _sympystr(self, p):
        return f"d/dt({p._print(self.args[0])})"

    def _mathml_presentation(self, p):
        return _mrow(p, p._print(self._op()), _paren_ml(p, p._print(self.args[0])))


class Bracket(Node):
    """``[x]`` with an explicit left factor: ``mu(theta_4) . [ ... ]``."""
    nargs = 1

    def _latex(self, p):
        return rf"\left[{p._print(self.args[0])}\right]"

    def _sympystr(self, p):
        return f"[{p._print(self.args[0])}]"

    def _mathml_presentation(self, p):
        return _mrow(p, _mo(p, "["), p._print(self.args[0]), _mo(p, "]"))


def label(text: str) -> sp.Symbol:
    """A label symbol (S, S*, D, 0, 1) printed upright."""
    return sp.Symbol(text)


# -- builders -------------------------------------------------------------------

def prod(*factors):
    """An unevaluated product; a negative number after the first factor is put in
    parentheses, factors equal to 1 are dropped."""
    fs = [f for f in factors if not (isinstance(f, sp.Number) and f == 1)]
    if not fs:
        return sp.Integer(1)
    first = fs[0]
    if isinstance(first, sp.Number) and first < 0 and len(fs) > 1:
        first = Paren(first)
    out = [first] + [Paren(f) if isinstance(f, sp.Number) and f < 0 else f for f in fs[1:]]
    if len(out) == 1:
        return out[0]
    return sp.Mul(*out, evaluate=False)


def sq(x):
    """``x^2`` unevaluated."""
    return sp.Pow(x, 2, evaluate=False)


def signed_sum(terms):
    """``[(sign, expr), ...]`` -> an unevaluated sum ``e1 - e2 + ...`` kept in order."""
    parts = []
    for i, (sg, e) in enumerate(terms):
        if sg < 0:
            parts.append(Neg(e) if i == 0 else sp.Mul(-1, e, evaluate=False))
        else:
            parts.append(e)
    if not parts:
        return sp.Integer(0)
    if len(parts) == 1:
        return parts[0]
    return sp.Add(*parts, evaluate=False)


def diff_angle(a, b):
    """``a - b`` unevaluated."""
    return sp.Add(a, sp.Mul(-1, b, evaluate=False), evaluate=False)


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
