"""SymPy vocabulary of the worked solutions: the notes' symbols and the printing nodes
(printed by :mod:`reports.explain.printing`; the numbers in them and the check of the
printed values: :mod:`reports.explain.numbers`).

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

Every node evaluates with :func:`reports.explain.printing.value`; its string form uses
``cosd``, ``sind``, ``asind``, ``acosd``, ``atan2d`` (degrees), which
:data:`reports.explain.printing.CHECK_FUNCTIONS` defines for ``sympy.parse_expr``, so a
reader (and the tests) can evaluate the plain-text line printed under each substituted
equation.
"""

from __future__ import annotations

import sympy as sp

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


