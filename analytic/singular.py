"""Rates and forces at singular samples: their limits along the followed branch.

At an input value where the loop Jacobian in the unknowns is singular (condition number
at or above :data:`analytic.tolerances.SINGULAR_CONDITION`) the loop equations do not fix
the rates, and the statics do not fix the reactions.  What the tool reports there:

* **Kinematics.**  Where the linkage passes through the position (a change point on the
  branch followed, :mod:`analytic.branches`), its motion is smooth and the rates are the
  limits along the branch.  They are extrapolated from four regular samples at
  ``(-2, -1, 1, 2) * h``, h from :data:`LIMIT_STEP` (rad, or sizes for a prismatic
  input): the symmetric means with Richardson's weights, error O(h^4) (~1e-12
  relative).  The one-sided extrapolations ``2 f(-h) - f(-2h)`` and ``2 f(h) - f(2h)`` must agree to
  :data:`LIMIT_CONTINUITY` of the rates' scale; where they do not (a dead centre the
  input cannot drive through, a kinked held branch, the end of a feasible range) the rates
  are not determined by the input: NaN, status :data:`UNDETERMINED`.
* **Forces.**  At a change point the links are collinear and a *self-stress* (a force
  along their common line) is in equilibrium with nothing: the reactions are determined
  only up to it.  Along the branch the reactions are ``c / s + f0 + O(s)`` (``s`` the
  distance from the change point): ``c`` is the load's work in the motion the
  singular position leaves free (gravity across the line, say) divided by the rate at
  which the Jacobian becomes singular.  The self-stress does no work on the input (the
  input drives through the position, so the driver's column lies in the Jacobian's
  range), so the **drive effort and power** have finite limits, which are written.  A
  joint force has a finite limit only where ``c = 0`` (no load in that motion); where
  ``c != 0`` it is **unbounded** (opposite signs either side, no limit): NaN, status
  :data:`UNBOUNDED_FORCES`, and the sweep's row, notes and events say so.  The same
  one-sided test decides (a divergent quantity's one-sided extrapolations differ by
  ``3 c / h``), from the wider steps :data:`FORCE_LIMIT_STEP` and the looser
  :data:`FORCE_LIMIT_CONTINUITY`: the reactions near a singular position amplify the
  positions' rounding by the condition number once more.  Each output takes its limit
  from the first of those steps at which it is continuous (a branch that bends on the
  scale of the wider step is not a divergence).

Status codes (``Kinematics.at_singular``, ``Forces.at_singular``, the sweep's ``singular``
column): :data:`REGULAR` 0, :data:`LIMIT` 1 (every value is the limit along the branch),
:data:`UNBOUNDED_FORCES` 2 (as 1, but some joint forces unbounded: NaN), :data:`UNDETERMINED`
3 (not passed through: rates and forces NaN).
"""

from __future__ import annotations

import numpy as np

from .errors import LinkageError
from .positions import size_of
from .tolerances import (
    FORCE_LIMIT_CONTINUITY,
    FORCE_LIMIT_STEP,
    LIMIT_CONTINUITY,
    LIMIT_STEP,
    SINGULAR_CONDITION,
)

REGULAR, LIMIT, UNBOUNDED_FORCES, UNDETERMINED = 0, 1, 2, 3

_OFFSETS = np.array([-2.0, -1.0, 1.0, 2.0])
_RATE_FIELDS = ("qd", "qdd", "omega", "alpha", "zv", "za")


def _extrapolate(f: np.ndarray):
    """``(limit, left, right)`` from values ``f (4, ...)`` at offsets ``_OFFSETS * h``."""
    m1, m2 = 0.5 * (f[1] + f[2]), 0.5 * (f[0] + f[3])
    return (4.0 * m1 - m2) / 3.0, 2.0 * f[1] - f[0], 2.0 * f[2] - f[3]


def _continuous(f: np.ndarray, scale: float, tol: float = LIMIT_CONTINUITY) -> bool:
    _, left, right = _extrapolate(f)
    jump = float(np.max(np.abs(left - right))) if f.size else 0.0
    return jump <= tol * scale


def _sides(linkage, value, velocity, acceleration, branch, steps=LIMIT_STEP):
    """Regular kinematics at the four side values of ``value`` (the first step of
    ``steps`` at which all four are regular and continuous), or ``None``."""
    unit = 1.0 if linkage.driver_is_revolute else size_of(linkage.topo)
    ng = linkage.topo.n_groups
    for h in steps:
        x = value + _OFFSETS * h * unit
        try:
            side = linkage.kinematics(x, velocity, acceleration, on_singular="flag",
                                      branch=branch, limits=False)
        except LinkageError:  # beyond a limit position: not passed through
            continue
        if not np.all(side.condition < SINGULAR_CONDITION):
            continue
        # slider rates in sizes, like the angles'; an acceleration's scale is at least
        # the square of the velocities' (a constant-speed parallelogram's are all 0)
        gd, gdd = side.qd.copy(), side.qdd.copy()
        gd[:, ng:] /= size_of(linkage.topo)
        gdd[:, ng:] /= size_of(linkage.topo)
        sd = float(np.max(np.abs(gd))) if gd.size else 0.0
        sdd = max(float(np.max(np.abs(gdd))) if gdd.size else 0.0, sd * sd)
        if np.all(np.isfinite(gd)) and np.all(np.isfinite(gdd)) and \
                _continuous(gd, sd) and _continuous(gdd, sdd):
            return side
    return None


def rate_limits(linkage, kin, idx: np.ndarray, branch: str) -> None:
    """Set the rates of ``kin`` at the singular samples ``idx`` to their limits along the
    branch (or NaN where the linkage does not pass through); records
    ``kin.at_singular`` and keeps the side kinematics for :func:`force_limits`."""
    status = np.zeros(kin.n, np.int8)
    for i in np.asarray(idx, int):
        side = _sides(linkage, float(kin.value[i]), kin.velocity[i], kin.acceleration[i],
                      branch)
        if side is None:
            status[i] = UNDETERMINED
            for f in _RATE_FIELDS:
                getattr(kin, f)[i] = np.nan
            continue
        status[i] = LIMIT
        for f in _RATE_FIELDS:
            getattr(kin, f)[i] = _extrapolate(getattr(side, f))[0]
    kin.at_singular = status
    kin.singular_branch = branch


def singular_samples(kin) -> np.ndarray:
    """Indices of the samples whose loop Jacobian is singular."""
    return np.flatnonzero(~(kin.condition < SINGULAR_CONDITION))


def _force_arrays(frc, keys=None) -> list[tuple[str, np.ndarray]]:
    """``(kind, array)`` for every force-like output of ``frc``: kind ``"f"`` a force,
    ``"m"`` a moment, ``"e"`` the drive effort, ``"p"`` a power.  ``keys`` (another
    :class:`Forces`) fixes the joints' order."""
    keys = frc if keys is None else keys
    return ([("f", frc.joint_force[k]) for k in keys.joint_force]
            + [("f", frc.normal[k]) for k in keys.normal]
            + [("m", frc.moment[k]) for k in keys.moment]
            + [("e", frc.effort)]
            + [("p", a) for a in (frc.power, frc.kinetic_rate, frc.load_power)])


def _limits_from(linkage, kin, frc, i: int, side, pending: list[int]) -> list[int]:
    """Write the limits at sample ``i`` of the outputs ``pending`` (indices into
    :func:`_force_arrays`) that are continuous across ``side`` (regular kinematics at the
    four side values of one step); returns those that are not."""
    size = size_of(linkage.topo)
    arrays = _force_arrays(frc)
    side_arrays = [a for _, a in _force_arrays(linkage.forces(side), keys=frc)]
    fs = max([float(np.max(np.abs(a))) for (k, _), a in zip(arrays, side_arrays,
                                                             strict=True)
              if k == "f"] + [0.0])
    ps = max(float(np.max(np.abs(a))) for a in side_arrays[-3:])
    es = max(float(np.max(np.abs(side_arrays[-4]))),
             fs * (size if linkage.driver_is_revolute else 1.0))
    # a power's scale is at least the effort's times the input's speed (the
    # inertia terms of a constant-speed parallelogram cancel to rounding)
    ps = max(ps, es * abs(float(kin.velocity[i])))
    scale = {"f": fs, "m": max(fs * size, es), "e": es, "p": ps}
    left = []
    for n in pending:
        kind, a = arrays[n]
        if _continuous(side_arrays[n], scale[kind], FORCE_LIMIT_CONTINUITY):
            a[i] = _extrapolate(side_arrays[n])[0]
        else:
            left.append(n)
    return left


def force_limits(linkage, kin, frc, idx: np.ndarray) -> None:
    """Set the forces of ``frc`` at the singular samples ``idx`` (see the module
    docstring): limits where bounded, NaN where unbounded or undetermined; records
    ``frc.at_singular``.

    Each output is tried at the steps of :data:`FORCE_LIMIT_STEP` in order and takes
    its limit from the first at which it is continuous.  One step alone cannot tell a
    divergence from a branch that curves sharply on the scale of the step: a bounded
    output's one-sided extrapolations differ by ``12 h^3`` times its third derivative,
    which falls a thousandfold from one step to the next, an unbounded one's by
    ``3 c / h``, as large a fraction of its scale at every step."""
    status = np.array(kin.at_singular if getattr(kin, "at_singular", None) is not None
                      else np.zeros(kin.n, np.int8), np.int8)
    arrays = _force_arrays(frc)
    branch = getattr(kin, "singular_branch", "continued")
    for i in np.asarray(idx, int):
        pending, passed = list(range(len(arrays))), False
        for h in (FORCE_LIMIT_STEP if status[i] != UNDETERMINED else ()):
            side = _sides(linkage, float(kin.value[i]), kin.velocity[i],
                          kin.acceleration[i], branch, (h,))
            if side is not None:
                passed = True
                pending = _limits_from(linkage, kin, frc, i, side, pending)
            if not pending:
                break
        if not passed:
            status[i] = UNDETERMINED
            pending = list(range(len(arrays)))
        for n in pending:
            arrays[n][1][i] = np.nan
        if not passed:
            frc.power_residual[i] = np.nan
            continue
        # the power is the effort times the input's speed, whichever step each came from
        frc.power[i] = frc.effort[i] * kin.velocity[i]
        frc.power_residual[i] = frc.power[i] - (frc.kinetic_rate[i] - frc.load_power[i])
        status[i] = UNBOUNDED_FORCES if pending else LIMIT
    frc.at_singular = status
