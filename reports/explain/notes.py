"""Where the course notes' printed figures come from, for the notes' own examples.

The notes (``/work/shared/seeds``; restated in REFERENCE.md S1, S2, S4) carry
rounded intermediates from step to step: the slider-crank's theta3 = 345.5 deg and
omega3 = -89.45 rad/s, the quadratic for AC with 17.32 for 2 * 10 * cos 30.  Here
the notes' own closed forms are evaluated with the notes' rounded inputs, which
reproduces their figures; the exact values are those of the worked solution.
Only the seed cases at the notes' input get this section.
"""

from __future__ import annotations

import math

import sympy as sp

from reports.explain import numbers as N
from reports.explain import printing as P
from reports.explain import sym as S
from reports.explain.blocks import Heading, Math, Para, Table

DEG = math.pi / 180.0


def _d(x):
    return S.Deg(N.num(x))


def _calc(expr, unit: str, note: str = "") -> Math:
    v = P.value(expr)
    return Math([expr], N.fmt_of(v, expr), unit, P.text(expr), note)


def _at(ctx, name: str, angle_deg: float, omega: float) -> bool:
    kin = ctx.kin
    return (ctx.mech.name == name and abs(math.degrees(kin.value[0]) - angle_deg) < 1e-9
            and abs(kin.velocity[0] - omega) < 1e-9 and kin.acceleration[0] == 0.0)


def notes_sections(ctx) -> list:
    if _at(ctx, "seed-slider-crank", 30.0, 200.0):
        return _slider_crank(ctx)
    if _at(ctx, "seed-four-bar", 60.0, 15.0):
        return _four_bar(ctx)
    return []


def _slider_crank(ctx) -> list:
    """S1 (week 4) and S2 (week 8) of the notes."""
    t3n, w3n = 345.5, -89.45
    quad = S.Frac(sp.Add(N.num(17.32), sp.sqrt(sp.Add(S.sq(N.num(17.32)), S.prod(4, 300),
                                                       evaluate=False), evaluate=False),
                         evaluate=False), 2)
    w3 = S.Frac(S.Neg(S.prod(10, 200, S.cos(S.diff_angle(_d(30), _d(180))))),
                S.prod(20, S.cos(S.diff_angle(_d(t3n), _d(180)))))
    v4 = S.Frac(S.Neg(S.prod(10, 200, S.sin(S.diff_angle(_d(t3n), _d(30))))),
                S.cos(S.diff_angle(_d(180), _d(t3n))))
    a3 = S.Frac(sp.Add(S.prod(10, S.sq(N.num(200)), S.sin(S.diff_angle(_d(30), _d(180)))),
                       S.prod(20, S.sq(N.num(w3n)), S.sin(S.diff_angle(_d(t3n), _d(180)))),
                       evaluate=False), S.prod(20, S.cos(S.diff_angle(_d(t3n), _d(180)))))
    a4 = S.Frac(sp.Add(S.prod(10, S.sq(N.num(200)), S.cos(S.diff_angle(_d(30), _d(t3n)))),
                       S.prod(20, S.sq(N.num(w3n))), evaluate=False),
                S.cos(S.diff_angle(_d(180), _d(t3n))))
    q = ctx.q
    exact_t3 = math.degrees(q[1]) % 360.0
    out = [Heading(2, "Where the notes' figures come from"),
           Para(["The notes (mechanism technique, week 4) solve this slider-crank with rounded "
                 "intermediates and carry them on; their closed forms evaluated with their "
                 "rounded inputs give their printed figures:"]),
           Para(["AC = 28.0 cm: the notes' quadratic X² − 17.32 X − 300 = 0 (cosine law, "
                 "with 17.32 for 2·10·cos 30° = 17.3205), root"]),
           _calc(quad, "cm", "printed as 28.0 and carried on as 28; the exact AC is "
                              f"{N.fmt(q[2] / ctx.L)} cm"),
           Para([f"θ3 = 345.5° (−14.47°): the exact θ3 = {N.fmt(exact_t3)}° "
                 f"({N.fmt(exact_t3 - 360)}°) rounded; the notes then use 345.5°. "
                 "ω3 = −89.45 rad/s is the notes' closed form with θ3 = 345.5°:"]),
           _calc(w3, "rad/s", f"exact {N.fmt(ctx.qd[1])} rad/s"),
           Para([S.r("4", 1), ": the notes print −1447.93 cm/s; their closed form with "
                 "θ3 = 345.5°:"]),
           _calc(v4, "cm/s", f"exact {N.fmt(ctx.qd[2] / ctx.L)} cm/s"),
           Para(["α3 = 8259 rad/s² (8259.7 cut to four figures): the closed form with "
                 "θ3 = 345.5° and ω3 = −89.45 rad/s:"]),
           _calc(a3, "rad/s^2", f"exact {N.fmt(ctx.qdd[1])} rad/s²"),
           Para([S.r("4", 2), " = −459977.6 cm/s² ≈ −4600 m/s²: the same rounded inputs:"]),
           _calc(a4, "cm/s^2", f"exact {N.fmt(ctx.qdd[2] / ctx.L)} cm/s²")]
    if "effort" in ctx.extra:
        f = ctx.extra["forces"]
        rb = math.hypot(f["F_23x"], f["F_23y"])
        rc = math.hypot(f["F_34x"], f["F_34y"])
        out += [Para(["The force analysis (week 8) is graphical: two sub-problems (slider mass "
                      "and load; rod inertia) with lever arms measured on a drawing, "
                      "superposed. Its figures beside the equilibrium equations' (g = 0, "
                      "as in the notes):"]),
                Table("notes-forces", "The notes' force figures and the worked solution's",
                      ["quantity", "notes", "this solution", "why they differ"],
                      [["motor torque T (N m)", "476 = 233 + 243",
                        N.fmt(ctx.extra["effort"]), "rounded lever arms (0.009 m, 19 mm)"],
                       ["motor power (kW)", "95.2", N.fmt(ctx.extra["power"] / 1000),
                        "476 × 200"],
                       ["force at B, |F23| (N)", "16160", N.fmt(rb),
                        "sub-problem forces added as magnitudes; a_B written with 0.2 m and "
                        "I3 α3 with 0.2 instead of 0.1"],
                       ["force at C, |F34| (N)", "3359 (sub-problem A alone)", N.fmt(rc),
                        "only the slider's sub-problem"]])]
    return out


def _four_bar(ctx) -> list:
    """S4 (machine dynamics, week 6)."""
    t2, t3, t4, w2, w3, w4 = 60.0, 29.38, 290.75, 15.0, -3.916, 3.091
    a3 = S.Frac(sp.Add(S.prod(100, S.sq(N.num(w2)), S.cos(S.diff_angle(_d(t2), _d(t4)))),
                       S.prod(300, S.sq(N.num(w3)), S.cos(S.diff_angle(_d(t3), _d(t4)))),
                       S.prod(250, S.sq(N.num(w4))), evaluate=False),
                S.prod(300, S.sin(S.diff_angle(_d(t4), _d(t3)))))
    a4 = S.Frac(sp.Add(S.prod(100, S.sq(N.num(w2)), S.cos(S.diff_angle(_d(t2), _d(t3)))),
                       S.prod(300, S.sq(N.num(w3))),
                       S.prod(250, S.sq(N.num(w4)), S.cos(S.diff_angle(_d(t4), _d(t3)))),
                       evaluate=False),
                S.prod(250, S.sin(S.diff_angle(_d(t3), _d(t4)))))
    sw3 = S.prod(N.num(2421.706), S.Frac(sp.pi, 180))
    sw4 = S.prod(N.num(5471.96), S.Frac(sp.pi, 180))
    return [Heading(2, "Where the notes' figures come from"),
            Para(["The notes (machine dynamics, week 6) print θ3 = 29.38°, θ4 = 290.75°, "
                  "ω3 = −3.916, ω4 = 3.091 rad/s: the exact values above rounded. Their "
                  "acceleration formulas with those rounded inputs give their α3 = 42.27 and "
                  "α4 = 95.5 rad/s²:"]),
            _calc(a3, "rad/s^2", f"exact {N.fmt(ctx.qdd[1])} rad/s²"),
            _calc(a4, "rad/s^2", f"exact {N.fmt(ctx.qdd[2])} rad/s²"),
            Para(["The notes' SolidWorks Motion check reads 2421.706 and 5471.96 deg/s²; in "
                  "rad/s²:"]),
            _calc(sw3, "rad/s^2"), _calc(sw4, "rad/s^2")]
