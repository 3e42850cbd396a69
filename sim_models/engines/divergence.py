"""The divergence checks of an engine's run: a state (tree coordinates, or a loop gap and
the driver's rate) that has left the motion: non-finite or huge values, a loop open beyond
``max_violation`` of the size, the driver's rate off its prescribed law.  Shared by every
engine's session (:mod:`sim_models.engines.protocol` re-exports them)."""

from __future__ import annotations

import math

import numpy as np

from ..builders.tree import SimTree
from ..runs.engine_run import loop_gap


def check_state(tree: SimTree, q, qd, t: float, max_violation: float,
                max_speed_error: float) -> str | None:
    """The shared divergence check of raw tree coordinates at time ``t``."""
    q, qd = np.asarray(q, float), np.asarray(qd, float)
    why = check_raw_state(q, qd)
    if why is not None:
        return why
    th, _, _, org, _, _ = tree.propagate(q[None], qd[None], np.zeros_like(q)[None])
    return check_motion(tree, loop_gap(tree, th, org),
                        tree.driver_sigma * qd[tree.driver_tree], t, max_violation,
                        max_speed_error)


def check_motion(tree: SimTree, gap: float, rate: float, t: float, max_violation: float,
                 max_speed_error: float) -> str | None:
    """The divergence check from a loop gap (m) and the driver's rate at time ``t``
    (for engines in absolute coordinates; NaN counts as diverged)."""
    if not (math.isfinite(gap) and math.isfinite(rate)) or abs(rate) > HUGE:
        return "non-finite or huge state (simulation diverged)"
    vmax = max_violation * tree.size
    if gap > vmax:
        return f"loop violation {gap:.3g} m > {vmax:.3g} m"
    _, vel, _ = tree.driver_path(t)
    vel = float(vel)
    ref = max(abs(vel), abs(tree.mech.driver.velocity), 1e-12)
    if abs(rate - vel) > max_speed_error * ref:
        return f"driver rate off by {abs(rate - vel):.3g} (> {max_speed_error:g} relative)"
    return None


def check_raw_state(q, qd) -> str | None:
    """The part of :func:`check_state` a raw record needs no conversion for: non-finite
    or huge tree coordinates ``q, qd`` (same messages)."""
    if not (np.isfinite(q).all() and np.isfinite(qd).all()):
        return "non-finite state (simulation diverged)"
    if np.abs(qd).max(initial=0.0) > HUGE:
        return "huge velocities (simulation diverged)"
    return None


def first_divergence(tree: SimTree, gap, rate, times, max_violation: float,
                     max_speed_error: float) -> tuple[int | None, str | None]:
    """The first record (index into ``times``) whose loop gap or driver rate fails
    :func:`check_motion`, and its reason; ``(None, None)`` when none does.  Vectorised
    screen (a slightly wider net), then :func:`check_motion` itself on the candidates,
    so the verdict and the message are exactly the per-sample check's."""
    gap, rate, times = (np.asarray(x, float) for x in (gap, rate, times))
    if not len(times):
        return None, None
    _, vel, _ = tree.driver_path(times)
    ref = np.maximum(np.maximum(np.abs(vel), abs(tree.mech.driver.velocity)), 1e-12)
    with np.errstate(invalid="ignore", over="ignore"):
        net = 1.0 - 1e-9
        bad = ~(np.isfinite(gap) & np.isfinite(rate)) | (np.abs(rate) > net * HUGE) \
            | (gap > net * max_violation * tree.size) \
            | (np.abs(rate - vel) > net * max_speed_error * ref)
    for k in np.flatnonzero(bad):
        why = check_motion(tree, float(gap[k]), float(rate[k]), float(times[k]),
                           max_violation, max_speed_error)
        if why is not None:
            return int(k), why
    return None, None


#: Velocities above this (MuJoCo's own "huge value" threshold) count as divergence.
HUGE = 1e10
