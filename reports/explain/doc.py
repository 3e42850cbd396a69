"""Assemble the worked solution of one configuration (``xval explain``).

Order as in the notes: the problem and its units, then loop by loop (polygon,
loop equation, position, first variable table, velocity, second variable
table, acceleration, the matrix method beside), then the kinetostatics when the
description has masses, and, for the notes' own examples, where the notes'
rounded figures come from.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import sympy as sp

from analytic import Linkage
from analytic.mechanism import Revolute
from analytic.toml_io import LENGTH_UNITS
from reports.explain import numbers as N
from reports.explain.blocks import Document, Heading, Para, Table
from reports.explain.forces import force_sections
from reports.explain.kin import coupled_section, loop_sections, make_ctx, scales
from reports.explain.loops import build_polygons
from reports.explain.notes import notes_sections


def file_unit(mech) -> str:
    """The description file's length unit (``[units] length``), ``m`` without a file."""
    if mech.source and Path(mech.source).is_file():
        try:
            doc = tomllib.loads(Path(mech.source).read_text(encoding="utf-8"))
            u = doc.get("units", {}).get("length", "m")
            if u in LENGTH_UNITS:
                return u
        except (OSError, tomllib.TOMLDecodeError, AttributeError):
            pass
    return "m"


def explain(mech, value: float | None = None) -> Document:
    """The worked solution at driver value ``value`` (rad or m; default the
    description's)."""
    lk = Linkage(mech)
    kin = lk.kinematics(value)
    unit = file_unit(mech)
    L = LENGTH_UNITS[unit]
    polys = build_polygons(lk.topo)
    ctx = make_ctx(mech, lk, kin, polys, unit, L)
    rev = isinstance(mech.driver_joint, Revolute)
    v0 = kin.value[0]
    at = f"{math.degrees(v0):.6g}°" if rev else f"{v0 / L:.6g} {unit}"
    doc = Document(f"Worked solution: {mech.name}, input {mech.driver.joint} = {at}")
    doc.add(*_problem(ctx, rev))
    for n, loop in enumerate(polys.loops, start=1):
        if loop.unknowns:
            doc.add(*N.build_checked(loop_sections, ctx, loop, n))
        else:
            doc.add(*coupled_section(ctx, loop, n))
    doc.add(*_results(ctx))
    if mech.has_mass:
        doc.add(*N.build_checked(force_sections, ctx))
    doc.add(*notes_sections(ctx))
    return doc


def _problem(ctx, rev: bool) -> list:
    mech, kin, unit = ctx.mech, ctx.kin, ctx.unit
    d = mech.driver
    desc = mech.description.strip().replace("\n", " ")
    if rev:
        inp = (f"input joint {d.joint}: angle {math.degrees(kin.value[0]):.6g}°, "
               f"ω = {kin.velocity[0]:.6g} rad/s, α = {kin.acceleration[0]:.6g} rad/s²")
    else:
        inp = (f"input slider {d.joint}: s = {kin.value[0] / ctx.L:.6g} {unit}, "
               f"velocity {kin.velocity[0] / ctx.L:.6g} {unit}/s, "
               f"acceleration {kin.acceleration[0] / ctx.L:.6g} {unit}/s²")
    src = f" (file {mech.source})" if mech.source else ""
    return [
        Heading(2, "The problem"),
        Para([desc or mech.name]),
        Para([f"Given: {inp}."]),
        Para([f"Units: lengths in {unit}, the unit of the description{src}; angles in degrees; "
              "angular velocities in rad/s and accelerations in rad/s², as in the notes. "
              "The force analysis works in SI (m, kg, N, N m, W). Angles, ω and α are "
              "counter-clockwise positive from +x."]),
        Para(["Method, as in the notes: draw the vector polygon, write the loop equation "
              "with μ(θ) = (cos θ, sin θ) and σ(θ) = (−sin θ, cos θ), find the positions, "
              "mark what varies, differentiate twice, and remove one unknown at a time by a "
              "dot product with the unit vector perpendicular to it. Under each substituted "
              "expression a 'calc:' line repeats it as plain text for a calculator or "
              "SymPy (cosd, sind, asind, acosd, atan2d work in degrees)."]),
    ]


def _results(ctx) -> list:
    """Every link's angle, omega and alpha and every slider, from the hand values."""
    lk, unit, L = ctx.lk, ctx.unit, ctx.L
    topo = lk.topo
    sc = scales(ctx)
    rows = []
    for b in topo.order[1:]:
        g = topo.group_of[b]
        if g < 0:
            continue
        th = math.degrees(ctx.q[g] + topo.offset[b]) % 360.0
        rows.append([f"{topo.body_names[b]} (link {ctx.polys.numbers[b]})",
                     N.fmt(th, scale=360.0), N.fmt(ctx.qd[g], scale=sc["w"]),
                     N.fmt(ctx.qdd[g], scale=sc["al"])])
    out = [Heading(2, "Results"),
           Table("links", "Links: the angle of each body's own x axis (deg), ω (rad/s), "
                 "α (rad/s²), from the hand method"
                 + ("" if ctx.hand_ok and not ctx.polys.coupled else
                    " (the matrix method's where the loops above say so)"),
                 ["link", "angle (deg)", "ω (rad/s)", "α (rad/s²)"], rows)]
    srows = []
    for j in topo.prismatic:
        i = topo.n_groups + topo.slider_index[j]
        s, v, a = ctx.q[i], ctx.qd[i], ctx.qdd[i]
        srows.append([topo.joint_names[j],
                      f"{N.fmt(s / L, scale=sc['r'] / L)} {unit} = {N.fmt(s, scale=sc['r'])} m",
                      f"{N.fmt(v / L, scale=sc['v'] / L)} {unit}/s = "
                      f"{N.fmt(v, scale=sc['v'])} m/s",
                      f"{N.fmt(a / L, scale=sc['a'] / L)} {unit}/s² = "
                      f"{N.fmt(a, scale=sc['a'])} m/s²"])
    if srows:
        out.append(Table("sliders", "Sliders: displacement s along the line from its origin "
                         "point, its velocity and acceleration, in the file's unit and in SI",
                         ["joint", sp.Symbol("s"), sp.Symbol("sdot"), sp.Symbol("sddot")],
                         srows))
    return out
