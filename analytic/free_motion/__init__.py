"""Free motion: a released linkage's exact trajectory (the reference side of the engine
comparison in free motion).

    from analytic import load_case
    from analytic.free_motion import simulate
    traj = simulate(load_case("iftomm-a01-pendulum"))
    s = traj.at([0.0, 1.0])        # FreeSamples: joints, bodies, energies, reactions
    traj.events                    # switches, singular crossings, limit positions

See :mod:`.dynamics` (the equation of motion from the solver), :mod:`.integrate` (DOP853
and coordinate switching) and :mod:`.trajectory` (sampling, events).
"""

from __future__ import annotations

from ..errors import DescriptionError
from ..motion_spec import check_duration
from .clock import MAX_WALL_LIMIT, WallClock, WallLimitError
from .integrate import RTOL, integrate
from .trajectory import Event, FreeSamples, FreeTrajectory, find_events


def simulate(mech, duration: float | None = None, rtol: float = RTOL,
             method: str = "DOP853", wall_limit: float | None = None,
             progress=None) -> FreeTrajectory:
    """Integrate ``mech.motion`` (its ``[motion]`` description) over ``duration`` s
    (default the description's); ``method`` any of SciPy's ``solve_ivp`` methods
    (``"Radau"`` for a second opinion).  Returns the :class:`FreeTrajectory`, with
    ``events`` listed.  ``wall_limit`` s (None: none) bounds the integration and the
    event location (:class:`~.clock.WallLimitError` past it, checked at every
    evaluation); ``progress(t, duration)`` is called every quarter second.  The
    trajectory keeps that clock as ``clock``: ``traj.at(times, clock=traj.clock)``
    samples it under the same limit (what the command line does)."""
    if mech.motion is None:
        raise DescriptionError("no [motion] table: free motion needs the initial joint, "
                               "value, rate and duration", mech.source)
    if duration is not None:
        check_duration(mech, duration)  # in range, and every motor table covers it
    T = mech.motion.duration if duration is None else float(duration)
    where = f"{mech.source}: " if mech.source else ""
    clock = WallClock(f"{where}mechanism {mech.name!r}", T, wall_limit, progress)
    segs, switches = integrate(mech, duration, rtol, method, clock)
    traj = FreeTrajectory(mech, segs, switches, rtol, method)
    traj.events = find_events(traj, clock)
    traj.clock = clock  # the same limit for its sampling: traj.at(..., clock=traj.clock)
    return traj


__all__ = ["MAX_WALL_LIMIT", "Event", "FreeSamples", "FreeTrajectory", "WallLimitError",
           "simulate"]
