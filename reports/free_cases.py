"""The free-motion cases the verdicts, studies and report run: the IFToMM problems and
the built-in cases released under gravity.

A built-in case has no ``[motion]`` table (it is driven): :func:`released` gives it one,
released at rest from its driver's reference value, under standard gravity where the
case has none (the seed four-bar, the six-bar and the slider-cranks are drawn in a
horizontal plane; without gravity, at rest, nothing would move).
"""

from __future__ import annotations

import math
from dataclasses import replace

from analytic import Mechanism, load_case
from analytic.errors import DescriptionError
from analytic.motion_spec import FreeMotion

#: Gravity given to a built-in case that has none when it is released, m/s^2 (standard
#: gravity, in -y as the IFToMM problems have it).
RELEASE_GRAVITY = (0.0, -9.81)
#: How long a released built-in case runs, s (issue 21: "released under gravity for 2 s").
RELEASE_DURATION = 2.0
#: The IFToMM A02 file's name (written by analytic.free_motion.iftomm.n_four_bar_toml).
A02 = "iftomm-a02-n-four-bar"


def released(mech: Mechanism, duration: float = RELEASE_DURATION) -> Mechanism:
    """``mech`` released at rest from its driver's reference value (its ``[motion]``
    kept when it has one, with ``duration``), under :data:`RELEASE_GRAVITY` when it has
    no gravity."""
    if mech.motion is not None:
        return replace(mech, motion=replace(mech.motion, duration=float(duration)))
    g = mech.gravity if math.hypot(*mech.gravity) > 0 else RELEASE_GRAVITY
    return replace(mech, gravity=g, motion=FreeMotion(mech.driver.joint, mech.driver.value,
                                                      0.0, float(duration)))


def free_case(name: str, duration: float | None = None) -> Mechanism:
    """A free-motion case by name or file: its own ``[motion]`` (duration overridden by
    ``duration``) or, for a driven case, :func:`released`.  A02 comes from
    :func:`analytic.free_motion.iftomm.n_four_bar_toml` when no file of that name is
    shipped."""
    if name == A02:
        try:
            mech = load_case(name)
        except DescriptionError:  # not shipped (yet): write it
            mech = _a02()
    else:
        mech = load_case(name)
    if mech.motion is None:
        return released(mech, RELEASE_DURATION if duration is None else duration)
    return mech if duration is None else released(mech, duration)


def _a02() -> Mechanism:
    import tomllib

    from analytic.free_motion.iftomm import n_four_bar_toml
    from analytic.toml_io import mechanism_from_dict
    return mechanism_from_dict(tomllib.loads(n_four_bar_toml()), A02)
