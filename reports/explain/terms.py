"""Terms of the velocity and acceleration equations, and the notes' elimination.

Differentiating ``sum r_k mu(theta_k) = 0`` with ``d mu/dt = thetadot sigma`` and
``d sigma/dt = -thetadot mu`` gives, per vector,

* velocity:      ``rdot_k mu(theta_k) + r_k thetadot_k sigma(theta_k)``
* acceleration:  ``rddot_k mu + 2 rdot_k thetadot_k sigma + r_k thetaddot_k sigma
  - r_k thetadot_k^2 mu``

where a term is present only when its factors vary (the notes' variable tables).
One unknown is eliminated by the dot product with the unit vector perpendicular
to its own (``mu(a).sigma(a) = 0``), with the identities
``mu(a).mu(b) = sigma(a).sigma(b) = cos(a - b)``, ``mu(a).sigma(b) = sin(a - b)``,
``sigma(a).mu(b) = sin(b - a)``.

Numbers here are in the file's length unit (lengths, length/s, length/s^2),
rad/s and rad/s^2; angles in degrees for printing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import sympy as sp

from reports.explain import numbers as N
from reports.explain import sym as S
from reports.explain.loops import Loop, LoopVector, Var, parallel


@dataclass(frozen=True)
class Term:
    """``sign * factors * unit(theta_angle)``; ``var`` is the unknown the term is
    linear in (its rate factor), or ``None``."""

    sign: int
    factors: tuple[tuple[str, str], ...]   # (kind, label): r rdot rddot w w2 al two
    unit: str                              # "mu" | "sigma"
    angle: str                             # label of the vector giving the angle
    var: Var | None
    rate_kind: str = ""                    # the factor kind that is the variable's rate


@dataclass
class Numbers:
    """Values of one configuration in the file's units (see module docstring)."""

    r: dict[str, float]        # label -> length
    theta: dict[str, float]    # label -> angle, deg in [0, 360)
    rdot: dict[str, float]
    rddot: dict[str, float]
    w: dict[str, float]        # rate label -> thetadot (rad/s)
    al: dict[str, float]


def vec_of(loop: Loop, label: str) -> LoopVector:
    return next(v for v in loop.vectors if v.label == label)


def var_of_vector(loop: Loop, v: LoopVector, ng: int):
    g = Var("g", v.group, v.group) if v.group >= 0 else None
    s = Var("s", v.slider, ng + v.slider) if v.slider >= 0 else None
    return g, s


def velocity_terms(loop: Loop, ng: int) -> list[Term]:
    out = []
    for v in loop.vectors:
        g, s = var_of_vector(loop, v, ng)
        if s is not None:
            out.append(Term(1, (("rdot", v.label),), "mu", v.label, s, "rdot"))
        if g is not None:
            out.append(Term(1, (("r", v.label), ("w", loop.rate_label[v.group])), "sigma",
                            v.label, g, "w"))
    return out


def acceleration_terms(loop: Loop, ng: int, const_rate: set[Var]) -> list[Term]:
    """``const_rate``: variables whose rate is constant (S*): their second
    derivative terms vanish."""
    out = []
    for v in loop.vectors:
        g, s = var_of_vector(loop, v, ng)
        rl = loop.rate_label.get(v.group, "")
        if s is not None and s not in const_rate:
            out.append(Term(1, (("rddot", v.label),), "mu", v.label, s, "rddot"))
        if s is not None and g is not None:
            out.append(Term(1, (("two", ""), ("rdot", v.label), ("w", rl)), "sigma",
                            v.label, None))
        if g is not None and g not in const_rate:
            out.append(Term(1, (("r", v.label), ("al", rl)), "sigma", v.label, g, "al"))
        if g is not None:
            out.append(Term(-1, (("r", v.label), ("w2", rl)), "mu", v.label, None))
    return out


# -- printing of factors ------------------------------------------------------------

def factor_sym(kind: str, lab: str):
    return {"r": lambda: S.r(lab), "rdot": lambda: S.r(lab, 1), "rddot": lambda: S.r(lab, 2),
            "w": lambda: S.th(lab, 1), "w2": lambda: S.sq(S.th(lab, 1)),
            "al": lambda: S.th(lab, 2), "two": lambda: sp.Integer(2)}[kind]()


def factor_val(kind: str, lab: str, n: Numbers) -> float:
    return {"r": lambda: n.r[lab], "rdot": lambda: n.rdot[lab], "rddot": lambda: n.rddot[lab],
            "w": lambda: n.w[lab], "w2": lambda: n.w[lab] ** 2, "al": lambda: n.al[lab],
            "two": lambda: 2.0}[kind]()


def factor_num(kind: str, lab: str, n: Numbers):
    if kind == "w2":
        return S.sq(N.num(n.w[lab]))
    return N.num(factor_val(kind, lab, n))


def unit_sym(unit: str, lab: str):
    return (S.MU if unit == "mu" else S.SIGMA)(S.th(lab))


def term_sym(t: Term, with_unit: bool = True):
    fs = [factor_sym(k, lab) for k, lab in t.factors]
    if with_unit:
        fs.append(unit_sym(t.unit, t.angle))
    return S.prod(*fs)


def equation_sym(terms: list[Term]):
    return S.signed_sum([(t.sign, term_sym(t)) for t in terms])


def angle_num(lab: str, n: Numbers):
    return S.Deg(N.num(n.theta[lab]))


# -- dot products ---------------------------------------------------------------------

@dataclass(frozen=True)
class DotResult:
    sym: object         # identity's symbolic value (cos(...), sin(...), 1 or 0)
    num: object         # with the angles substituted
    value: float
    reason: str         # why it is 0 or 1, when it is


def dot(unit_a: str, la: str, unit_b: str, lb: str, n: Numbers, loop: Loop) -> DotResult:
    """``unit_a(theta_la) . unit_b(theta_lb)`` by the notes' identities."""
    if la == lb:
        if unit_a == unit_b:
            return DotResult(sp.Integer(1), sp.Integer(1), 1.0, "unit vector with itself")
        return DotResult(sp.Integer(0), sp.Integer(0), 0.0,
                         "mu and sigma of one angle are perpendicular")
    ta, tb = S.th(la), S.th(lb)
    a, b = n.theta[la], n.theta[lb]
    if unit_a == unit_b:
        sym = S.cos(S.diff_angle(ta, tb))
        numx = S.cos(S.diff_angle(angle_num(la, n), angle_num(lb, n)))
        val = math.cos(math.radians(a - b))
    elif unit_a == "mu":
        sym = S.sin(S.diff_angle(ta, tb))
        numx = S.sin(S.diff_angle(angle_num(la, n), angle_num(lb, n)))
        val = math.sin(math.radians(a - b))
    else:
        sym = S.sin(S.diff_angle(tb, ta))
        numx = S.sin(S.diff_angle(angle_num(lb, n), angle_num(la, n)))
        val = math.sin(math.radians(b - a))
    va, vb = _vec(loop, la), _vec(loop, lb)
    if (unit_a != unit_b and va.group == vb.group
            and parallel(va.beta, vb.beta)):
        return DotResult(sym, numx, 0.0, f"theta_{la} and theta_{lb} differ by a constant "
                         "0 or 180 deg (one rotation)")
    return DotResult(sym, numx, val, "")


def _vec(loop: Loop, lab: str) -> LoopVector:
    return vec_of(loop, lab)


# -- elimination -------------------------------------------------------------------------

@dataclass
class Elimination:
    """Solving a loop's vector equation for unknown ``x`` by dotting it with ``e``."""

    x: Var
    x_sym: object
    e_unit: str
    e_label: str
    dots: list[DotResult]         # one per term
    closed: object                # closed-form expression of x
    substituted: object
    value: float
    ok: bool                      # False: the other unknown's terms do not all vanish


def perpendicular(y: Var, loop: Loop, terms: list[Term]) -> tuple[str, str]:
    """The unit vector that eliminates ``y``: perpendicular to the unit vector of its
    terms (``sigma(theta)`` for an angle's rate, ``mu(theta)`` for a length's)."""
    t = next(t for t in terms if t.var == y)
    return ("mu" if t.unit == "sigma" else "sigma"), t.angle


def rate_symbol(x: Var, loop: Loop, terms: list[Term]):
    t = next(t for t in terms if t.var == x)
    k, lab = next((k, lab) for k, lab in t.factors if k == t.rate_kind)
    return factor_sym(k, lab)


def eliminate(loop: Loop, terms: list[Term], x: Var, y: Var, n: Numbers) -> Elimination:
    e_unit, e_label = perpendicular(y, loop, terms)
    dots = [dot(t.unit, t.angle, e_unit, e_label, n, loop) for t in terms]
    ok = all(d.value == 0.0 for t, d in zip(terms, dots, strict=True) if t.var == y)
    num_terms, num_subs, den_terms, den_subs = [], [], [], []
    numer, denom = 0.0, 0.0
    for t, d in zip(terms, dots, strict=True):
        if d.value == 0.0 and d.sym == 0 or t.var == y:
            continue
        if d.reason and d.value == 0.0:
            continue
        own = [(k, lab) for k, lab in t.factors if not (t.var == x and k == t.rate_kind)]
        syms = [factor_sym(k, lab) for k, lab in own]
        nums = [factor_num(k, lab, n) for k, lab in own]
        val = t.sign * math.prod(factor_val(k, lab, n) for k, lab in own) * d.value
        if d.sym != 1:
            syms.append(d.sym)
            nums.append(d.num)
        if t.var == x:
            den_terms.append((t.sign, S.prod(*syms)))
            den_subs.append((t.sign, S.prod(*nums)))
            denom += val
        else:  # moved to the other side: the sign flips
            num_terms.append((-t.sign, S.prod(*syms)))
            num_subs.append((-t.sign, S.prod(*nums)))
            numer -= val
    if len(den_terms) == 1 and den_terms[0][0] < 0:
        num_terms = [(-s, e) for s, e in num_terms]
        num_subs = [(-s, e) for s, e in num_subs]
        den_terms, den_subs = [(1, den_terms[0][1])], [(1, den_subs[0][1])]
    closed = _quotient(num_terms, den_terms)
    subs = _quotient(num_subs, den_subs)
    value = numer / denom if denom != 0 else math.nan
    return Elimination(x, rate_symbol(x, loop, terms), e_unit, e_label, dots, closed, subs,
                       value, ok)


def _quotient(num_terms, den_terms):
    top = S.signed_sum(num_terms) if num_terms else sp.Integer(0)
    if len(den_terms) == 1 and den_terms[0] == (1, sp.Integer(1)):
        return top
    return S.Frac(top, S.signed_sum(den_terms))


def dotted_equation(terms: list[Term], el: Elimination):
    """The equation dotted term by term, each product braced with its value:
    ``r_2 thetadot_2 sigma(theta_2).mu(theta_4)`` over ``sin(theta_4 - theta_2)``."""
    e = S.MU(S.th(el.e_label)) if el.e_unit == "mu" else S.SIGMA(S.th(el.e_label))
    parts = []
    for t, d in zip(terms, el.dots, strict=True):
        body = S.prod(*[factor_sym(k, lab) for k, lab in t.factors],
                      S.Dot(unit_sym(t.unit, t.angle), e))
        parts.append((t.sign, S.Brace(body, d.sym)))
    return S.signed_sum(parts), e
