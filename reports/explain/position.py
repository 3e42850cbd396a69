"""Position analysis of one loop by hand: the two unknowns from the loop equation.

The cases the notes meet, by the kind of the loop's two unknowns:

* two angles (a four-bar's coupler and rocker): the known vectors are moved to
  the right-hand side, ``D = -(known)``, and the triangle with sides
  ``r_a, r_b, |D|`` gives ``theta_a = delta +- arccos(...)`` (law of cosines);
* an angle and a length along a known direction (the slider-crank): dotting with
  ``sigma`` of that direction removes the length (the notes' route in week 4),
  dotting with ``mu`` of it gives the length;
* an angle and a length on the same vector (a block in a pivoted slot): that
  vector is ``-(known)``, its angle and length are the polar form;
* two lengths along known directions: two dot products.

Each has two branches; the one the solver assembled (the description's assembly
hints) is taken and the other is named.  Anything else is left to the solver's
closed-form dyads and said so.  Values in the file's length unit and degrees.
"""

from __future__ import annotations

import math

import sympy as sp

from reports.explain import numbers as N
from reports.explain import printing as P
from reports.explain import sym as S
from reports.explain.blocks import Math, Para
from reports.explain.loops import Loop, LoopVector, Var

DEG = math.pi / 180.0


def _wrap(a: float) -> float:
    return a % 360.0


def _close(a: float, b: float) -> float:
    d = (a - b) % 360.0
    return min(d, 360.0 - d)


def _known_vectors(loop: Loop, unknown_labels) -> list[LoopVector]:
    return [v for v in loop.vectors if v.label not in unknown_labels]


def _vec_for(loop: Loop, var: Var) -> list[LoopVector]:
    if var.kind == "g":
        return [v for v in loop.vectors if v.group == var.index]
    return [v for v in loop.vectors if v.slider == var.index]


def _sum_sym(vs, fn):
    return S.signed_sum([(1, S.prod(S.r(v.label), fn(S.th(v.label)))) for v in vs])


def _sum_num(vs, fn, r, th):
    return S.signed_sum([(1, S.prod(N.num(r[v.label]), fn(S.Deg(N.num(th[v.label])))))
                         for v in vs])


def solve_loop_position(loop: Loop, r: dict, th: dict, want: dict):
    """Solve the two unknowns of ``loop`` by hand.

    ``r``/``th`` hold the known lengths (file unit) and angles (deg); ``want`` the
    solver's values of the unknown vectors' ``(r, theta)`` by label, used only to
    pick the branch.  Returns ``(blocks, values)`` with ``values`` label ->
    ``(r, theta)``, or ``None`` when the loop is not one of the hand cases.
    """
    x, y = loop.unknowns
    vx, vy = _vec_for(loop, x), _vec_for(loop, y)
    kinds = (x.kind, y.kind)
    if kinds == ("g", "g") and len(vx) == 1 and len(vy) == 1 \
            and not vx[0].var_length and not vy[0].var_length:
        return _two_angles(loop, vx[0], vy[0], r, th, want)
    if set(kinds) == {"g", "s"}:
        g, s = (x, y) if x.kind == "g" else (y, x)
        vg, vs = _vec_for(loop, g), _vec_for(loop, s)
        if len(vs) == 1 and vs[0].group != g.index and len(vg) == 1:
            return _angle_and_length(loop, vg[0], vs[0], r, th, want)
        if len(vs) == 1 and vg == vs:
            return _polar(loop, vs[0], r, th, want)
    if kinds == ("s", "s") and len(vx) == 1 and len(vy) == 1 \
            and not vx[0].var_angle and not vy[0].var_angle:
        return _two_lengths(loop, vx[0], vy[0], r, th)
    return None


def _dvec(loop, unknown, r, th):
    """``D = -(sum of the known vectors)``: components, symbolic and substituted."""
    known = _known_vectors(loop, unknown)
    dx = -sum(r[v.label] * math.cos(th[v.label] * DEG) for v in known)
    dy = -sum(r[v.label] * math.sin(th[v.label] * DEG) for v in known)
    blocks = [
        Math([S.name("D", "x"), S.Neg(_sum_sym(known, S.cos)), S.Neg(_sum_num(known, S.cos,
                                                                            r, th))],
             N.fmt_of(dx, S.Neg(_sum_num(known, S.cos, r, th))), "",
             P.text(S.Neg(_sum_num(known, S.cos, r, th)))),
        Math([S.name("D", "y"), S.Neg(_sum_sym(known, S.sin)), S.Neg(_sum_num(known, S.sin,
                                                                            r, th))],
             N.fmt_of(dy, S.Neg(_sum_num(known, S.sin, r, th))), "",
             P.text(S.Neg(_sum_num(known, S.sin, r, th)))),
    ]
    return dx, dy, blocks


def _two_angles(loop, va, vb, r, th, want):
    a, b = va.label, vb.label
    dx, dy, blocks = _dvec(loop, {a, b}, r, th)
    d = math.hypot(dx, dy)
    delta = math.degrees(math.atan2(dy, dx))
    ra, rb = r[a], r[b]
    c = (ra * ra + d * d - rb * rb) / (2 * ra * d)
    if abs(c) > 1:
        return None
    gam = math.degrees(math.acos(c))
    cands = [_wrap(delta + gam), _wrap(delta - gam)]
    k = min((0, 1), key=lambda i: _close(cands[i], want[a][1]))
    ta = cands[k]
    tb = _wrap(math.degrees(math.atan2(dy - ra * math.sin(ta * DEG),
                                       dx - ra * math.cos(ta * DEG))))
    Dx, Dy, Dm, dl = S.name("D", "x"), S.name("D", "y"), sp.Symbol("D"), sp.Symbol("delta")
    nDx, nDy = N.num(dx), N.num(dy)
    mag = sp.sqrt(sp.Add(S.sq(nDx), S.sq(nDy), evaluate=False), evaluate=False)
    sgn = 1 if k == 0 else -1
    acos_sym = S.acos(S.Frac(sp.Add(S.sq(S.r(a)), S.sq(Dm), sp.Mul(-1, S.sq(S.r(b)),
                                                                     evaluate=False),
                                    evaluate=False), S.prod(2, S.r(a), Dm)))
    acos_num = S.acos(S.Frac(sp.Add(S.sq(N.num(ra)), S.sq(N.num(d)),
                                    sp.Mul(-1, S.sq(N.num(rb)), evaluate=False),
                                    evaluate=False), S.prod(2, N.num(ra), N.num(d))))
    ta_num = S.signed_sum([(1, N.num(delta)), (sgn, acos_num)])
    tb_num = S.atan2(S.signed_sum([(1, N.num(dy)), (-1, S.prod(N.num(ra), S.sin(S.Deg(
        N.num(ta)))))]), S.signed_sum([(1, N.num(dx)), (-1, S.prod(N.num(ra), S.cos(S.Deg(
            N.num(ta)))))]))
    tb_raw = math.degrees(math.atan2(dy - ra * math.sin(ta * DEG), dx - ra * math.cos(ta * DEG)))
    blocks = [
        Para([f"Two angles are unknown, θ{a} and θ{b}. Move the known vectors to the "
              "right-hand side: ", S.prod(S.r(a), S.MU(S.th(a))), " + ",
              S.prod(S.r(b), S.MU(S.th(b))), " = D, with D = −(sum of the known vectors):"]),
        *blocks,
        Math([Dm, sp.sqrt(sp.Add(S.sq(Dx), S.sq(Dy), evaluate=False), evaluate=False), mag],
             N.fmt_of(d, mag), "", P.text(mag)),
        Math([dl, S.atan2(Dy, Dx), S.atan2(nDy, nDx)], N.fmt_of(delta, S.atan2(nDy, nDx)), "deg",
             P.text(S.atan2(nDy, nDx))),
        Para([f"r{a}, r{b} and D form a triangle; the law of cosines gives the angle between "
              f"D and r{a}:"]),
        Math([S.th(a), S.signed_sum([(1, dl), (sgn, acos_sym)]), ta_num], N.fmt_of(
            delta + sgn * gam, ta_num), "deg", P.text(ta_num),
             note=f"the sign {'+' if sgn > 0 else '−'} is the description's assembly; the "
                  f"other sign gives the other branch, θ{a} = {N.fmt(cands[1 - k])}°"),
        Math([S.th(b), S.atan2(sp.Add(Dy, sp.Mul(-1, S.r(a), S.sin(S.th(a)), evaluate=False),
                                      evaluate=False),
                               sp.Add(Dx, sp.Mul(-1, S.r(a), S.cos(S.th(a)), evaluate=False),
                                      evaluate=False)), tb_num],
             N.fmt_of(tb_raw, tb_num), "deg", P.text(tb_num),
             note=f"= {N.fmt(tb)}° in [0°, 360°)" if abs(tb - tb_raw) > 1e-9 else ""),
    ]
    return blocks, {a: (ra, ta), b: (rb, tb)}


def _angle_and_length(loop, va, vs, r, th, want):
    """The notes' slider-crank route: sigma(theta_s) removes r_s, mu(theta_s) gives it."""
    a, s = va.label, vs.label
    ts = th[s]
    known = _known_vectors(loop, {a, s})
    ssum = -sum(r[v.label] * math.sin((th[v.label] - ts) * DEG) for v in known) / r[a]
    if abs(ssum) > 1:
        return None
    base = math.degrees(math.asin(ssum))
    cands = [_wrap(ts + base), _wrap(ts + 180.0 - base)]
    k = min((0, 1), key=lambda i: _close(cands[i], want[a][1]))
    ta = cands[k]
    tsym, tnum = S.th(s), S.Deg(N.num(ts))

    def sin_terms(vs_, num):
        if num:
            return S.signed_sum([(1, S.prod(N.num(r[v.label]), S.sin(S.diff_angle(
                S.Deg(N.num(th[v.label])), tnum)))) for v in vs_])
        return S.signed_sum([(1, S.prod(S.r(v.label), S.sin(S.diff_angle(S.th(v.label), tsym))))
                             for v in vs_])

    asin_sym = S.asin(S.Frac(S.Neg(sin_terms(known, False)), S.r(a)))
    asin_num = S.asin(S.Frac(S.Neg(sin_terms(known, True)), N.num(r[a])))
    if k == 0:
        ta_sym = sp.Add(tsym, asin_sym, evaluate=False)
        ta_num = sp.Add(N.num(ts), asin_num, evaluate=False)
        ta_raw = ts + base
    else:
        ta_sym = S.signed_sum([(1, tsym), (1, N.num(180)), (-1, asin_sym)])
        ta_num = S.signed_sum([(1, N.num(ts)), (1, N.num(180)), (-1, asin_num)])
        ta_raw = ts + 180.0 - base
    allk = known + [va]
    th2 = dict(th)
    th2[a] = ta
    rs = -sum(r[v.label] * math.cos((th2[v.label] - ts) * DEG) for v in allk)
    cos_sym = S.Neg(S.signed_sum([(1, S.prod(S.r(v.label), S.cos(S.diff_angle(
        S.th(v.label), tsym)))) for v in allk]))
    cos_num = S.Neg(S.signed_sum([(1, S.prod(N.num(r[v.label]), S.cos(S.diff_angle(
        S.Deg(N.num(th2[v.label])), tnum)))) for v in allk]))
    eq = S.signed_sum([(1, S.prod(S.r(v.label), S.MU(S.th(v.label)))) for v in loop.vectors])
    blocks = [
        Para([f"The unknowns are the angle θ{a} and the length r{s}, whose direction θ{s} = "
              f"{N.fmt(ts)}° is known. Dot the loop equation with σ(θ{s}): the r{s} term "
              f"vanishes (μ(θ{s})·σ(θ{s}) = 0) and μ(θk)·σ(θ{s}) = sin(θk − θ{s}):"]),
        Math([S.Dot(S.SIGMA(tsym), S.Bracket(eq)), sp.Integer(0)]),
        Math([S.signed_sum([(1, S.prod(S.r(v.label), S.sin(S.diff_angle(S.th(v.label), tsym))))
                            for v in allk]), sp.Integer(0)]),
        Math([S.th(a), ta_sym, ta_num], N.fmt_of(ta_raw, ta_num), "deg", P.text(ta_num),
             note=(f"= {N.fmt(ta)}° in [0°, 360°)"
                   + (f", i.e. {N.fmt(ta - 360)}°" if ta > 180 else "")
                   + f"; the other root, θ{a} = {N.fmt(cands[1 - k])}°, is the other branch")),
        Para([f"Dot the loop equation with μ(θ{s}) (μ(θk)·μ(θ{s}) = cos(θk − θ{s})) for "
              f"r{s}:"]),
        Math([S.r(s), cos_sym, cos_num], N.fmt_of(rs, cos_num), "", P.text(cos_num)),
    ]
    return blocks, {a: (r[a], ta), s: (rs, ts)}


def _polar(loop, vs, r, th, want):
    """A length and its own angle (a block sliding in a pivoted slot)."""
    s = vs.label
    dx, dy, blocks = _dvec(loop, {s}, r, th)
    d = math.hypot(dx, dy)
    t0 = _wrap(math.degrees(math.atan2(dy, dx)))
    flip = _close(t0, want[s][1]) > 90.0
    ts, rs = (_wrap(t0 + 180.0), -d) if flip else (t0, d)
    Dx, Dy = S.name("D", "x"), S.name("D", "y")
    nDx, nDy = N.num(dx), N.num(dy)
    mag = sp.sqrt(sp.Add(S.sq(nDx), S.sq(nDy), evaluate=False), evaluate=False)
    raw = math.degrees(math.atan2(dy, dx))
    blocks = [
        Para([f"The unknowns are the length r{s} and its own angle θ{s}: "
              f"r{s} μ(θ{s}) = D = −(sum of the known vectors), so r{s} and θ{s} are D in "
              "polar form:"]),
        *blocks,
        Math([S.r(s), sp.sqrt(sp.Add(S.sq(Dx), S.sq(Dy), evaluate=False), evaluate=False),
              mag], N.fmt_of(d, mag), "", P.text(mag),
             note=f"taken negative, r{s} = {N.fmt(rs)}, with θ{s} turned by 180°: the "
                  "description's assembly" if flip else ""),
        Math([S.th(s), S.atan2(Dy, Dx), S.atan2(nDy, nDx)], N.fmt_of(raw, S.atan2(nDy, nDx)),
             "deg",
             P.text(S.atan2(nDy, nDx)),
             note=f"θ{s} = {N.fmt(ts)}° in [0°, 360°)" if abs(ts - raw) > 1e-9 else ""),
    ]
    return blocks, {s: (rs, ts)}


def _two_lengths(loop, va, vb, r, th):
    a, b = va.label, vb.label
    known = _known_vectors(loop, {a, b})
    blocks, out = [], {}
    for x, other in ((a, b), (b, a)):
        to = th[other]
        num_sym = S.Neg(S.signed_sum([(1, S.prod(S.r(v.label), S.sin(S.diff_angle(
            S.th(v.label), S.th(other))))) for v in known]))
        num_num = S.Neg(S.signed_sum([(1, S.prod(N.num(r[v.label]), S.sin(S.diff_angle(
            S.Deg(N.num(th[v.label])), S.Deg(N.num(to)))))) for v in known]))
        den_sym = S.sin(S.diff_angle(S.th(x), S.th(other)))
        den_num = S.sin(S.diff_angle(S.Deg(N.num(th[x])), S.Deg(N.num(to))))
        val = (-sum(r[v.label] * math.sin((th[v.label] - to) * DEG) for v in known)
               / math.sin((th[x] - to) * DEG))
        expr = S.Frac(num_num, den_num)
        blocks += [Para([f"Dot with σ(θ{other}) to remove r{other}:"]),
                   Math([S.r(x), S.Frac(num_sym, den_sym), expr], N.fmt_of(val, expr), "",
                        P.text(expr))]
        out[x] = (val, th[x])
    return blocks, out
