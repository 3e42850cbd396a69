"""What a failed free-motion verdict says beside its numbers: the reference event nearest
the time the trust was lost (:func:`near_free_event`) and how far the released joint moves
in one engine step (:func:`free_step_note`)."""

from __future__ import annotations

import math

import numpy as np

from analytic.mechanism import Revolute

#: A failed verdict names a reference event within this fraction of the run's duration
#: of the time the trust was lost (the first tolerance excess): an error that starts
#: growing there was started by the event (a singular crossing is where an engine picks
#: a branch), one farther off was not.  The window never reaches halfway to the next
#: event or to the run's start or end: A02 crosses a singular position every 0.52 s,
#: and 5% of its 20 s would have named the crossing at 0.72 s for a trust lost at 0.10 s.
NEAR_EVENT_FRACTION = 0.05
#: Reference events named for a failed verdict (a turning point of the motion is not a
#: place where anything is singular).
EVENT_KINDS = ("switch", "singular", "limit")


def near_free_event(v, events) -> str | None:
    """For a failed verdict ``v`` (a :class:`~reports.comparison.free_compare.FreeVerdict`):
    the reference event (:data:`EVENT_KINDS`) nearest the time the trust was lost (its
    trusted horizon), when within :data:`NEAR_EVENT_FRACTION` of the duration and nearer
    than halfway to the event's neighbours (the events before and after it, or the run's
    start and end); else None."""
    t_lost = v.horizon
    if not math.isfinite(t_lost):
        return None
    evs = sorted((e for e in events if e.kind in EVENT_KINDS), key=lambda e: e.t)
    if not evs:
        return None
    i = min(range(len(evs)), key=lambda k: abs(evs[k].t - t_lost))
    e = evs[i]
    dt = t_lost - e.t
    # the neighbour on the side the trust was lost: the event there, or the run's end
    if dt >= 0:
        neighbour = evs[i + 1].t if i + 1 < len(evs) else v.duration
    else:
        neighbour = evs[i - 1].t if i > 0 else 0.0
    if abs(dt) > min(NEAR_EVENT_FRACTION * v.duration, abs(neighbour - e.t) / 2):
        return None
    kind = {"switch": "coordinate switch", "singular": "singular position crossed",
            "limit": "limit position"}[e.kind]
    side = "after" if dt >= 0 else "before"
    who = v.lost_by.quantity if v.lost_by else "the run stopped"
    return (f"the trust is lost at t = {t_lost:.4g} s ({who}), {abs(dt):.3g} s "
            f"{side} the reference's {kind} at t = {e.t:.6g} s ({e.joint}: {e.detail}): "
            "there the motion picks a branch or a coordinate fails, so a small engine "
            "offset becomes a large error")


def free_step_note(run, ref, mech) -> str | None:
    """For a failed verdict: the engine's step in time and how far the released joint
    (``mech.motion.joint``) moves in one step at its fastest."""
    dt = float(run.timestep)
    if not (math.isfinite(dt) and dt > 0) or mech.motion is None:
        return None
    jn = mech.motion.joint
    i = list(ref.joints).index(jn)
    rate = np.abs(ref.xd[:, i])
    rate = rate[np.isfinite(rate)]
    if not rate.size:
        return None
    k = float(np.max(rate))
    revolute = isinstance(next(j for j in mech.joints if j.name == jn), Revolute)
    inc = (f"{k * dt:.3g} rad ({math.degrees(k * dt):.3g} deg)" if revolute
           else f"{k * dt:.3g} m")
    return (f"the engine steps {dt:.3g} s ({run.integrator}); joint {jn} moves up to {inc} "
            f"per step ({k:.4g} {'rad/s' if revolute else 'm/s'} at its fastest): rerun with "
            f"--timestep {dt / 4:.2g} to see whether the error falls with the step (the "
            "integrator) or not (the model or the constraint stabilisation)")


__all__ = ["EVENT_KINDS", "NEAR_EVENT_FRACTION", "free_step_note", "near_free_event"]
