"""``xval animate CASE|FILE --out F.gif|F.mp4|F.html``: the linkage moving through a cycle.

A full-turn input turns once from its reference value, so the first frame is the
assembled reference pose; a limited input goes from the reference value to one end of
its feasible range, back to the other and back to the reference (its time runs on at
the description's rate).  Each frame draws the bodies (outline through their points,
named), the joints (named; a slider as a square on its dashed line), the ground hatched
under its pivots and guides, the paths of the points of the bodies not pinned to the
ground (thin grey, traced in colour up to the frame), the current input value and time,
and with ``--forces`` the joint forces as arrows on a common scale with a key.

With ``--engine`` the engine's poses (its body angles and frame origins at its samples,
from the run's tree coordinates through :meth:`sim_models.tree.SimTree.propagate`) are
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

from analytic import load_case
from analytic.errors import LinkageError, OutputError
from analytic.input_display import InputConvention, convention_of, input_text
from analytic.mechanism import Prismatic, Revolute
from analytic.motion_spec import MAX_DURATION
from analytic.sweep import input_values
from reports.cli import options as opt
from reports.cli.paths import check_outputs
from reports.cli.plot import check_out
from reports.cli.simulate import MIN_DURATION
from reports.comparison.progress import engine_progress
from reports.comparison.runs import engine_list
from reports.figures import plots
from reports.figures.free_plots import (
    FreeOptionError,
    free_poses,
    is_free,
    sample_times,
    swing_note,
    trajectory,
)
from sim_models import compile_linkage
from sim_models.engines import run
from sim_models.registry import engine_names, get_engine
from sim_models.sampling import plan_samples, times_plan, travel_time

#: Frames per cycle by default (>= 36 so a turn is drawn every 5 deg at most).
FRAMES = 72
FORMATS = (".gif", ".mp4", ".html")
#: The longest force arrow, as a fraction of the mechanism's size.
ARROW_FRACTION = 0.3
ENGINE_COLOURS = {"mujoco": "tab:red", "pybullet": "tab:orange", "exudyn": "tab:green"}


@dataclass
class Poses:
    """Body poses along the frames: ``theta`` (F, B) rad and ``origin`` (F, B, 2) m of
    every body frame (description order, ground included); NaN where not available."""

    label: str
    theta: np.ndarray
    origin: np.ndarray


@dataclass
class Frames:
    """What the animation shows, frame by frame (SI)."""

    mech: object
    values: np.ndarray            # (F,) input value, rad or m
    times: np.ndarray             # (F,) s
    analytic: Poses
    engines: list[Poses] = field(default_factory=list)
    forces: dict | None = None    # joint -> (F, 2) N, by body_a on body_b
    revolute: bool = True
    rates: np.ndarray | None = None          # (F,) prescribed rate, rad/s or m/s
    accelerations: np.ndarray | None = None  # (F,) prescribed acceleration
    convention: object = None     # analytic.input_display.InputConvention of the input
    free_joint: str | None = None  # a free run's [motion] joint: values, rates are its own

    @property
    def n(self) -> int:
        return len(self.values)


# ============================================================================ frames
def frame_times(linkage, frames: int = FRAMES, tree=None) -> np.ndarray:
    """Equal times (s, from t = 0) along the prescribed motion: one turn of a full-turn
    input (its first, at the accelerating rate where it accelerates), else the
    interval the engines run (:func:`sim_models.sampling.plan_samples`: until the input
    nears a limit position, or has travelled its range).  A driver with neither rate
    nor acceleration has no motion: one line, status 2."""
    d = linkage.mech.driver
    if input_values(linkage, 2)[1]:
        T = travel_time(d, 2 * math.pi)
        if math.isfinite(T) and T > 0:
            return T * np.arange(frames) / frames
    plan = plan_samples(tree or compile_linkage(linkage.mech), 1, max(frames, 2))
    return np.linspace(0.0, float(plan.t_end), frames)


def frame_inputs(linkage, frames: int = FRAMES, tree=None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """``(values, times)`` of the frames: :func:`frame_times` and the prescribed input
    value (rad or m) there, ``value + v t + a t^2 / 2``, unwrapped."""
    t = frame_times(linkage, frames, tree)
    return prescribed(linkage, t)[0], t


def prescribed(linkage, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The description's driver law at times ``t`` (s): value, rate, acceleration."""
    d = linkage.mech.driver
    t = np.asarray(t, float)
    return (d.value + d.velocity * t + 0.5 * d.acceleration * t * t,
            d.velocity + d.acceleration * t, np.full_like(t, d.acceleration))


def analytic_frames(linkage, frames: int = FRAMES, forces: bool = False,
                    tree=None) -> Frames:
    """The analytic poses (and joint forces) at :func:`frame_times` along the
    prescribed motion (its rate and acceleration at each frame), on the branch the
    moving linkage follows from the reference assembly."""
    mech = linkage.mech
    times = frame_times(linkage, frames, tree)
    values, rate, acc = prescribed(linkage, times)
    kin = linkage.kinematics_along(values, rate, acc)
    frc = None
    if forces:
        if not mech.has_mass:
            raise LinkageError(f"--forces: {mech.name!r} has no masses, so no joint forces "
                               "are computed")
        f = linkage.forces(kin)
        frc = {jt.name: np.asarray(f.joint_force[jt.name], float) for jt in mech.joints}
    return Frames(mech, values, times, Poses("analytic", np.asarray(kin.theta, float),
                                             np.asarray(kin.origin, float)),
                  forces=frc, revolute=linkage.driver_is_revolute, rates=rate,
                  accelerations=acc, convention=convention_of(linkage))


def free_frames(traj, frames: int, forces: bool = False):
    """:class:`Frames` at ``frames`` evenly spaced times from 0 to the
    duration: the poses, the ``[motion]`` joint's coordinate and rate, and with
    ``forces`` the joint reactions (N, by body_a on body_b)."""
    mech = traj.mech
    t = sample_times(traj, frames)
    smp = traj.at(t, forces=forces)
    k = traj.joints.index(mech.motion.joint)
    theta, origin = free_poses(traj, t)
    return Frames(mech, smp.x[:, k], t, Poses("analytic", theta, origin),
                  forces=dict(smp.reactions) if forces else None,
                  revolute=isinstance(mech.joints[k], Revolute), rates=smp.xd[:, k],
                  accelerations=smp.xdd[:, k], free_joint=mech.motion.joint)


def engine_pose_arrays(run_, tree) -> tuple[np.ndarray, np.ndarray]:
    """``(theta (N, B), origin (N, B, 2))`` of an engine run's samples: from its tree
    coordinates (:meth:`sim_models.tree.SimTree.propagate`) where it has them, else
    the absolute poses it recorded (an engine in absolute coordinates, Exudyn); NaN
    where it has neither."""
    N, B = np.shape(run_.theta)
    theta, origin = np.full((N, B), np.nan), np.full((N, B, 2), np.nan)
    if run_.q is not None:
        ok = np.all(np.isfinite(run_.q), axis=1)
        if ok.any():
            th, _, _, org = tree.propagate(run_.q[ok], run_.qd[ok], run_.qdd[ok])[:4]
            theta[ok], origin[ok] = th, org
    if run_.origin is not None:
        absent = ~np.all(np.isfinite(theta), axis=1)
        theta[absent] = np.asarray(run_.theta, float)[absent]
        origin[absent] = np.asarray(run_.origin, float)[absent]
    return theta, origin


def engine_poses(run_, tree, values: np.ndarray, full: bool, times=None) -> Poses:
    """The engine's body poses at the frames: with ``times`` (the frames' times, s),
    the run's sample at the same time (within 1e-9 of the run's span: a run sampled at
    the frames, :func:`engine_run`); else the sample at the same input value (modulo a
    turn for a full-turn crank; within a tenth of the frame spacing).  NaN where the
    run has none."""
    th, org = engine_pose_arrays(run_, tree)
    ok = np.all(np.isfinite(th), axis=1) & np.all(np.isfinite(org), axis=(1, 2))
    F, B = len(values), th.shape[1]
    theta, origin = np.full((F, B), np.nan), np.full((F, B, 2), np.nan)
    if times is not None:
        st = np.asarray(run_.times, float)
        span = max(float(np.nanmax(st)) if np.isfinite(st).any() else 0.0, 1e-12)
        for i, t in enumerate(np.asarray(times, float)):
            dt = np.where(ok & np.isfinite(st), np.abs(st - t), np.inf)
            k = int(np.argmin(dt))
            if dt[k] <= 1e-9 * span:
                theta[i], origin[i] = th[k], org[k]
        return Poses(run_.engine, theta, origin)
    sv = np.asarray(run_.values, float)
    spacing = np.min(np.abs(np.diff(values))) if len(values) > 1 else 1.0
    for i, v in enumerate(values):
        dv = sv - v
        if full:
            dv = (dv + math.pi) % (2 * math.pi) - math.pi
        dv = np.where(ok, np.abs(dv), np.inf)
        k = int(np.argmin(dv))
        if dv[k] <= 0.1 * spacing:
            theta[i], origin[i] = th[k], org[k]
    return Poses(run_.engine, theta, origin)


def engine_run(mech, tree, engine: str, frames: int, times=None):
    """An engine run sampled at the frames: at their ``times`` (s, the prescribed
    motion from t = 0: one sample a frame) when given, else at the verdict's plan
    (``frames`` samples of the last of two turns)."""
    settings = get_engine(engine).settings({})
    if times is not None:
        return run(tree, engine, settings, plan=times_plan(tree, np.asarray(times, float)))
    return run(tree, engine, settings, revolutions=2, samples=frames)


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


def cmd_animate(args) -> int:
    if args.out is None:
        raise OutputError("option --out is required: F.gif, F.mp4 or F.html")
    check_out(args.out, FORMATS)
    check_outputs([("--out", args.out)], [("the case file", args.case)])
    if Path(args.out).suffix.lower() == ".mp4":
        if not animation.writers.is_available("ffmpeg"):
            raise OutputError(f"--out {args.out!r}: MP4 needs ffmpeg, which is not on PATH; "
                              "write .gif or .html instead (or install ffmpeg)")
    mech = load_case(args.case)
    if is_free(mech, args.free, args.driven):
        return _animate_free(args, mech)
    if args.duration is not None:
        raise FreeOptionError("option --duration is for free motion (a description with "
                              "[motion]); a prescribed animation runs one cycle")
    # the compiled linkage (analytic solution + simulation tree): the frames' times come
    # from the engines' plan where the input does not turn fully
    tree = compile_linkage(mech)
    fr = analytic_frames(tree.linkage, args.frames, args.forces, tree)
    notes = []
    if args.engine:
        for e in engine_list(args.engine):
            with engine_progress(f"{e}: {mech.name}, {fr.n} frames"):
                r = engine_run(mech, tree, e, args.frames, times=fr.times)  # a frame a sample
            if not r.ok:
                notes.append(f"{e}: run failed: {r.reason}")
            poses = engine_poses(r, tree, fr.values, False, times=fr.times)
            missing = int(np.sum(~np.all(np.isfinite(poses.theta), axis=1)))
            if missing == fr.n:
                notes.append(f"{e}: not drawn: no pose at any frame ("
                             + (r.reason or "the run recorded no body poses") + ")")
            elif missing:
                notes.append(f"{e}: no pose at {missing} of {fr.n} frames (drawn where it "
                             "has one" + (f"; {r.reason}" if r.reason else "") + ")")
            fr.engines.append(poses)
    label = "analytic" + ("".join(f" + {e.label} (dashed)" for e in fr.engines))
    an = build_animation(fr, f"{mech.name}: {label}")
    write(an, args.out, args.fps)
    for n in notes:
        print("note:", n)
    print(f"wrote {args.out} ({fr.n} frames, {fr.times[-1]:.4g} s of motion)")
    return 0


def _animate_free(args, mech) -> int:
    """The free motion of ``[motion]``: poses at ``--frames`` evenly spaced times from 0
    to the duration, with the clock."""
    if args.engine:
        raise FreeOptionError(f"option --engine: {mech.name!r} is animated in free motion (its "
                              "[motion] table), which draws no engine run; add --driven for "
                              "the prescribed cycle")
    traj = trajectory(mech, args.duration)
    fr = free_frames(traj, args.frames, args.forces)
    an = build_animation(fr, f"{mech.name}: free motion, {traj.duration:g} s "
                             f"({len(traj.events)} events)")
    write(an, args.out, args.fps)
    note = swing_note(traj, traj.duration / (fr.n - 1), "frames")
    if note:
        print("note:", note)
    print(f"wrote {args.out} (free motion, {fr.n} frames every "
          f"{traj.duration / (fr.n - 1):.4g} s over {traj.duration:g} s)")
    return 0


def register(sub) -> None:
    s = sub.add_parser("animate", help="the linkage moving through a cycle, or its free "
                       "motion (GIF, MP4, HTML)")
    s.add_argument("case", help="built-in case name or TOML file")
    mode = s.add_mutually_exclusive_group()
    mode.add_argument("--free", action="store_true",
                      help="animate the free motion of the description's [motion] table (the "
                           "default when it has one): poses at evenly spaced times, clock shown")
    mode.add_argument("--driven", action="store_true",
                      help="animate the prescribed cycle of [driver] even when the "
                           "description has a [motion] table")
    s.add_argument("--out", type=opt.output_file, help="F.gif, F.mp4 (needs ffmpeg) or F.html")
    s.add_argument("--engine", choices=[*engine_names(), "all"],
                   help="draw this engine's poses (dashed) over the analytic ones")
    s.add_argument("--forces", action="store_true",
                   help="joint forces as arrows on one scale, with a key")
    s.add_argument("--frames", type=opt.int_range(36, 720, "frames per cycle"),
                   default=FRAMES, help=f"frames per cycle (free motion: over the run), 36 "
                                        f"to 720 (default {FRAMES})")
    s.add_argument("--duration", type=opt.finite_float(MAX_DURATION, "s", lo=MIN_DURATION),
                   help=f"free motion: seconds, {MIN_DURATION:g} to {MAX_DURATION:g} "
                        "(default the description's)")
    s.add_argument("--fps", type=opt.int_range(1, 60, "frames per second"), default=24,
                   help="frames per second, 1 to 60 (default 24)")
    s.set_defaults(func=cmd_animate)


__all__ = ["Animator", "Frames", "Poses", "analytic_frames", "body_outlines", "free_frames",
           "build_animation", "cmd_animate", "engine_poses", "frame_inputs", "frames_rgb",
           "joint_positions", "register", "write", "write_gif"]
