"""Released variants of prescribed-motion cases, for the engines' free runs and their
studies: :func:`released` turns a description with a ``[driver]`` into one with a
``[motion]`` (the driver's joint released at its reference value, at rest, under
gravity), optionally with force elements.  SI in and out."""

from __future__ import annotations

import math
from dataclasses import replace

from analytic import Mechanism
from analytic.motion_spec import FreeMotion

#: Standard gravity, m/s^2 (the IFToMM problems' 9.81).
G = 9.81


def released(mech: Mechanism, duration: float = 2.0, gravity: float = G,
             samples: int = 201, rate: float = 0.0, springs=(), dampers=(),
             motors=(), name: str | None = None) -> Mechanism:
    """``mech`` released at its driver's reference value with ``rate`` (rad/s or m/s)
    for ``duration`` s, gravity ``gravity`` m/s^2 in -y (the description's own gravity
    when ``gravity`` is None), with the given force elements
    (:mod:`analytic.motion_spec`).  Named ``<name>-released`` unless ``name``."""
    d = mech.driver
    g = mech.gravity if gravity is None else (0.0, -float(gravity))
    motion = FreeMotion(joint=d.joint, value=d.value, rate=float(rate),
                        duration=float(duration), samples=int(samples),
                        springs=tuple(springs), dampers=tuple(dampers), motors=tuple(motors))
    if not math.isfinite(duration) or duration <= 0:
        raise ValueError(f"duration must be > 0 s, got {duration!r}")
    return replace(mech, name=name or f"{mech.name}-released", gravity=g, motion=motion)


__all__ = ["G", "released"]
