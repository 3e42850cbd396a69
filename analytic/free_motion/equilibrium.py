"""A release at rest in an equilibrium: the exact motion stays there.

Released at rest where the generalized force is zero, the exact solution of the
equation of motion is rest, whether the equilibrium is stable or not.  An integration
from there still moves off an unstable one: the generalized force is rounding noise
(~1e-16 of its terms), which the instability amplifies exponentially (A02 upright,
N = 4: B0 3.6e-3 m off at 10 s, 2 m at 12 s).  That motion belongs to the rounding, not
to the description, so the run holds the equilibrium and says so (a ``stop`` event).
"""

from __future__ import annotations

import numpy as np

#: A generalized force below this fraction of the sum of its terms' magnitudes is zero:
#: the description's numbers are doubles, and the pose's rounding alone gives forces of
#: ~1e-16 of the terms; 1e-13 leaves a margin of a thousand for sums over many bodies.
EQUILIBRIUM_REL = 1e-13


def force_scale(lk, co) -> float:
    """The sum of the magnitudes of gravity's and the constant loads' terms in the
    generalized force at the first state of ``co`` (N m or N)."""
    from .dynamics import _massive
    mech, kin = lk.mech, co.kin
    g = abs(complex(*mech.gravity))
    bs, com, mass, _ = _massive(lk)
    total = 0.0
    if len(bs):
        r = kin.E[0, bs] * com
        vG = kin.zv[0, bs] + 1j * kin.omega[0, bs] * r
        total += float(np.sum(mass * g * np.abs(vG)))
    for ld in mech.loads:
        b = lk.body_index(ld.body)
        vP = (kin.point_c(b, ld.point)[1] if ld.point is not None else kin.com_c(b)[1])[0]
        total += abs(complex(*ld.force)) * abs(vP) + abs(ld.torque * kin.omega[0, b])
    return total


def held(mech, lk, co, Q: float) -> bool:
    """Whether a release at rest is an equilibrium to hold: no force element (springs
    and motors act through their own terms; a motor table may start later), and the
    generalized force ``Q`` at most :data:`EQUILIBRIUM_REL` of :func:`force_scale`."""
    fm = mech.motion
    if fm.rate != 0.0 or fm.springs or fm.motors:
        return False
    scale = force_scale(lk, co)
    return scale > 0.0 and abs(Q) <= EQUILIBRIUM_REL * scale
