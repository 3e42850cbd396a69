"""The free-motion cases the verdicts, studies and report run: the IFToMM problems and
the built-in cases released under gravity.

A built-in case has no ``[motion]`` table (it is driven): the engines' own
:func:`sim_models.free_cases.released` gives it one (released at rest from its driver's
reference value under 9.81 m/s^2 in -y, named ``<case>-released``), so the verdicts
judge exactly the mechanism the engines run.
"""

from __future__ import annotations

from dataclasses import replace

from analytic import Mechanism, load_case
from analytic.errors import DescriptionError
from sim_models.free_cases import released

#: How long a released built-in case runs, s (issue 21: "released under gravity for 2 s").
RELEASE_DURATION = 2.0
#: The IFToMM A02 file's name (written by analytic.free_motion.iftomm.n_four_bar_toml).
A02 = "iftomm-a02-n-four-bar"


def free_case(name: str, duration: float | None = None) -> Mechanism:
    """A free-motion case by name or file: its own ``[motion]`` (duration overridden by
    ``duration``) or, for a driven case, released for ``duration`` (default
    :data:`RELEASE_DURATION`).  A02 comes from
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
    if duration is None:
        return mech
    return replace(mech, motion=replace(mech.motion, duration=float(duration)))


def _a02() -> Mechanism:
    import tomllib

    from analytic.free_motion.iftomm import n_four_bar_toml
    from analytic.toml_io import mechanism_from_dict
    return mechanism_from_dict(tomllib.loads(n_four_bar_toml()), A02)
