"""The linkage moving through a cycle, drawn frame by frame and written as GIF, MP4
or HTML (the frames: :mod:`reports.figures.poses`; the command ``xval animate``:
:mod:`reports.cli.animate`).

A full-turn input turns once from its reference value, so the first frame is the
assembled reference pose; a limited input goes from the reference value to one end of
its feasible range, back to the other and back to the reference (its time runs on at
the description's rate).  Each frame draws the bodies (outline through their points,
named), the joints (named; a slider as a square on its dashed line), the ground hatched
under its pivots and guides, the paths of the points of the bodies not pinned to the
ground (thin grey, traced in colour up to the frame), the current input value and time,
and with ``--forces`` the joint forces as arrows on a common scale with a key.

With ``--engine`` the engine's poses (its body angles and frame origins at its samples,
from the run's tree coordinates through :meth:`sim_models.builders.tree.SimTree.propagate`) are
drawn over the analytic ones, dashed in the engine's colour: a drifting loop shows as a
gap.  Engine and analytic poses go through the same drawing function
(:func:`body_outlines`), so what differs on screen differs in the numbers.

A description with a ``[motion]`` table is animated in free motion (``--driven``: its
prescribed cycle instead): the poses at evenly spaced times from 0 to the duration
(:func:`free_frames`), drawn by the same functions, with the clock.

Writers: GIF through Pillow, MP4 through ffmpeg (where it is on PATH; else one line,
status 2), HTML as one self-contained page (matplotlib's ``to_jshtml``).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib import animation
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Polygon, Rectangle

from analytic.errors import OutputError
from analytic.input_display import InputConvention, input_text
from analytic.mechanism import Prismatic
from reports.figures import plots
from reports.figures.poses import ARROW_FRACTION, ENGINE_COLOURS, Frames, Poses


# ============================================================================ drawing
def body_points(mech, b: int) -> list[tuple[str, np.ndarray]]:
    """The named points of body ``b`` (body frame, m), joint points first."""
    body = mech.bodies[b]
    return [(n, np.asarray(p, float)) for n, p in body.points.items()]


def world(theta, origin, local) -> np.ndarray:
    """World position of a body-frame point for a body at ``theta`` (rad), ``origin``."""
    c, s = math.cos(theta), math.sin(theta)
    return origin + np.array([c * local[0] - s * local[1], s * local[0] + c * local[1]])


def body_outlines(mech, poses: Poses, i: int) -> dict[str, np.ndarray]:
    """Each moving body's outline at frame ``i``: its points in world axes (k, 2), in
    convex-outline order and closed when it has three or more (NaN if no pose)."""
    ground = mech.body_index(mech.ground) if hasattr(mech, "body_index") else \
        [b.name for b in mech.bodies].index(mech.ground)
    out = {}
    for b, body in enumerate(mech.bodies):
        if b == ground:
            continue
        pts = np.array([world(poses.theta[i, b], poses.origin[i, b], p)
                        for _, p in body_points(mech, b)])
        if len(pts) >= 3:
            c = pts.mean(axis=0)
            order = np.argsort(np.arctan2(pts[:, 1] - c[1], pts[:, 0] - c[0]))
            pts = np.vstack([pts[order], pts[order][:1]])
        out[body.name] = pts
    return out


def joint_positions(mech, poses: Poses, i: int) -> dict[str, np.ndarray]:
    """World position of each joint at frame ``i`` (a prismatic joint: its slider point)."""
    names = [b.name for b in mech.bodies]
    out = {}
    for jt in mech.joints:
        if isinstance(jt, Prismatic):
            b, p = names.index(jt.slider), mech.bodies[names.index(jt.slider)].points[jt.point]
        else:
            b, p = names.index(jt.body_b), mech.bodies[names.index(jt.body_b)].points[jt.point_b]
        out[jt.name] = world(poses.theta[i, b], poses.origin[i, b], np.asarray(p, float))
    return out


def traced_points(mech) -> list[tuple[int, str]]:
    """``(body, point)`` of the points whose paths are drawn: every point of a moving
    body with no joint to the ground (the couplers), else every moving point."""
    names = [b.name for b in mech.bodies]
    pinned = {n for jt in mech.joints for n in jt.bodies if mech.ground in jt.bodies}
    out = [(b, pn) for b, body in enumerate(mech.bodies)
           if body.name != mech.ground and body.name not in pinned for pn in body.points]
    if not out:
        out = [(b, pn) for b, body in enumerate(mech.bodies) if body.name != mech.ground
               for pn in body.points]
    return [(b, pn) for b, pn in out if names[b] != mech.ground]


def _nice(x: float) -> float:
    """A round number near ``x`` (1, 2, 5 x 10^k)."""
    if not (x > 0 and math.isfinite(x)):
        return 1.0
    e = math.floor(math.log10(x))
    m = x / 10 ** e
    return (1 if m < 1.5 else 2 if m < 3.5 else 5 if m < 7.5 else 10) * 10 ** e


def _ground_art(ax, mech, size: float, analytic: Poses) -> None:
    """The ground: a hatched block under each ground pivot and along each fixed guide."""

    g = mech.body(mech.ground)
    w = 0.08 * size
    for jt in mech.joints:
        if mech.ground not in jt.bodies or isinstance(jt, Prismatic):
            continue
        p = np.asarray(g.points[jt.point_a if jt.body_a == mech.ground else jt.point_b], float)
        ax.add_patch(Rectangle((p[0] - w / 2, p[1] - 0.6 * w), w, 0.35 * w, hatch="////",
                               fill=False, lw=0.8, color="0.25", zorder=1))
        ax.plot([p[0], p[0] - w / 3, p[0] + w / 3, p[0]],
                [p[1], p[1] - 0.25 * w, p[1] - 0.25 * w, p[1]], color="0.25", lw=1, zorder=1)
    for jt in mech.joints:
        if not (isinstance(jt, Prismatic) and jt.guide == mech.ground):
            continue
        o = np.asarray(g.points[jt.origin], float)
        u = np.array([math.cos(jt.direction), math.sin(jt.direction)])
        nrm = np.array([-u[1], u[0]])
        names = [b.name for b in mech.bodies]
        b = names.index(jt.slider)
        pts = np.array([world(analytic.theta[i, b], analytic.origin[i, b],
                              np.asarray(mech.bodies[b].points[jt.point], float))
                        for i in range(len(analytic.theta))])
        s = (pts - o) @ u
        a, e = o + (s.min() - 0.15 * size) * u, o + (s.max() + 0.15 * size) * u
        ax.plot([a[0], e[0]], [a[1], e[1]], "k--", lw=0.8, zorder=1)
        # hatched band just behind the line, on its right-hand side (the ground's side)
        h = 0.035 * size
        poly = np.array([a - 0.2 * h * nrm, e - 0.2 * h * nrm, e - 1.2 * h * nrm,
                         a - 1.2 * h * nrm])
        ax.add_patch(Polygon(poly, closed=True, hatch="////", fill=False, lw=0.6,
                             color="0.35", zorder=1))


@dataclass
class Animator:
    """The figure of an animation and how to draw frame ``i`` (``draw(i)`` updates the
    moving artists ``dynamic``; everything else is drawn once)."""

    fig: object
    ax: object
    draw: object
    dynamic: list
    n: int
    labels: list = field(default_factory=list)  # moving Text artists of constant text


def build_animation(fr: Frames, title: str = "", dpi: int = 80) -> Animator:
    """The figure of ``fr`` with its moving artists; frame 0 is drawn.  Phases: the
    axes and the still parts (:func:`_axes`, :func:`_ground_art`), the traced paths,
    the bodies and joints, the engines' poses, the force arrows, then ``draw(i)``."""
    mech = fr.mech
    fig, ax, size = _axes(fr, title, dpi)
    _ground_art(ax, mech, size, fr.analytic)
    traces = _traces(ax, fr)
    body_art, joints, jtext = _bodies(ax, mech)
    eng_art = _engines(ax, fr, list(body_art))
    quiv = _force_arrows(ax, fr, size)
    # under the axes, where it covers neither the linkage nor the legend
    info = fig.text(0.02, 0.01, "", va="bottom", ha="left", fontsize=9,
                    family="monospace", bbox=dict(fc="white", ec="0.7", alpha=0.9), zorder=9)
    ax.legend(fontsize=9, loc="upper right")
    conv = fr.convention or InputConvention(fr.revolute, fr.revolute)

    def draw(i: int):
        outl = body_outlines(mech, fr.analytic, i)
        for n, (ln, fill, txt) in body_art.items():
            pts = outl[n]
            ln.set_data(pts[:, 0], pts[:, 1])
            fill.set_xy(pts if len(pts) >= 3 else np.zeros((1, 2)))
            txt.set_position(np.nanmean(pts[:-1] if len(pts) >= 3 else pts, axis=0))
        jp = joint_positions(mech, fr.analytic, i)
        xy = np.array(list(jp.values()))
        joints.set_data(xy[:, 0], xy[:, 1])
        for n, p in jp.items():
            jtext[n].set_position(p + np.array([0.02, -0.045]) * size)
        for path, ln in traces:
            ln.set_data(path[:i + 1, 0], path[:i + 1, 1])
        for e, lines, ej in eng_art:
            eo = body_outlines(mech, e, i)
            for n, ln in lines.items():
                ln.set_data(eo[n][:, 0], eo[n][:, 1])
            ejp = np.array(list(joint_positions(mech, e, i).values()))
            ej.set_data(ejp[:, 0], ejp[:, 1])
        if quiv is not None:
            F = np.array([fr.forces[jt.name][i] for jt in mech.joints])
            quiv.set_offsets(xy)
            quiv.set_UVC(F[:, 0], F[:, 1])
        info.set_text(info_text(fr, i, conv))
        return []

    labels = [txt for _, _, txt in body_art.values()] + list(jtext.values())
    dynamic = [a for ln, fill, _ in body_art.values() for a in (ln, fill)] + [joints, info]
    dynamic += [ln for _, ln in traces]
    dynamic += [a for _, lines, ej in eng_art for a in (*lines.values(), ej)]
    if quiv is not None:
        dynamic.append(quiv)
    draw(0)
    return Animator(fig, ax, draw, dynamic, fr.n, labels)


def info_text(fr: Frames, i: int, conv) -> str:
    """The text box of frame ``i``: the input (the one display convention), its
    prescribed rate (and acceleration) there, the time along the motion."""
    if fr.free_joint is not None:  # a free run: its [motion] joint and the clock
        return free_info_text(fr, i)
    d = fr.mech.driver
    u = "rad/s" if fr.revolute else "m/s"
    rate = fr.rates[i] if fr.rates is not None else d.velocity
    acc = fr.accelerations[i] if fr.accelerations is not None else d.acceleration
    line = f"input {d.joint} = {input_text(float(fr.values[i]), conv)}, {rate:.4g} {u}"
    if acc:
        line += f", {acc:.4g} {u[:-2]}/s^2"
    return f"{line}\nt = {fr.times[i]:.4f} s   frame {i + 1}/{fr.n}"


def free_info_text(fr: Frames, i: int) -> str:
    """The text box of a free run's frame: its ``[motion]`` joint's coordinate and rate
    there, and the clock."""
    if fr.revolute:
        v = f"{math.degrees(float(fr.values[i])):.4f} deg, {fr.rates[i]:.4g} rad/s"
    else:
        v = f"{float(fr.values[i]):.6g} m, {fr.rates[i]:.4g} m/s"
    return (f"free motion: {fr.free_joint} = {v}\n"
            f"t = {fr.times[i]:.6g} s of {fr.times[-1]:.6g} s   frame {i + 1}/{fr.n}")


def _axes(fr: Frames, title: str, dpi: int):
    """``(fig, ax, size)``: equal axes around every frame's bodies, with room for the
    text box; ``size`` (m) the largest extent of the motion."""
    pts = np.array([p for i in range(fr.n)
                    for o in body_outlines(fr.mech, fr.analytic, i).values() for p in o])
    lo, hi = np.nanmin(pts, axis=0), np.nanmax(pts, axis=0)
    size = float(np.max(hi - lo)) or 1.0
    fig, ax = plots.plt.subplots(figsize=(6.4, 4.8), dpi=dpi)
    fig.subplots_adjust(bottom=0.2)  # the frame's text box below the axes
    pad = 0.15 * size
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad - 0.05 * size, hi[1] + pad + 0.1 * size)  # room for the legend
    ax.set_aspect("equal")
    ax.grid(alpha=0.25)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title or fr.mech.name, fontsize=10)
    return fig, ax, size


def _traces(ax, fr: Frames) -> list:
    """The traced points' whole paths (thin grey) and their lines up to the frame:
    ``[(path (F, 2), line)]``."""
    mech = fr.mech
    out = []
    for b, pn in traced_points(mech):
        p = np.asarray(mech.bodies[b].points[pn], float)
        path = np.array([world(fr.analytic.theta[i, b], fr.analytic.origin[i, b], p)
                         for i in range(fr.n)])
        ax.plot(path[:, 0], path[:, 1], color="0.75", lw=0.7, zorder=2)
        out.append((path, ax.plot([], [], color="tab:purple", lw=1.2, zorder=2)[0]))
    ax.plot([], [], color="tab:purple", lw=1.2, label="point paths")
    return out


def _bodies(ax, mech):
    """``(body_art, joints, jtext)``: per moving body its outline line, fill and name
    (a one-point body, a slider block, as a square); the joint markers; joint names."""
    colours = matplotlib.rcParams["axes.prop_cycle"].by_key()["color"]
    body_art = {}
    for k, body in enumerate(mech.moving_bodies):
        col = colours[k % len(colours)]
        one = len(body.points) == 1
        (ln,) = ax.plot([], [], "-", color=col, lw=2.5, solid_capstyle="round", zorder=4,
                        marker="s" if one else None, ms=13, mfc=col, mec="k", alpha=0.9)
        fill = ax.fill([0], [0], color=col, alpha=0.2, lw=0, zorder=3)[0]
        txt = ax.text(0, 0, body.name, fontsize=8, fontweight="bold", ha="center",
                      va="bottom", color="0.1", zorder=7)
        body_art[body.name] = (ln, fill, txt)
    ax.plot([], [], "-", color="0.3", lw=2.5, label="analytic")
    (joints,) = ax.plot([], [], "o", ms=6, mfc="white", mec="k", mew=1.2, zorder=6)
    jtext = {jt.name: ax.text(0, 0, jt.name, fontsize=7, color="darkred", zorder=7)
             for jt in mech.joints}
    return body_art, joints, jtext


def _engines(ax, fr: Frames, bodies: list[str]) -> list:
    """Per engine pose set: its dashed body lines and joint crosses."""
    out = []
    for e in fr.engines:
        col = ENGINE_COLOURS.get(e.label, "tab:red")
        lines = {n: ax.plot([], [], "--", color=col, lw=1.4, zorder=5)[0] for n in bodies}
        (ej,) = ax.plot([], [], "x", color=col, ms=7, mew=1.5, zorder=6)
        ax.plot([], [], "--x", color=col, lw=1.4, label=f"{e.label} (engine)")
        out.append((e, lines, ej))
    return out


def _force_arrows(ax, fr: Frames, size: float):
    """The joint-force arrows (longest :data:`ARROW_FRACTION` of ``size``) and their
    key, or None without ``--forces``."""
    if fr.forces is None:
        return None
    n = len(fr.forces)
    peak = max(float(np.nanmax(np.linalg.norm(f, axis=1))) for f in fr.forces.values())
    scale = peak / (ARROW_FRACTION * size) if peak > 0 else 1.0  # N per m of arrow
    quiv = ax.quiver(np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), angles="xy",
                     scale_units="xy", scale=scale, color="tab:red", width=0.006, zorder=8)
    ref = _nice(0.5 * peak)
    ax.quiverkey(quiv, 0.80, 0.04, ref, f"{ref:g} N (force by body_a on body_b)",
                 labelpos="N", coordinates="axes", fontproperties={"size": 7})
    return quiv


def frames_rgb(an: Animator):
    """Each frame as an (H, W, 3) uint8 image: the still parts drawn once, the moving
    artists drawn over a copy of them per frame (blitting; the ticks' text is most of a
    full draw), and the moving names pasted as images rendered once (drawing a text
    costs ~4 ms, 4/5 of a frame, and a name's pixels do not change as it moves)."""
    canvas = an.fig.canvas
    for a in an.dynamic:
        a.set_animated(True)
    for t in an.labels:
        t.set_visible(False)
    canvas.draw()
    bg = canvas.copy_from_bbox(an.fig.bbox)
    sprites = [_sprite(t, an.fig.dpi) for t in an.labels]
    for i in range(an.n):
        canvas.restore_region(bg)
        an.draw(i)
        for a in an.dynamic:
            an.ax.draw_artist(a)
        rgb = np.asarray(canvas.buffer_rgba())[..., :3].copy()
        for t, sp in zip(an.labels, sprites, strict=True):
            _paste(rgb, sp, an.ax.transData.transform(t.get_position()))
        yield rgb
    for a in an.dynamic:
        a.set_animated(False)
    for t in an.labels:
        t.set_visible(True)


def _sprite(text, dpi: float):
    """``(rgb (h, w, 3) float, alpha (h, w, 1), (dx, dy))``: ``text`` rendered once
    alone, and the offset of its anchor from the image's top-left corner (pixels)."""
    fig = Figure(figsize=(3, 1), dpi=dpi)
    fig.patch.set_alpha(0.0)
    canvas = FigureCanvasAgg(fig)
    t = fig.text(0.5, 0.5, text.get_text(), fontproperties=text.get_fontproperties(),
                 color=text.get_color(), ha=text.get_ha(), va=text.get_va())
    canvas.draw()
    buf = np.asarray(canvas.buffer_rgba()).astype(float) / 255.0
    H = buf.shape[0]
    bb = t.get_window_extent(canvas.get_renderer())
    x0, x1 = int(math.floor(bb.x0)) - 1, int(math.ceil(bb.x1)) + 1
    r0, r1 = H - int(math.ceil(bb.y1)) - 1, H - int(math.floor(bb.y0)) + 1
    x0, r0 = max(x0, 0), max(r0, 0)
    crop = buf[r0:r1, x0:x1]
    ax_, ay_ = fig.transFigure.transform((0.5, 0.5))
    alpha = crop[..., 3:4]
    rgb = np.where(alpha > 0, crop[..., :3] / np.maximum(alpha, 1e-9), 0.0)  # unpremultiply
    return np.clip(rgb, 0, 1), alpha, (ax_ - x0, (H - ay_) - r0)


def _paste(img: np.ndarray, sprite, anchor_px) -> None:
    """Blend ``sprite`` into ``img`` (uint8, rows from the top) at the display point
    ``anchor_px`` (pixels from the bottom-left), clipped to the image."""
    rgb, alpha, (dx, dy) = sprite
    H, W = img.shape[:2]
    if not np.all(np.isfinite(anchor_px)):
        return
    c0 = int(round(anchor_px[0] - dx))
    r0 = int(round(H - anchor_px[1] - dy))
    h, w = alpha.shape[:2]
    rs, cs = max(r0, 0), max(c0, 0)
    re, ce = min(r0 + h, H), min(c0 + w, W)
    if rs >= re or cs >= ce:
        return
    sub = img[rs:re, cs:ce].astype(float) / 255.0
    a = alpha[rs - r0:re - r0, cs - c0:ce - c0]
    src = rgb[rs - r0:re - r0, cs - c0:ce - c0]
    img[rs:re, cs:ce] = np.round(255.0 * (sub * (1 - a) + src * a)).astype(np.uint8)


def write_gif(an: Animator, out: str, fps: int = 24) -> int:
    """The GIF through Pillow: one adaptive palette from the first frame (the still
    parts and the linkage's colours), no dithering.  Returns the frame count."""
    from PIL import Image
    rgbs = list(frames_rgb(an))
    # one palette for every frame, from frames spread over the cycle (colours that
    # appear late, such as the traced paths, are in it)
    pick = rgbs[:: max(1, len(rgbs) // 4)]
    pal = Image.fromarray(np.concatenate(pick, axis=0)).quantize(
        colors=128, method=Image.Quantize.MEDIANCUT)
    imgs = [Image.fromarray(rgb).quantize(palette=pal, dither=Image.Dither.NONE)
            for rgb in rgbs]
    imgs[0].save(out, save_all=True, append_images=imgs[1:], duration=round(1000 / fps),
                 loop=0, optimize=False, disposal=1)
    return len(imgs)


def write(an: Animator, out: str, fps: int = 24) -> None:
    """Write the animation to ``out`` by its extension: GIF (Pillow), MP4 (ffmpeg),
    HTML (matplotlib's self-contained JavaScript player)."""

    ext = Path(out).suffix.lower()
    try:
        if ext == ".gif":
            write_gif(an, out, fps)
            return
        if ext == ".mp4" and not animation.writers.is_available("ffmpeg"):
            raise OutputError(f"--out {out!r}: MP4 needs ffmpeg, which is not on PATH; "
                              "write .gif or .html instead (or install ffmpeg)")
        anim = animation.FuncAnimation(an.fig, an.draw, frames=an.n, interval=1000 / fps)
        if ext == ".mp4":
            anim.save(out, writer=animation.FFMpegWriter(fps=fps))
        else:
            Path(out).write_text(offline_html(anim.to_jshtml(fps=fps, default_mode="loop")))
    except OSError as e:
        raise OutputError(f"cannot write {out!r}: {e.strerror or e}") from None
    finally:
        plots.plt.close(an.fig)


#: The player's Font Awesome icons (fetched from a CDN by ``to_jshtml``) as characters,
#: so the page needs no network.
_ICONS = {"fa fa-minus": "&minus;", "fa fa-fast-backward": "&#x23EE;",
          "fa fa-step-backward": "&#x23F4;&#x2759;", "fa fa-play fa-flip-horizontal": "&#x25C0;",
          "fa fa-pause": "&#x23F8;", "fa fa-play": "&#x25B6;",
          "fa fa-step-forward": "&#x2759;&#x23F5;", "fa fa-fast-forward": "&#x23ED;",
          "fa fa-plus": "+"}


def offline_html(html: str) -> str:
    """matplotlib's JavaScript player without its one network reference (the icon
    font's stylesheet): the icons become characters."""
    html = re.sub(r'<link rel="stylesheet"\s+href="https?://[^"]*font-awesome[^"]*">', "",
                  html)
    for cls, ch in _ICONS.items():
        html = html.replace(f'<i class="{cls}"></i>', ch)
    return html


