"""The speed studies' timing: steps per second of an engine's bare stepping loop, no
readout (:func:`time_steps` for a driven session from the analytic reference state,
:func:`time_free_steps` for a released one from its start; one loop,
:func:`best_step_rate`)."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..engines.free_protocol import FreeSession, FreeStart
    from ..engines.protocol import Session


def time_steps(session: Session, h: float, n: int, repeats: int = 3,
               clock=time.perf_counter) -> float:
    """Steps per second of ``n`` bare steps (:meth:`Session.advance`, no readout) from
    the analytic reference state, best of ``repeats``: what the speed studies time.  A
    loop that diverges is timed up to that point.  ``clock``: wall time by default;
    ``time.process_time`` counts this process's CPU only (``xval tune``)."""
    return best_step_rate(lambda: session.reset(0.0, h), session.advance, h, n, repeats,
                          clock)


def best_step_rate(start, advance, h: float, n: int, repeats: int = 3,
                   clock=time.perf_counter) -> float:
    """Steps per second of ``n`` bare steps ``advance(t, h, k)`` (in chunks of at most
    200, stopping where it returns a reason) after ``start()``, best of ``repeats``: the
    one timing loop of the driven (:func:`time_steps`) and the released runs."""
    best = 0.0
    chunk = max(1, min(n, 200))
    for _ in range(max(1, repeats)):
        start()
        done, t = 0, 0.0
        t0 = clock()
        while done < n:
            k = min(chunk, n - done)
            why = advance(t, h, k)
            done += k
            t += k * h
            if why is not None:
                break
        el = clock() - t0
        if el > 0:
            best = max(best, done / el)
    return best


def time_free_steps(session: FreeSession, s0: FreeStart, h: float, n: int,
                    repeats: int = 3, clock=time.perf_counter) -> float:
    """Steps per second of ``n`` bare :meth:`FreeSession.advance` steps from the
    released state (no readout), best of ``repeats``: what the speed study times.
    ``clock``: wall time by default; ``time.process_time`` for CPU (``xval tune``)."""
    return best_step_rate(lambda: session.start(s0, h), session.advance, h, n, repeats,
                          clock)


__all__ = ["best_step_rate", "time_free_steps", "time_steps"]
