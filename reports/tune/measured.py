"""One candidate's measured run (:class:`Measured`) and the quantity families it is
judged by: shared by the built-in cases' runs (:mod:`reports.tune.measure`) and the
user's own model's (:mod:`reports.tune.own`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

#: Prescribed quantity families, by a quantity name's last part (``rocker.alpha``).
PRESCRIBED_FAMILY = {"alpha": "acceleration", "a": "acceleration", "effort": "force",
                     "force": "force", "normal": "force", "moment": "force"}
PRESCRIBED_FAMILIES = ("acceleration", "force")
#: Free-motion families (:class:`reports.comparison.free_compare.FreeComparison.family`).
FREE_FAMILIES = ("joint angle", "joint rate", "slider", "slider rate", "angle",
                 "angular rate", "angular acceleration", "reaction", "energy", "loop")


@dataclass(frozen=True)
class Measured:
    """One candidate's run: ``errors`` quantity -> (family, normalised error, floor);
    ``unit_steps``: steps per revolution (prescribed) or per simulated second (free);
    ``steps``: steps the run took; ``cpu``: process CPU seconds of the run; ``units``:
    revolutions or simulated seconds run."""

    overrides: dict
    ok: bool
    reason: str
    errors: dict = field(default_factory=dict)
    unit_steps: float = math.nan
    steps: int = 0
    cpu: float = math.nan
    units: float = 1.0
    settings_text: str = ""
    #: s per step of the bare stepping loop (best of a few; NaN: not timed)
    step_cost: float = math.nan
    #: process CPU s of the whole task (run, judging, timing): what the budget counts
    task_cpu: float = 0.0

    def worst(self, family: str | None = None) -> tuple[str, float]:
        """The judged quantity of ``family`` (None: all) with the largest error, and it
        (``("", inf)`` for a run that failed)."""
        if not self.ok:
            return "", math.inf
        sel = [(q, e) for q, (f, e, _fl) in self.errors.items() if family in (None, f)]
        if not sel:
            return "", math.nan
        q, e = max(sel, key=lambda x: x[1] if math.isfinite(x[1]) else math.inf)
        return q, (e if math.isfinite(e) else math.inf)

    def floor(self, family: str | None = None) -> float:
        """The largest arithmetic error floor of the family's quantities (0: float64)."""
        return max((fl for f, _e, fl in self.errors.values() if family in (None, f)),
                   default=0.0)


def prescribed_errors(comps) -> dict:
    """:attr:`Measured.errors` of a prescribed run's judged comparisons: quantity ->
    (family by the name's last part, normalised error (inf: not measured), floor)."""
    out = {}
    for c in comps:
        last = c.quantity.rsplit(".", 1)[-1]
        out[c.quantity] = (PRESCRIBED_FAMILY.get(last, last),
                           float(c.normalised) if c.measured else math.inf, float(c.floor))
    return out


def free_errors(verdict) -> dict:
    """:attr:`Measured.errors` of a free run's verdict: quantity -> (family, normalised
    error (inf: not measured), 0); the loop gap only where the model has a loop."""
    out = {c.quantity: (c.family, float(c.normalised) if c.measured else math.inf, 0.0)
           for c in verdict.judged}
    if not verdict.has_loop:
        out.pop("loop.gap", None)
    return out


__all__ = ["FREE_FAMILIES", "Measured", "PRESCRIBED_FAMILIES", "PRESCRIBED_FAMILY",
           "free_errors", "prescribed_errors"]
