"""Loop-by-loop kinematics in the notes' order: polygon, loop equation, position
table, first variable table, velocity equation and its elimination, velocity
table, second variable table, acceleration equation and its elimination,
acceleration table, and the solver's matrix-method values beside the hand ones.

The hand values are computed here from the notes' closed forms (dot products
with the perpendicular unit vector), loop after loop, from the driver's values
and the loops before; the solver's ``J q' = 0``, ``J q'' = -gamma`` values are only
printed beside them.  Lengths in the file's unit ``ctx.unit``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from analytic.positions import size_of
from reports.explain import numbers as N
from reports.explain import printing as P
from reports.explain import sym as S
from reports.explain.blocks import Heading, Math, Para, Table
from reports.explain.draw import polygon_figure
from reports.explain.loops import Loop, Var, angle, length
from reports.explain.position import solve_loop_position
from reports.explain.terms import (
    Numbers,
    acceleration_terms,
    dotted_equation,
    eliminate,
    equation_sym,
    rate_symbol,
    term_sym,
    velocity_terms,
)

RR, TH = sp.Symbol("r"), sp.Symbol("theta")
MATRIX_V = sp.Eq(sp.Mul(sp.Symbol("J"), sp.Symbol("qdot"), evaluate=False), 0, evaluate=False)
MATRIX_A = sp.Eq(sp.Mul(sp.Symbol("J"), sp.Symbol("qddot"), evaluate=False),
                 S.Neg(sp.Symbol("gamma")), evaluate=False)
DMU = sp.Eq(S.DDt(S.MU(TH)), S.prod(sp.Symbol("thetadot"), S.SIGMA(TH)), evaluate=False)
DSIGMA = sp.Eq(S.DDt(S.SIGMA(TH)), S.Neg(S.prod(sp.Symbol("thetadot"), S.MU(TH))),
               evaluate=False)
CORI1 = S.prod(sp.Symbol("rdot"), sp.Symbol("thetadot"), sp.Symbol("sigma"))
CORI2 = S.prod(2, sp.Symbol("rdot"), sp.Symbol("thetadot"), S.SIGMA(TH))
RDOT, THDOT = sp.Symbol("rdot"), sp.Symbol("thetadot")
RDDOT, THDDOT = sp.Symbol("rddot"), sp.Symbol("thetaddot")


@dataclass
class Ctx:
    """A configuration being worked: the solver's result and the hand values (SI)."""

    mech: object
    lk: object
    kin: object
    polys: object
    unit: str
    L: float                 # metres per file length unit
    q: np.ndarray            # hand positions (solver's where not yet worked)
    qd: np.ndarray
    qdd: np.ndarray
    known: set = field(default_factory=set)
    const_rate: set = field(default_factory=set)
    hand_ok: bool = True
    extra: dict = field(default_factory=dict)   # results later sections refer to

    @property
    def ng(self) -> int:
        return self.lk.topo.n_groups

    def vname(self, loop: Loop, var: Var, dots: int = 0):
        """The unknown as a symbol: theta of its group's first vector, or r of its slider
        vector, with ``dots`` time derivatives."""
        if var.kind == "g":
            return S.th(loop.rate_label[var.index], dots)
        lab = next(v.label for v in loop.vectors if v.slider == var.index)
        return S.r(lab, dots)


def make_ctx(mech, lk, kin, polys, unit: str, L: float) -> Ctx:
    topo = lk.topo
    nq = topo.nq
    ctx = Ctx(mech, lk, kin, polys, unit, L, kin.q[0].copy(), np.full(nq, np.nan),
              np.full(nq, np.nan))
    if polys.driven is not None:
        k = polys.driven.q
        c = topo.driver_row[k]
        ctx.qd[k] = kin.velocity[0] / c
        ctx.qdd[k] = kin.acceleration[0] / c
        ctx.known.add(polys.driven)
        if kin.acceleration[0] == 0.0:
            ctx.const_rate.add(polys.driven)
    return ctx


def numbers(ctx: Ctx, loop: Loop) -> Numbers:
    n = Numbers({}, {}, {}, {}, {}, {})
    for v in loop.vectors:
        n.r[v.label] = length(v, ctx.q, ctx.ng) / ctx.L
        n.theta[v.label] = math.degrees(angle(v, ctx.q))
        i = ctx.ng + v.slider
        n.rdot[v.label] = ctx.qd[i] / ctx.L if v.slider >= 0 else 0.0
        n.rddot[v.label] = ctx.qdd[i] / ctx.L if v.slider >= 0 else 0.0
    for g, lab in loop.rate_label.items():
        n.w[lab] = ctx.qd[g]
        n.al[lab] = ctx.qdd[g]
    return n


def _body(ctx, b) -> str:
    return ctx.lk.topo.body_names[b]


def _body_angle(ctx, b) -> float:
    """A body's own angle (deg, [0, 360)) from the hand positions."""
    topo = ctx.lk.topo
    return math.degrees(ctx.q[topo.group_of[b]] + topo.offset[b]) % 360.0


def _cols(loop):
    return [S.r(v.label) for v in loop.vectors]


def scales(ctx) -> dict[str, float]:
    """The magnitudes the tables' values are computed from (SI): the mechanism's size,
    and the velocity and acceleration scales that its largest rates give.  A value
    below :data:`reports.explain.numbers.ROUNDOFF` of its kind's scale is round-off of a
    zero (a slider passing its origin, a rate at a dwell); anything larger is printed
    at its own scale, however small the mechanism."""
    kin, ng = ctx.kin, ctx.ng
    size = size_of(ctx.lk.topo)
    w, al = (float(np.max(np.abs(x[0, :ng]), initial=0.0)) for x in (kin.qd, kin.qdd))
    sv, sa = (float(np.max(np.abs(x[0, ng:]), initial=0.0)) for x in (kin.qd, kin.qdd))
    v = size * w + sv
    a = size * (al + w * w) + sa + 2.0 * sv * w
    return {"r": size, "v": v, "a": a, "w": v / size, "al": a / size, "deg": 360.0}


def _fmt(ctx, x: float, kind: str, per_unit: bool = True) -> str:
    """A table value of ``kind`` (see :func:`scales`); lengths and their rates in the
    file's unit when ``per_unit``."""
    sc = scales(ctx)[kind]
    if per_unit and kind in ("r", "v", "a"):
        sc /= ctx.L
    return N.fmt(x, scale=sc)


def _deg_cell(a: float) -> str:
    s = N.fmt(a, scale=360.0)
    return s + (f" ({N.fmt(a - 360.0, scale=360.0)})" if a > 180.0 else "")


def _rate_cell(loop, v, vals, ctx, which):
    """thetadot / thetaddot of a vector's angle: 0 on the ground."""
    if v.group < 0:
        return "0"
    return _fmt(ctx, vals[loop.rate_label[v.group]], which)


# -- sections --------------------------------------------------------------------------------

def polygon_section(ctx: Ctx, loop: Loop, n: int) -> list:
    _mech, nums = ctx.mech, ctx.polys.numbers
    out = [Heading(2, f"Loop {n}" + (f" (the solver's loop {loop.index + 1})"
                                     if loop.index + 1 != n else "")),
           Heading(3, "Vector polygon")]
    lines = []
    for v in loop.vectors:
        who = (f"in link {nums[v.body]} ({_body(ctx, v.body)})" if v.kind == "body" else
               f"the slider {_body(ctx, v.body)} (link {nums[v.body]}) on its line: "
               "a vector of variable length")
        lines.append(f"r{v.label}: from {v.tail} to {v.head}, {who}")
    out.append(Para(["Links are numbered as in the notes: the ground 1, then "
                     + ", ".join(f"{_body(ctx, b)} {k}" for b, k in sorted(
                         nums.items(), key=lambda kv: kv[1]) if k > 1)
                     + ". The vectors of this loop, tip to tail: " + "; ".join(lines) + "."]))
    out.append(polygon_figure(ctx, loop, n))
    return out


def loop_equation(ctx: Ctx, loop: Loop) -> list:
    eq = S.signed_sum([(1, S.prod(S.r(v.label), S.MU(S.th(v.label)))) for v in loop.vectors])
    return [Heading(3, "Loop equation"),
            Para(["Each vector is its length times the unit vector of its angle, "
                  "μ(θ) = (cos θ, sin θ); σ(θ) = (−sin θ, cos θ) is μ turned by +90°:"]),
            Math([eq, sp.Integer(0)])]


def position_section(ctx: Ctx, loop: Loop, n: int) -> list:
    out = [Heading(3, "Position")]
    nn = numbers(ctx, loop)
    if loop.unknowns:
        want = {v.label: (length(v, ctx.kin.q[0], ctx.ng) / ctx.L,
                          math.degrees(angle(v, ctx.kin.q[0]))) for v in loop.vectors}
        res = solve_loop_position(loop, nn.r, nn.theta, want)
        if res is None:
            out.append(Para(["This loop is not one of the notes' hand cases; its position "
                             "comes from the solver's closed-form dyads."]))
        else:
            blocks, vals = res
            out += blocks
            for v in loop.vectors:
                if v.label in vals:
                    rr, tt = vals[v.label]
                    if v.slider >= 0:
                        ctx.q[ctx.ng + v.slider] = rr * ctx.L
                    if v.group >= 0 and v.group in [u.index for u in loop.unknowns
                                                    if u.kind == "g"]:
                        ctx.q[v.group] = (math.radians(tt) - v.beta)
        nn = numbers(ctx, loop)
    out.append(Table(f"position-{n}", f"Position table, loop {n} (lengths in {ctx.unit}, "
                     "angles in degrees; in brackets the same angle in (−180°, 180°])",
                     ["", "unit"] + _cols(loop),
                     [[RR, ctx.unit] + [_fmt(ctx, nn.r[v.label], "r") for v in loop.vectors],
                      [TH, "deg"] + [_deg_cell(nn.theta[v.label]) for v in loop.vectors]]))
    notes = [f"θ{v.label} is the angle of the loop vector r{v.label}; the "
             f"{_body(ctx, v.body)}'s own x axis is at {N.fmt(_body_angle(ctx, v.body))}°"
             for v in loop.vectors if v.kind == "body" and v.group >= 0
             and abs((angle(v, ctx.q) - math.radians(_body_angle(ctx, v.body)) + math.pi)
                     % (2 * math.pi) - math.pi) > 1e-9]
    if notes:
        out.append(Para(["; ".join(notes) + "."]))
    return out


def variable_table_1(ctx: Ctx, loop: Loop, n: int) -> list:
    return [Heading(3, "First variable table"),
            Para(["Which magnitudes and angles change as the linkage moves "
                  "(S constant, D variable):"]),
            Table(f"variables1-{n}", f"First variable table, loop {n}", [""] + _cols(loop),
                  [[RR] + ["D" if v.var_length else "S" for v in loop.vectors],
                   [TH] + ["D" if v.var_angle else "S" for v in loop.vectors]])]


def _mark(ctx, loop, v, which) -> str:
    """Second-table mark of a vector's rdot or thetadot: S, S* or D."""
    if which == "r":
        if not v.var_length:
            return "S"
        var = Var("s", v.slider, ctx.ng + v.slider)
    else:
        if not v.var_angle:
            return "S"
        var = Var("g", v.group, v.group)
    return "S*" if var in ctx.const_rate else "D"


def velocity_equation(ctx: Ctx, loop: Loop) -> tuple[list, list]:
    terms = velocity_terms(loop, ctx.ng)
    out = [Heading(3, "Velocity equation"),
           Para(["Differentiate each vector with ", DMU, "; a constant (S) factor has no "
                 "derivative:"])]
    for v in loop.vectors:
        mine = [t for t in terms if t.angle == v.label]
        rhs = S.signed_sum([(t.sign, term_sym(t)) for t in mine]) if mine else sp.Integer(0)
        why = (f"r{v.label} {'D' if v.var_length else 'S'}, "
               f"θ{v.label} {'D' if v.var_angle else 'S'}")
        out.append(Math([S.DDt(S.prod(S.r(v.label), S.MU(S.th(v.label)))), rhs], note=why))
    for v in loop.vectors:
        rl = loop.rate_label.get(v.group)
        if rl is not None and rl != v.label:
            w = next(u for u in loop.vectors if u.label == rl)
            off = math.degrees(v.beta - w.beta) % 360.0
            out.append(Para([S.th(v.label), " = ", S.th(rl), f" + {N.fmt(off)}°: r{v.label} "
                             f"and r{rl} turn together (one rotation), so ",
                             S.th(v.label, 1), " = ", S.th(rl, 1), "."]))
    out.append(Para(["The velocity equation:"]))
    out.append(Math([equation_sym(terms), sp.Integer(0)]))
    return out, terms


def _solve_for(ctx, loop, terms, nn, what: str) -> list:
    """Both unknowns by elimination; stores the values in ctx (SI)."""
    out = []
    x0, y0 = loop.unknowns
    for x, y in ((x0, y0), (y0, x0)):
        el = eliminate(loop, terms, x, y, nn)
        if not el.ok:
            ctx.hand_ok = False
            out.append(Para(["The terms of ", ctx.vname(loop, y), " are not along one unit "
                             "vector here, so one dot product cannot remove them; the "
                             "solver's matrix method gives this loop's ", what, "."]))
            src = ctx.kin.qd if what == "velocity" else ctx.kin.qdd
            store = ctx.qd if what == "velocity" else ctx.qdd
            for u in loop.unknowns:
                store[u.q] = src[0, u.q]
            return out
        ysym = rate_symbol(y, loop, terms)
        e = S.MU(S.th(el.e_label)) if el.e_unit == "mu" else S.SIGMA(S.th(el.e_label))
        other_unit = "σ" if el.e_unit == "mu" else "μ"
        e_name = "μ" if el.e_unit == "mu" else "σ"
        dotted, _ = dotted_equation(terms, el)
        unit = _unit_of(ctx, x, what)
        out += [
            Para(["To find ", el.x_sym, ", eliminate ", ysym, f": it multiplies "
                  f"{other_unit}(θ{el.e_label}), so dot the equation with ", e,
                  f" ({other_unit}(θ{el.e_label})·{e_name}(θ{el.e_label}) = 0: "
                  "perpendicular unit vectors, 'outer different, inner same' in the "
                  "notes):"]),
            Math([S.Dot(e, S.Bracket(equation_sym(terms))), sp.Integer(0)]),
            Math([dotted, sp.Integer(0)],
                 note="under each term its dot product: μ(a)·μ(b) = σ(a)·σ(b) = cos(a − b), "
                      "μ(a)·σ(b) = sin(a − b), σ(a)·μ(b) = sin(b − a)"),
            Math([el.x_sym, el.closed, el.substituted], N.fmt_of(el.value, el.substituted), unit,
                 P.text(el.substituted)),
        ]
        store = ctx.qd if what == "velocity" else ctx.qdd
        store[x.q] = el.value * (ctx.L if x.kind == "s" else 1.0)
    return out


def _unit_of(ctx, var, what) -> str:
    if var.kind == "s":
        return f"{ctx.unit}/s" if what == "velocity" else f"{ctx.unit}/s^2"
    return "rad/s" if what == "velocity" else "rad/s^2"


def velocity_section(ctx: Ctx, loop: Loop, n: int) -> list:
    out, terms = velocity_equation(ctx, loop)
    u0, u1 = loop.unknowns
    out.append(Para(["The unknowns are ", ctx.vname(loop, u0, 1), " and ",
                     ctx.vname(loop, u1, 1), "; everything else is known (the input and "
                     "the loops before)."]))
    out += _solve_for(ctx, loop, terms, numbers(ctx, loop), "velocity")
    nn = numbers(ctx, loop)
    out.append(Table(f"velocity-{n}", f"Velocity table, loop {n} (rates of lengths in "
                     f"{ctx.unit}/s, of angles in rad/s)", ["", "unit"] + _cols(loop),
                     [[RDOT, f"{ctx.unit}/s"] + [_fmt(ctx, nn.rdot[v.label], "v")
                                                 for v in loop.vectors],
                      [THDOT, "rad/s"] + [_rate_cell(loop, v, nn.w, ctx, "w")
                                       for v in loop.vectors]]))
    return out


def variable_table_2(ctx: Ctx, loop: Loop, n: int) -> list:
    marks_r = [_mark(ctx, loop, v, "r") for v in loop.vectors]
    marks_t = [_mark(ctx, loop, v, "t") for v in loop.vectors]
    u0, u1 = loop.unknowns
    return [Heading(3, "Second variable table"),
            Para(["How the rates change (S: no rate, the quantity is constant; S*: constant "
                  "rate; D: variable rate). A D entry has a second derivative in the "
                  "acceleration equation; a one-degree-of-freedom loop must leave exactly "
                  "two unknown ones: here ", ctx.vname(loop, u0, 2), " and ",
                  ctx.vname(loop, u1, 2), "."]),
            Table(f"variables2-{n}", f"Second variable table, loop {n}", [""] + _cols(loop),
                  [[RDOT] + marks_r, [THDOT] + marks_t])]


def acceleration_section(ctx: Ctx, loop: Loop, n: int) -> list:
    vterms = velocity_terms(loop, ctx.ng)
    aterms = acceleration_terms(loop, ctx.ng, ctx.const_rate)
    out = [Heading(3, "Acceleration equation"),
           Para(["Differentiate each velocity term by the product rule; a factor marked "
                 "S or S* in the second table has no derivative, ", DSIGMA, ":"])]
    for t in vterms:
        out.append(Math([S.DDt(term_sym(t)), _derivative(ctx, loop, t)],
                        note=_why(ctx, loop, t)))
    if any(f[0] == "two" for t in aterms for f in t.factors):
        out.append(Para(["Where a vector changes both its length and its angle (a slider on "
                         "a turning guide), the two ", CORI1, " terms add up to the Coriolis term ",
                         CORI2, "."]))
    out.append(Para(["The acceleration equation:"]))
    out.append(Math([equation_sym(aterms), sp.Integer(0)]))
    out += _solve_for(ctx, loop, aterms, numbers(ctx, loop), "acceleration")
    nn = numbers(ctx, loop)
    out.append(Table(f"acceleration-{n}", f"Acceleration table, loop {n} ("
                     f"lengths in {ctx.unit}/s², angles in rad/s²)", ["", "unit"] + _cols(loop),
                     [[RDDOT, f"{ctx.unit}/s²"] + [_fmt(ctx, nn.rddot[v.label], "a")
                                                for v in loop.vectors],
                      [THDDOT, "rad/s²"] + [_rate_cell(loop, v, nn.al, ctx, "al")
                                        for v in loop.vectors]]))
    return out


def _derivative(ctx, loop, t):
    """d/dt of one velocity term, by the product rule and the variable tables."""
    v = next(u for u in loop.vectors if u.label == t.angle)
    parts = []
    g = Var("g", v.group, v.group) if v.group >= 0 else None
    s = Var("s", v.slider, ctx.ng + v.slider) if v.slider >= 0 else None
    rl = loop.rate_label.get(v.group, "")
    if t.unit == "mu":  # rdot mu(theta)
        if s not in ctx.const_rate:
            parts.append((1, S.prod(S.r(v.label, 2), S.MU(S.th(v.label)))))
        if g is not None:
            parts.append((1, S.prod(S.r(v.label, 1), S.th(rl, 1), S.SIGMA(S.th(v.label)))))
    else:  # r thetadot sigma(theta)
        if s is not None:
            parts.append((1, S.prod(S.r(v.label, 1), S.th(rl, 1), S.SIGMA(S.th(v.label)))))
        if g not in ctx.const_rate:
            parts.append((1, S.prod(S.r(v.label), S.th(rl, 2), S.SIGMA(S.th(v.label)))))
        parts.append((-1, S.prod(S.r(v.label), S.sq(S.th(rl, 1)), S.MU(S.th(v.label)))))
    return S.signed_sum(parts) if parts else sp.Integer(0)


def _why(ctx, loop, t) -> list:
    v = next(u for u in loop.vectors if u.label == t.angle)
    if t.unit == "mu":
        return [S.r(v.label, 1), f" {_mark(ctx, loop, v, 'r')}, ", S.MU(S.th(v.label)),
                f" {'D' if v.var_angle else 'S'}"]
    return [S.r(v.label), f" {'D' if v.var_length else 'S'}, ",
            S.th(loop.rate_label[v.group], 1), f" {_mark(ctx, loop, v, 't')}, ",
            S.SIGMA(S.th(v.label)), " D"]


def matrix_section(ctx: Ctx, loop: Loop, n: int) -> list:
    """The hand values beside the solver's (``J q' = 0``, ``J q'' = -gamma``)."""
    kin = ctx.kin
    rows = []
    for u in loop.unknowns:
        nm = [ctx.vname(loop, u, d) for d in range(3)]
        sc = 1.0 / ctx.L if u.kind == "s" else 1.0
        if u.kind == "g":
            v = next(w for w in loop.vectors if w.group == u.index)
            pos_h = math.degrees(angle(v, ctx.q))
            pos_m = math.degrees(angle(v, kin.q[0]))
            unit_p, unit_v, unit_a = "deg", "rad/s", "rad/s²"
            kinds = ("deg", "w", "al")
        else:
            pos_h, pos_m = ctx.q[u.q] * sc, kin.q[0, u.q] * sc
            unit_p, unit_v, unit_a = ctx.unit, f"{ctx.unit}/s", f"{ctx.unit}/s²"
            kinds = ("r", "v", "a")
        for q_, h, m, un, kd in ((nm[0], pos_h, pos_m, unit_p, kinds[0]),
                                 (nm[1], ctx.qd[u.q] * sc, kin.qd[0, u.q] * sc, unit_v,
                                  kinds[1]),
                                 (nm[2], ctx.qdd[u.q] * sc, kin.qdd[0, u.q] * sc, unit_a,
                                  kinds[2])):
            rows.append([q_, un, _fmt(ctx, h, kd), _fmt(ctx, m, kd), f"{abs(h - m):.2g}"])
    return [Heading(3, "Hand method beside the matrix method"),
            Para(["The solver writes all loops at once as ", MATRIX_V, " and ", MATRIX_A,
                  " (J the loop Jacobian, q the unknown angles and lengths, γ the velocity-"
                  "product terms) and solves the "
                  "linear systems; its values beside the hand method's:"]),
            Table(f"matrix-{n}", f"Loop {n}: hand method and matrix method",
                  ["quantity", "unit", "hand method", "matrix method", "|difference|"], rows)]


def loop_sections(ctx: Ctx, loop: Loop, n: int) -> list:
    out = polygon_section(ctx, loop, n) + loop_equation(ctx, loop)
    out += position_section(ctx, loop, n) + variable_table_1(ctx, loop, n)
    out += velocity_section(ctx, loop, n) + variable_table_2(ctx, loop, n)
    out += acceleration_section(ctx, loop, n) + matrix_section(ctx, loop, n)
    ctx.known.update(loop.unknowns)
    return out


def coupled_section(ctx: Ctx, loop: Loop, n: int) -> list:
    """A loop whose unknowns cannot be taken two at a time: the matrix method."""
    kin = ctx.kin
    ctx.q[:] = kin.q[0]
    out = polygon_section(ctx, loop, n) + loop_equation(ctx, loop)
    out.append(Para(["This loop shares more than two unknowns with the loops not yet "
                     "solved, so it cannot be solved alone by the notes' elimination; the "
                     "solver's matrix method gives its values."]))
    for u in [w for w in ctx.polys.variables if w not in ctx.known]:
        ctx.qd[u.q], ctx.qdd[u.q] = kin.qd[0, u.q], kin.qdd[0, u.q]
        ctx.known.add(u)
    nn = numbers(ctx, loop)
    src = " (matrix method)"
    out += [Table(f"position-{n}", f"Position table, loop {n}{src}", ["", "unit"] + _cols(loop),
                  [[RR, ctx.unit] + [_fmt(ctx, nn.r[v.label], "r") for v in loop.vectors],
                   [TH, "deg"] + [_deg_cell(nn.theta[v.label]) for v in loop.vectors]]),
            Table(f"velocity-{n}", f"Velocity table, loop {n}{src}", ["", "unit"] + _cols(loop),
                  [[RDOT, f"{ctx.unit}/s"] + [_fmt(ctx, nn.rdot[v.label], "v")
                                                 for v in loop.vectors],
                   [THDOT, "rad/s"] + [_rate_cell(loop, v, nn.w, ctx, "w")
                                       for v in loop.vectors]]),
            Table(f"acceleration-{n}", f"Acceleration table, loop {n}{src}",
                  ["", "unit"] + _cols(loop),
                  [[RDDOT, f"{ctx.unit}/s²"] + [_fmt(ctx, nn.rddot[v.label], "a")
                                                   for v in loop.vectors],
                   [THDDOT, "rad/s²"] + [_rate_cell(loop, v, nn.al, ctx, "al")
                                         for v in loop.vectors]])]
    return out
