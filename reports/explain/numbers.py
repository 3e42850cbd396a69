"""The numbers of the worked solutions: significant digits (:func:`digits`, :func:`num`),
the printed values (:func:`fmt`, never a false 0), and the check that every 'calc:'
line gives the value printed beside it (:func:`reproduces`, :func:`build_checked`)."""

from __future__ import annotations

import contextlib
import contextvars
import math

import sympy as sp

from analytic import LinkageError
from reports.explain.printing import CHECK_FUNCTIONS, text

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


