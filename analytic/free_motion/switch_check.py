"""The state at a coordinate switch, and the self-check that sees a state lost there.

A terminal event of ``solve_ivp`` ends the run at the event time with the state from the
step's dense output (DOP853's is of order 7, much less accurate than the step itself:
1.5e-10 rad/s off on the free01 reproducer, where the next coordinate's rate is four
times that and the motion then amplifies it tenfold).  :func:`event_state` integrates
instead from the last accepted step to the event time, so the state carried into the
new coordinate is as accurate as a step.

:class:`Overlap` is the self-check: the old coordinate, still regular just past the
switch (its coefficients are finite up to the limit position, and the switch is made a
factor :data:`~.integrate.SWITCH_RATIO` before it), is integrated on from its last step
to the new segment's first step, and the two solutions are compared there, the new
one mapped into the old coordinate.  Two integrations of the same motion in two
coordinates with different equations agree to the integration's tolerance; a state
lost at the switch, an error in either coordinate's accelerations or a branch mix-up
shows as their difference.  The defect is the larger of the coordinate's difference
(rad, or fraction of the mechanism's size) and the rate's (fraction of the rate scale
of the integration's absolute tolerance).
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from ..errors import LinkageError
from .dynamics import coefficients, unwrap_to

#: The old coordinate is integrated past the switch only while its largest coefficient
#: stays below this (per unit of its rate): far enough from its limit position that
#: it stays well conditioned (the switch happens at 4).
OVERLAP_RATIO = 16.0


def event_state(sysm, sol, method: str, rtol: float, atol) -> np.ndarray:
    """The state at ``sol``'s last time (a terminal event), integrated from the last
    accepted step rather than read from the dense output."""
    t0, t1 = float(sol.t[-2]), float(sol.t[-1])
    if not t1 > t0:
        return sol.y[:, -1].copy()
    last = sysm.last
    r = solve_ivp(sysm, (t0, t1), sol.y[:, -2], method=method, rtol=rtol, atol=atol)
    sysm.last = last
    if r.status != 0:
        return sol.y[:, -1].copy()
    return r.y[:, -1].copy()


class Overlap:
    """The old coordinate's last step before a switch, to be continued past it."""

    def __init__(self, sysm, t0: float, y0: np.ndarray, method: str, rtol: float, atol):
        self.sysm, self.t0, self.y0 = sysm, t0, y0
        self.method, self.rtol, self.atol = method, rtol, atol

    def defect(self, new_sysm, new_sol) -> float | None:
        """The difference of the two coordinates' solutions at the new segment's first
        step (see the module's docstring); None where the old coordinate cannot reach it
        regularly (the limit position comes first) or the new segment has no step."""
        if len(new_sol.t) < 2:
            return None
        tc = float(new_sol.t[1])
        old = self.sysm

        def too_far(t, y):
            return float(np.max(old.ratios(float(y[0])))) - OVERLAP_RATIO
        too_far.terminal = True
        try:
            r = solve_ivp(old, (self.t0, tc), self.y0, method=self.method, rtol=self.rtol,
                          atol=self.atol, events=[too_far])
        except LinkageError:
            return None
        if r.status != 0:
            return None
        q_old, qd_old = float(r.y[0, -1]), float(r.y[1, -1])
        co = coefficients(new_sysm.lk, float(new_sol.y[0, 1]))
        k = old.k
        x = unwrap_to(co.x[0], old.last, old.rev)
        dq = abs(x[k] - q_old) / self.atol[0] * self.rtol
        dqd = abs(co.x_q[0, k] * new_sol.y[1, 1] - qd_old) / self.atol[1] * self.rtol
        return float(max(dq, dqd))
