"""Kinetostatics in the notes' way: inertia forces and moments (d'Alembert), the
offset e = I alpha / (m a_G) of the resultant inertia force, the equilibrium
equations of every moving body, the joint forces, and the motor's torque and
power with the power balance as the check.

Every body gives ``sum F_x = 0``, ``sum F_y = 0`` and ``sum M_G = 0`` (moments about
its centre of mass) with the inertia force ``-m a_G`` and moment ``-I alpha``; the
unknowns are two per revolute joint (``F_ab``, the force by link a on link b), two
per slider (the normal force ``N_ab`` along the line's normal ``n``, at the slider
point, and the couple ``M_ab``, both by the guide on the slider) and the drive
effort: ``3 (n - 1)`` equations and unknowns, solved together here.  The solver's
tree-reduced method (:mod:`analytic.kinetostatics`) is printed beside.  SI units
throughout (m, kg, N, N m, W).
"""

from __future__ import annotations

import cmath
import math

import numpy as np
import sympy as sp

from analytic.mechanism import Revolute
from analytic.positions import size_of
from reports.explain import numbers as N
from reports.explain import printing as P
from reports.explain import sym as S
from reports.explain.blocks import Heading, Math, Para, Table


def _cross(a: complex, b: complex) -> float:
    return a.real * b.imag - a.imag * b.real


def _snap(z: complex, rel: float = 1e-12) -> complex:
    """Round-off-level components (below ``rel`` of the vector's size) set to 0."""
    tol = rel * abs(z)
    return complex(0.0 if abs(z.real) < tol else z.real, 0.0 if abs(z.imag) < tol else z.imag)


def _dot_expr(a: complex, b: complex):
    """``a_x b_x + a_y b_y`` as printed, without the zero products (None if all are)."""
    parts = [S.prod(N.num(p), N.num(q)) for p, q in ((a.real, b.real), (a.imag, b.imag))
             if p != 0 and q != 0]
    if not parts:
        return None
    return parts[0] if len(parts) == 1 else sp.Add(*parts, evaluate=False)


def _unknowns(ctx):
    """``[(symbol, joint index, role)]`` in order; role fx, fy, N, M or effort."""
    mech, nums, topo = ctx.mech, ctx.polys.numbers, ctx.lk.topo
    out = []
    for j, jt in enumerate(mech.joints):
        a, b = (nums[topo.body_names.index(n)] for n in jt.bodies)
        if isinstance(jt, Revolute):
            out += [(S.name("F", f"{a}{b}x"), j, "fx"), (S.name("F", f"{a}{b}y"), j, "fy")]
        else:
            out += [(S.name("N", f"{a}{b}"), j, "N"), (S.name("M", f"{a}{b}"), j, "M")]
    rev = isinstance(mech.driver_joint, Revolute)
    out.append((sp.Symbol("T") if rev else S.name("F", "d"), topo.driver_joint, "effort"))
    return out


def _equations(ctx):
    """Per moving body: ``(rows, consts, info)`` with rows ``{unknown index: coefficient}``
    for x, y and moment, consts the known parts (inertia, loads, gravity)."""
    mech, kin, topo = ctx.mech, ctx.kin, ctx.lk.topo
    unk = _unknowns(ctx)
    g = complex(*mech.gravity)
    out = []
    for b in topo.order[1:]:
        body = mech.bodies[b]
        rG, vG, aG = (_snap(complex(z[0])) for z in kin.com_c(b))
        rows = [dict(), dict(), dict()]
        for i, (_, j, role) in enumerate(unk):
            jt = mech.joints[j]
            if body.name not in jt.bodies:
                continue
            on_b = 1.0 if body.name == jt.body_b else -1.0
            P = complex(kin.joint_point[j][0])
            r = P - rG
            if role in ("fx", "fy"):
                f = on_b * (1.0 if role == "fx" else 1j)
            elif role == "N":
                f = on_b * kin.E[0, topo.body_names.index(jt.guide)] * 1j * cmath.exp(
                    1j * jt.direction)
            elif role == "M":
                rows[2][i] = on_b
                continue
            elif isinstance(jt, Revolute):  # drive torque
                rows[2][i] = on_b
                continue
            else:  # drive force along the line
                f = on_b * kin.E[0, topo.body_names.index(jt.guide)] * cmath.exp(
                    1j * jt.direction)
            for k, val in ((0, f.real), (1, f.imag), (2, _cross(r, f))):
                if val != 0.0:
                    rows[k][i] = rows[k].get(i, 0.0) + val
        m, inertia = body.mass or 0.0, body.inertia or 0.0
        alpha, omega = float(kin.alpha[0, b]), float(kin.omega[0, b])
        ext, torque = m * g, 0.0
        loads = []
        for ld in mech.loads:
            if ld.body != body.name:
                continue
            F = complex(*ld.force)
            rP = complex(kin.point_c(b, ld.point)[0][0]) if ld.point else rG
            ext += F
            torque += ld.torque + _cross(rP - rG, F)
            loads.append((ld, F, rP))
        consts = [ext.real - m * aG.real, ext.imag - m * aG.imag, torque - inertia * alpha]
        # the magnitudes each constant is computed from: it is round-off only below these
        cscale = [abs(m * g.real) + sum(abs(ld[1].real) for ld in loads) + abs(m * aG.real),
                  abs(m * g.imag) + sum(abs(ld[1].imag) for ld in loads) + abs(m * aG.imag),
                  sum(abs(ld[0].torque) + abs(ld[2] - rG) * abs(ld[1]) for ld in loads)
                  + abs(inertia * alpha)]
        out.append((b, rows, consts, dict(m=m, I=inertia, aG=aG, vG=vG, alpha=alpha,
                                          omega=omega, g=m * g, loads=loads, cscale=cscale)))
    return unk, out


def _eq_expr(rows_k, const, unk, const_label, cscale: float, lscale: float):
    """One equilibrium equation as printed: a coefficient or the constant is left out
    only where it is round-off of the magnitudes it came from (``lscale`` for the
    coefficients, a unit direction's components or a lever arm, m; ``cscale`` for the
    constant), never by an absolute threshold that a small mechanism falls under."""
    terms = []
    for i, c in sorted(rows_k.items()):
        if abs(c) <= N.ROUNDOFF * lscale:
            continue
        if abs(abs(c) - 1.0) < 1e-15:
            terms.append((1 if c > 0 else -1, unk[i][0]))
        else:
            terms.append((1 if c > 0 else -1, S.prod(N.num(abs(c), 6), unk[i][0])))
    if abs(const) > N.ROUNDOFF * cscale:
        terms.append((1 if const > 0 else -1, N.num(abs(const), 6)))
    return S.signed_sum(terms)


def _body_blocks(ctx, b, rows, consts, info, unk):
    nums, topo = ctx.polys.numbers, ctx.lk.topo
    k = nums[b]
    name = topo.body_names[b]
    m, inertia, aG, alpha = info["m"], info["I"], info["aG"], info["alpha"]
    out = [Heading(3, f"Link {k} ({name})")]
    a_mag = abs(aG)
    out.append(Para([f"m{k} = {N.fmt(m)} kg, I{k} = {N.fmt(inertia)} kg m² about G{k}; "
                     f"a_G{k} = ({N.fmt(aG.real)}, {N.fmt(aG.imag)}) m/s², "
                     f"|a_G{k}| = {N.fmt(a_mag)} m/s²; α{k} = {N.fmt(alpha)} rad/s². "
                     f"Inertia force −m{k} a_G{k} = ({N.fmt(-m * aG.real)}, "
                     f"{N.fmt(-m * aG.imag)}) N, inertia moment −I{k} α{k} = "
                     f"{N.fmt(-inertia * alpha)} N m."]))
    if m > 0 and a_mag > 0 and alpha == 0:
        out.append(Para([f"α{k} = 0, so e{k} = 0: the inertia force acts through G{k}."]))
    elif m > 0 and a_mag > 0:
        e_sym = S.Frac(S.prod(S.name("I", str(k)), S.name("alpha", str(k))),
                       S.prod(S.name("m", str(k)), S.name("a", f"G{k}")))
        e_num = S.Frac(S.prod(N.num(inertia), N.num(alpha)), S.prod(N.num(m), N.num(a_mag)))
        e_val = inertia * alpha / (m * a_mag)
        out.append(Math([S.name("e", str(k)), e_sym, e_num], N.fmt_of(e_val, e_num), "m",
                        P.text(e_num),
                        note="the resultant inertia force m a_G acts on a line offset by e "
                             "from G, so that its moment about G is the inertia moment "
                             "(the notes' inertia circle)"))
    out.append(Para(["Equilibrium with the inertia force and moment (moments about G"
                     f"{k}, counter-clockwise positive; forces in N, moments in N m):"]))
    size = size_of(topo)
    for lab, kk in (("ΣF_x", 0), ("ΣF_y", 1), ("ΣM_G", 2)):
        out.append(Math([_eq_expr(rows[kk], consts[kk], unk, lab, info["cscale"][kk],
                                  1.0 if kk < 2 else size), sp.Integer(0)],
                        note=lab))
    return out


def force_sections(ctx) -> list:
    """The kinetostatic part of the worked solution (needs every moving body's mass)."""
    unk, eqs = _equations(ctx)
    n = len(unk)
    A = np.zeros((n, n))
    rhs = np.zeros(n)
    r = 0
    for _, rows, consts, _ in eqs:
        for kk in range(3):
            for i, c in rows[kk].items():
                A[r, i] = c
            rhs[r] = -consts[kk]
            r += 1
    out = [Heading(2, "Kinetostatics"),
           Para(["D'Alembert: each moving link is in equilibrium under its joint forces, "
                 "the loads, gravity, the inertia force −m a_G at its centre of mass G and "
                 "the inertia moment −I α. F_ab is the force by link a on link b (link b "
                 "receives F_ab, link a −F_ab); N_ab and M_ab are the normal force (along "
                 "the line's normal n, at the slider point) and the couple of the guide a on "
                 "the slider b. The accelerations of the centres of mass come from the "
                 "kinematics above. Units: SI."])]
    for b, rows, consts, info in eqs:
        out += _body_blocks(ctx, b, rows, consts, info, unk)
    try:
        x = np.linalg.solve(A, rhs)
    except np.linalg.LinAlgError:
        out.append(Para(["The equilibrium equations are singular at this position (a dead "
                         "centre): the joint forces are not determined."]))
        return out
    out.append(Para([f"These are {n} linear equations in the {n} unknowns "
                     + ", ".join(str(u[0]).replace("_", "") for u in unk)
                     + "; solved together:"]))
    ctx.extra["forces"] = {str(u[0]): float(v) for u, v in zip(unk, x, strict=True)}
    out += _force_table(ctx, unk, x)
    out += _drive(ctx, unk, x, eqs)
    return out


def _body_power(ctx, b, info) -> tuple[list, float]:
    """One link's share of the power balance: ``m a_G·v_G + I α ω`` less the power of
    its gravity and loads, as ``(signed terms as printed, value W)``."""
    kin = ctx.kin
    m, inertia, w = info["m"], info["I"], info["omega"]
    aG, vG = _snap(info["aG"]), _snap(info["vG"])
    terms, total = [], 0.0
    d = _dot_expr(aG, vG)
    if m > 0 and d is not None:
        terms.append((1, S.prod(N.num(m), d)))
        total += m * (aG.real * vG.real + aG.imag * vG.imag)
    if inertia > 0 and w != 0 and info["alpha"] != 0:
        terms.append((1, S.prod(N.num(inertia), N.num(info["alpha"]), N.num(w))))
        total += inertia * info["alpha"] * w
    d = _dot_expr(info["g"], vG)
    if d is not None:
        terms.append((-1, d))
        total -= info["g"].real * vG.real + info["g"].imag * vG.imag
    for ld, F, _ in info["loads"]:
        vP = _snap(complex(kin.point_c(b, ld.point)[1][0])) if ld.point else vG
        d = _dot_expr(F, vP)
        if d is not None:
            terms.append((-1, d))
            total -= F.real * vP.real + F.imag * vP.imag
        if ld.torque and w:
            terms.append((-1, S.prod(N.num(ld.torque), N.num(w))))
            total -= ld.torque * w
    return terms, total


def _force_table(ctx, unk, x):
    mech, topo, nums = ctx.mech, ctx.lk.topo, ctx.polys.numbers
    size = size_of(topo)
    frc = ctx.lk.forces(ctx.kin)
    rows = []
    for j, jt in enumerate(mech.joints):
        a, b = (nums[topo.body_names.index(n)] for n in jt.bodies)
        idx = [i for i, u in enumerate(unk) if u[1] == j and u[2] != "effort"]
        if isinstance(jt, Revolute):
            fx, fy = x[idx[0]], x[idx[1]]
            mx, my = frc.joint_force[jt.name][0]
            f = math.hypot(fx, fy)
            rows.append([jt.name, f"F{a}{b}: {jt.body_a} on {jt.body_b}", N.fmt(fx, scale=f),
                         N.fmt(fy, scale=f),
                         N.fmt(math.hypot(fx, fy)), N.fmt(math.hypot(mx, my)),
                         f"{abs(math.hypot(fx, fy) - math.hypot(mx, my)):.2g}"])
        else:
            nn, mm = x[idx[0]], x[idx[1]]
            sn = float(frc.normal[jt.name][0])
            rows.append([jt.name, f"N{a}{b}, M{a}{b}: {jt.guide} on {jt.slider}",
                         f"N = {N.fmt(nn)}", f"M = {N.fmt(mm, scale=abs(nn) * size)} N m",
                         N.fmt(abs(nn)),
                         N.fmt(abs(sn)), f"{abs(abs(nn) - abs(sn)):.2g}"])
    return [Table("forces", "Joint forces (N), by the first link on the second, world axes; "
                  "the solver's tree-reduced method beside",
                  ["joint", "force", "F_x", "F_y", "|F| (hand)", "|F| (matrix method)",
                   "|difference|"], rows)]


def _drive(ctx, unk, x, eqs):
    mech, kin = ctx.mech, ctx.kin
    rev = isinstance(mech.driver_joint, Revolute)
    eff = float(x[-1])
    vel = float(kin.velocity[0])
    frc = ctx.lk.forces(kin)
    sym, unit = (sp.Symbol("T"), "N m") if rev else (S.name("F", "d"), "N")
    rate = sp.Symbol("omega") if rev else sp.Symbol("v")
    p_num = S.prod(N.num(eff), N.num(vel))
    power = eff * vel
    ctx.extra["effort"], ctx.extra["power"] = eff, power
    out = [Heading(3, "Motor torque and power" if rev else "Drive force and power"),
           Math([sym], N.fmt(eff), unit,
                note=f"the matrix method gives {N.fmt(float(frc.effort[0]))} {unit}"),
           Math([sp.Symbol("P"), S.prod(sym, rate), p_num], N.fmt_of(power, p_num), "W",
                P.text(p_num))]
    # one line per link: a single sum over every link scrolled off any page
    per_body = [(b, *_body_power(ctx, b, info)) for b, _, _, info in eqs]
    # a link's round-off power (the crank at constant speed) is its printed 0 in the sum too
    per_body = [(b, t, 0.0 if N.fmt_of(v, S.signed_sum(t)) == "0" else v)
                for b, t, v in per_body if t]
    total = sum(v for _, _, v in per_body)
    names = [S.name("P", str(ctx.polys.numbers[b])) for b, _, _ in per_body]
    nums = S.signed_sum([(1 if v >= 0 else -1, N.num(abs(v))) for _, _, v in per_body])
    out += [Para(["Check by the power balance: the input power equals the rate of change of "
                  "kinetic energy, Σ (m a_G·v_G + I α ω), less the power of the loads and of "
                  "gravity, Σ F·v_P; one term per moving link, each worked below:"]),
            Math([sp.Symbol("P"), S.signed_sum([(1, n) for n in names]), nums],
                 N.fmt_of(total, nums), "W", P.text(nums),
                 note=f"T ω − (this) = {power - total:.3g} W")]
    for (b, terms, v), nm in zip(per_body, names, strict=True):
        bal = S.signed_sum(terms)
        out.append(Math([nm, bal], N.fmt_of(v, bal), "W", P.text(bal),
                        note=f"link {ctx.polys.numbers[b]} ({ctx.lk.topo.body_names[b]})"))
    return out
