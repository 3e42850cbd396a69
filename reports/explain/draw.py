"""The vector polygon drawn as the notes draw it: each r_k an arrow from tail to
tip, named, with its angle theta_k marked counter-clockwise from +x at its tail.

Made at build time as SVG (for HTML and Markdown) and as TikZ (for LaTeX) from
the same geometry: tails at the linkage's world points, tips at ``tail + r_k
mu(theta_k)``, y up.  The linkage's bodies are drawn faintly underneath.
"""

from __future__ import annotations

import html
import math
import re

from analytic.positions import size_of
from reports.explain.blocks import Figure
from reports.explain.loops import angle, length
from reports.explain.render import _tex_text

COLOURS = ["#c0392b", "#2471a3", "#1e8449", "#7d3c98", "#b9770e", "#117a65", "#a04000",
           "#34495e"]
WIDTH = 560.0
PAD = 90.0


def _geometry(ctx, loop):
    """``[(label, tail (x, y), tip (x, y), theta deg, r)]`` in the file's unit."""
    kin, out = ctx.kin, []
    for v in loop.vectors:
        b, pn = v.tail_at
        z = complex(kin.point_c(b, pn)[0][0]) / ctx.L
        r = length(v, ctx.q, ctx.ng) / ctx.L
        t = angle(v, ctx.q)
        tip = z + r * complex(math.cos(t), math.sin(t))
        out.append((v.label, (z.real, z.imag), (tip.real, tip.imag), math.degrees(t), r,
                    v.tail, v.head))
    return out


def _bodies(ctx):
    """Segments between the joint points of each moving body (file unit)."""
    kin, topo, mech = ctx.kin, ctx.lk.topo, ctx.mech
    segs = []
    same = 1e-9 * size_of(topo) / ctx.L   # one point, to the solver's closure
    for b, body in enumerate(mech.bodies):
        if b == topo.ground:
            continue
        pts = []
        for j in mech.joints:
            if body.name in j.bodies:
                pn = j.point_a if j.body_a == body.name else j.point_b
                z = complex(kin.point_c(b, pn)[0][0]) / ctx.L
                if all(abs(z - p) > same for p in pts):
                    pts.append(z)
        for i in range(len(pts) - 1):
            segs.append(((pts[i].real, pts[i].imag), (pts[i + 1].real, pts[i + 1].imag)))
    return segs


def polygon_figure(ctx, loop, n: int) -> Figure:
    geo = _geometry(ctx, loop)
    segs = _bodies(ctx)
    caption = (f"Vector polygon of loop {n}: each r_k from tail to tip, its angle θ_k "
               f"counter-clockwise from +x (dashed) at its tail; lengths in {ctx.unit}; "
               "the linkage in grey.")
    return Figure(caption, _svg(geo, segs), _tikz(geo, segs), f"loop{n}")


def _frame(geo, segs):
    xs = [p[0] for g in geo for p in (g[1], g[2])] + [p[0] for s in segs for p in s]
    ys = [p[1] for g in geo for p in (g[1], g[2])] + [p[1] for s in segs for p in s]
    span = max(max(xs) - min(xs), max(ys) - min(ys)) or 1.0  # any size: lengths scale
    k = WIDTH / span
    return min(xs), max(ys), k, (max(xs) - min(xs)) * k, (max(ys) - min(ys)) * k


def _svg(geo, segs) -> str:
    x0, y1, k, w, h = _frame(geo, segs)

    def P(p):
        return PAD + (p[0] - x0) * k, PAD + (y1 - p[1]) * k

    W, H = w + 2 * PAD, h + 2 * PAD
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {W:.0f} {H:.0f}" '
           f'width="{W:.0f}" height="{H:.0f}" font-family="serif" font-size="15">',
           "<defs>" + "".join(
               f'<marker id="ah{i}" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="8" '
               f'markerHeight="8" orient="auto-start-reverse"><path d="M0,0 L10,5 L0,10 z" '
               f'fill="{c}"/></marker>' for i, c in enumerate(COLOURS)) + "</defs>",
           f'<rect width="{W:.0f}" height="{H:.0f}" fill="white"/>']
    for a, b in segs:
        (ax, ay), (bx, by) = P(a), P(b)
        out.append(f'<line x1="{ax:.1f}" y1="{ay:.1f}" x2="{bx:.1f}" y2="{by:.1f}" '
                   'stroke="#d5d8dc" stroke-width="9" stroke-linecap="round"/>')
    for i, (lab, tail, tip, th, r, tn, _hn) in enumerate(geo):
        c = COLOURS[i % len(COLOURS)]
        (tx, ty), (hx, hy) = P(tail), P(tip)
        rad = min(22 + 8 * i, 64)
        out.append(f'<line x1="{tx:.1f}" y1="{ty:.1f}" x2="{tx + rad + 14:.1f}" y2="{ty:.1f}" '
                   f'stroke="{c}" stroke-dasharray="4 3" stroke-width="1"/>')
        t = math.radians(th)
        ex, ey = tx + rad * math.cos(t), ty - rad * math.sin(t)
        large = 1 if th > 180 else 0
        out.append(f'<path d="M{tx + rad:.1f},{ty:.1f} A{rad},{rad} 0 {large} 0 {ex:.1f},'
                   f'{ey:.1f}" fill="none" stroke="{c}" stroke-width="1.2" '
                   f'marker-end="url(#ah{i % len(COLOURS)})"/>')
        m = math.radians(th / 2)
        lx, ly = tx + (rad + 10) * math.cos(m), ty - (rad + 10) * math.sin(m)
        out.append(f'<text x="{lx:.1f}" y="{ly:.1f}" fill="{c}" font-size="12">'
                   f'θ<tspan baseline-shift="sub" font-size="9">{lab}</tspan> = '
                   f'{th:.2f}°</text>')
        if abs(r) * k > 1:
            out.append(f'<line x1="{tx:.1f}" y1="{ty:.1f}" x2="{hx:.1f}" y2="{hy:.1f}" '
                       f'stroke="{c}" stroke-width="2.5" marker-end="url(#ah{i % len(COLOURS)})"/>')
        nx, ny = -(hy - ty), (hx - tx)
        nn = math.hypot(nx, ny) or 1.0
        mx, my = (tx + hx) / 2 + 16 * nx / nn, (ty + hy) / 2 + 16 * ny / nn
        out.append(f'<text x="{mx:.1f}" y="{my:.1f}" fill="{c}" font-weight="bold" '
                   f'font-style="italic">r<tspan baseline-shift="sub" font-size="11">{lab}'
                   "</tspan></text>")
        out.append(f'<circle cx="{tx:.1f}" cy="{ty:.1f}" r="3" fill="#222"/>')
        out.append(f'<text x="{tx - 14:.1f}" y="{ty + 18:.1f}" font-size="13">'
                   f'{html.escape(tn)}</text>')
    out.append("</svg>")
    return _clamp_text("\n".join(out), W, H)


def _clamp_text(svg: str, W: float, H: float) -> str:
    """Keep every label inside the picture (angle labels of long arcs can fall
    outside)."""

    def fix(m):
        x = min(max(float(m.group(1)), 4.0), W - 90.0)
        y = min(max(float(m.group(2)), 14.0), H - 4.0)
        return f'<text x="{x:.1f}" y="{y:.1f}"'
    return re.sub(r'<text x="(-?[0-9.]+)" y="(-?[0-9.]+)"', fix, svg)


def _tikz(geo, segs) -> str:
    x0, y1, k, w, h = _frame(geo, segs)
    s = 12.0 / (max(w, h) or 1.0) * k  # about 12 cm across

    def P(p):
        return f"({(p[0] - x0) * s:.3f},{(p[1] - y1) * s + h / k * s:.3f})"

    out = [r"\begin{tikzpicture}[>=stealth]"]
    for a, b in segs:
        out.append(rf"\draw[line width=5pt, gray!25, line cap=round] {P(a)} -- {P(b)};")
    for i, (lab, tail, tip, th, r, tn, _hn) in enumerate(geo):
        rad = 0.6 + 0.25 * i
        out.append(rf"\draw[dashed] {P(tail)} -- ++({rad + 0.3:.2f},0);")
        out.append(rf"\draw[->] {P(tail)} ++({rad:.2f},0) arc (0:{th:.3f}:{rad:.2f}) "
                   rf"node[pos=0.5, right, font=\scriptsize] {{$\theta_{{{lab}}} = "
                   rf"{th:.2f}^\circ$}};")
        if abs(r) * s > 1e-3:
            out.append(rf"\draw[->, very thick] {P(tail)} -- {P(tip)} node[midway, "
                       rf"above left] {{$r_{{{lab}}}$}};")
        out.append(rf"\fill {P(tail)} circle (1.5pt) node[below left] "
                   f"{{{_tex_text(tn)}}};")
    out.append(r"\end{tikzpicture}")
    return "\n".join(out)
