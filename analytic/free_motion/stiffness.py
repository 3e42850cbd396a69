"""A refusal, before integrating, of a force element too stiff to resolve.

A spring of stiffness ``k`` whose length changes at ``L_q`` per unit of the integrated
coordinate adds ``k L_q^2`` to the generalized stiffness: against the generalized
inertia ``M`` it oscillates at ``w = sqrt(k L_q^2 / M)``.  That oscillation is part of
the exact motion, so an implicit method (which damps what it does not resolve) would
change the answer; DOP853 resolves it with about :data:`STEPS_PER_PERIOD` steps per
period.  A damper ``c`` relaxes at the rate ``c L_q^2 / M``: an explicit method is stable
only with steps below about :data:`DOP853_STABILITY` over that rate.  A run that would
need more than :data:`MAX_STEPS` steps (each of ~12 evaluations of the equation of
motion, a millisecond or more: over 20 minutes) is refused in one line naming the
element, its stiffness, the time scale and the longest duration within the budget.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import LinkageError
from ..motion_spec import JointDamper, JointSpring

#: DOP853's steps per period of an oscillation at a tolerance of 1e-13 (order 8:
#: (1e-13)^(1/8) ~ 0.02 of a period per step, so ~50).
STEPS_PER_PERIOD = 50.0
#: DOP853's stability interval on the negative real axis, in step x rate (~6).
DOP853_STABILITY = 6.0
#: Most integration steps one element may demand (see the module's docstring).
MAX_STEPS = 1e5


class TooStiffError(LinkageError):
    """A spring or damper whose time scale the integration cannot resolve in bounds."""


def _rate_of_length(lk, co, el) -> float:
    from .dynamics import _point_pair, _size
    if isinstance(el, JointSpring | JointDamper):
        k = [j.name for j in lk.mech.joints].index(el.joint)
        return float(co.x_q[0, k])
    return float(_point_pair(co.kin, el, _size(lk))[1][0])


def check_stiffness(lk, co, M: float, duration: float) -> None:
    """Raise :class:`TooStiffError` for the first element needing over :data:`MAX_STEPS`
    steps over ``duration`` s, at the release (coefficients ``co``, inertia ``M``)."""
    mech = lk.mech
    fm = mech.motion
    if not (M > 0 and math.isfinite(M)):
        return
    for kind, els in (("spring", fm.springs), ("damper", fm.dampers)):
        for i, el in enumerate(els):
            L_q = _rate_of_length(lk, co, el)
            if not np.isfinite(L_q) or L_q == 0.0:
                continue
            if kind == "spring":
                w = math.sqrt(el.stiffness * L_q * L_q / M)
                scale, steps = 2 * math.pi / w, duration * w / (2 * math.pi) * STEPS_PER_PERIOD
                what = (f"stiffness {el.stiffness:g} {_unit(lk, el, 'N m/rad', 'N/m')}",
                        f"oscillates with a period of {scale:.3g} s")
            else:
                rate = el.coefficient * L_q * L_q / M
                scale, steps = 1.0 / rate, duration * rate / DOP853_STABILITY
                what = (f"coefficient {el.coefficient:g} "
                        f"{_unit(lk, el, 'N m s/rad', 'N s/m')}", f"relaxes in {scale:.3g} s")
            if steps > MAX_STEPS:
                raise TooStiffError(
                    f"{mech.source + ': ' if mech.source else ''}{kind} {i} "
                    f"({_name(el)}, {what[0]}): against the linkage's inertia it "
                    f"{what[1]}, so {duration:g} s of exact motion needs ~{steps:.2g} "
                    f"integration steps (at most {MAX_STEPS:g}: minutes); shorten the "
                    f"duration to {duration * MAX_STEPS / steps:.3g} s or lower the "
                    f"{kind}'s {what[0].split()[0]}")


def _name(el) -> str:
    if isinstance(el, JointSpring | JointDamper):
        return f"joint {el.joint!r}"
    return f"{el.body_a}.{el.point_a} - {el.body_b}.{el.point_b}"


def _unit(lk, el, revolute: str, linear: str) -> str:
    from ..mechanism import Revolute
    if isinstance(el, JointSpring | JointDamper):
        return revolute if isinstance(lk.mech.joint(el.joint), Revolute) else linear
    return linear
