"""Known engine limits of the report's free-motion verdicts, and the verdict each row
gets from them: ``pass``, ``FAIL``, or ``known limit``.

A *known limit* is a case an engine is measured not to follow at its recommended
free-motion setting for a reason that lies in the engine (its integrator's order at
that step), with the measurement that shows it.  The report states it in the verdict
table and on its summary line and does not count it in the exit status; a listed
limit holds only while the run completes and its worst error stays within
``worst_max``: a run that stopped, or an error beyond what was measured, is a FAIL
like any other (a regression of the engine or the harness is never hidden by the list).

No tolerance is widened here: the row's judged errors, horizon and drifts are those of
:mod:`reports.comparison.free_compare` at its tolerances; only the exit status differs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class KnownLimit:
    """One engine x case x duration the engine is measured not to follow at its
    recommended free-motion setting.  ``worst_max``: the largest worst error (of its
    scale, as :attr:`reports.studies.free_studies.FreeRow.worst_error`) the limit covers;
    ``reason``: what was measured, said in the report."""

    engine: str
    case: str
    duration: float
    worst_max: float
    reason: str


#: Measured 2026-11-27 on the shared 2-core machine (load 4), 100 samples, 1 s, the seed
#: four-bar released at rest under 9.81 m/s^2: PyBullet's worst error (O4.x over its
#: range) is 3.5e-2 at its recommended 1e-4 s step, 1.76e-2 at 5e-5 s and 8.8e-3 at
#: 2.5e-5 s (halving exactly with the step: its semi-implicit Euler, first order), and
#: 3.57e-2 / 3.50e-2 at ERP 0.2 / 0.8 (the loop stabilisation does not move it);
#: MuJoCo (3.6e-7), Exudyn (1.4e-4) and Pinocchio (1.4e-6) follow the same exact
#: trajectory, so neither the reference nor the model is wrong.  ``worst_max`` is twice
#: the measured error: the error of the same first-order integrator at twice the step,
#: so a halved effective accuracy (a step doubled, an order lost) is a FAIL.
KNOWN_LIMITS = (
    KnownLimit("pybullet", "seed-four-bar-released", 1.0, 7.0e-2,
               "PyBullet's semi-implicit Euler is first order: at its recommended 1e-4 s "
               "the phase error reaches 3.5e-2 of the range in 1 s (halved with each "
               "halved step, unchanged by ERP); 1e-2 over 1 s needs about 3e-5 s"),
)


def known_limit(engine: str, case: str, duration: float,
                limits=KNOWN_LIMITS) -> KnownLimit | None:
    """The listed limit of ``engine`` on ``case`` over ``duration`` s, or None."""
    for k in limits:
        if k.engine == engine and k.case == case and math.isclose(k.duration, duration):
            return k
    return None


def verdict_of(row, limits=KNOWN_LIMITS) -> tuple[str, str]:
    """``(verdict, note)`` of one :class:`reports.studies.free_studies.FreeRow` at the
    recommended settings: :func:`label` of its fields."""
    return label(row.engine, row.case, row.duration, row.passed, row.ok, row.worst_error,
                 row.reason, limits)


def verdict_of_free(v, limits=KNOWN_LIMITS) -> tuple[str, str]:
    """``(verdict, note)`` of one :class:`reports.comparison.free_compare.FreeVerdict`
    (``xval simulate --engine``): the same :func:`label` as the report's rows, so that
    the command and the report give the same run the same word and exit status."""
    return label(v.engine, v.case, v.duration, v.passed, v.run_ok, v.worst.normalised,
                 v.reason or "", limits)


def label(engine: str, case: str, duration: float, passed: bool, ok: bool, worst: float,
          reason: str, limits=KNOWN_LIMITS) -> tuple[str, str]:
    """``pass``; ``known limit`` (failed, run complete, worst error within the listed
    limit's ``worst_max``; the note is its reason); else ``FAIL`` (the note says why a
    listed limit does not cover it)."""
    if passed:
        return "pass", ""
    k = known_limit(engine, case, duration, limits)
    if k is None:
        return "FAIL", ""
    if not ok:
        return "FAIL", f"listed known limit does not cover a run that stopped: {reason}"
    if not (worst <= k.worst_max):
        return "FAIL", (f"beyond its listed known limit: worst error {worst:.3g} "
                        f"> {k.worst_max:.3g} ({k.reason})")
    return "known limit", k.reason


__all__ = ["KNOWN_LIMITS", "KnownLimit", "known_limit", "label", "verdict_of",
           "verdict_of_free"]
