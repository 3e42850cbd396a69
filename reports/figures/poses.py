"""What an animation shows, frame by frame: the bodies' poses from the analytic
solution, from a free trajectory, or from an engine's run (its body angles and frame
origins at its samples, through :meth:`sim_models.builders.tree.SimTree.propagate`), with the
input, the clock and the joint forces (:class:`Frames`).  Drawn by
:mod:`reports.figures.animation`; ``xval animate`` is :mod:`reports.cli.animate`."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from analytic.errors import LinkageError
from analytic.input_display import convention_of
from analytic.mechanism import Revolute
from analytic.sweep import input_values
from reports.figures.free_plots import (
    free_poses,
    sample_times,
)
from sim_models import compile_linkage
from sim_models.engines.registry import get_engine
from sim_models.runs.driven import run
from sim_models.runs.engine_run import RunRequest
from sim_models.runs.sampling import plan_samples, times_plan, travel_time

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
    interval the engines run (:func:`sim_models.runs.sampling.plan_samples`: until the input
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
    coordinates (:meth:`sim_models.builders.tree.SimTree.propagate`) where it has them, else
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
    (``frames`` samples of the last of :class:`sim_models.runs.engine_run.RunRequest`'s
    revolutions)."""
    settings = get_engine(engine).settings({})
    if times is not None:
        return run(tree, engine, settings, plan=times_plan(tree, np.asarray(times, float)))
    return run(tree, engine, settings, revolutions=RunRequest.revolutions, samples=frames)


