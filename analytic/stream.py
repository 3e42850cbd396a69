"""Blocked evaluation and the streamed sweep: flat cost and memory at any size.

:func:`evaluate_blocked` runs the solver over the input values in blocks of
:data:`BLOCK` configurations into preallocated outputs (the fused kernel where the
mechanism has one, else the numpy path block by block), so the working set per
block stays in cache and the temporaries do not grow with the sweep.

:func:`sweep_csv` is :func:`analytic.sweep.sweep` for tables too large to hold: each
block's table (:func:`analytic.sweep.to_frame`, the same columns and numbers) is
appended to the CSV as it is solved, and only the series that the events and the
summary read are kept for every point.

Memory ceiling of :func:`sweep_csv` per configuration: ``8 (2 nq + 3 + D + F)``
bytes, with ``nq`` the loop unknowns (their values and rates give every angle,
angular velocity and slider travel the events and summary read), the input value,
the Jacobian's determinant and condition number, ``D`` the dyads' transmission angles
and ``F`` = 5 with forces (drive effort, power terms): 112 B for a four-bar with
forces.  On top of that one block (:data:`BLOCK` configurations of the full tables,
about 20 MB for a four-bar) whatever the point count.
"""

from __future__ import annotations

import math
import sys
from contextlib import nullcontext

import numpy as np

from .fused import kernel_for

#: configurations per block: the fused kernel's outputs for a block of a four-bar
#: (~600 B each) stay within a few MB; the CSV of a block is written in one go
BLOCK = 1 << 15


class _Columns:
    """Per-body series from the group variables: ``[:, b]`` of theta or omega is the
    body's group column (plus its offset for angles); the ground's is zero."""

    def __init__(self, x: np.ndarray, topo, offset: bool):
        self.x, self.topo, self.offset = x, topo, offset

    def __getitem__(self, key):
        rows, b = key
        g = self.topo.group_of[b]
        if g < 0:
            return np.zeros(len(self.x))[rows]
        col = self.x[rows, g]
        return col + self.topo.offset[b] if self.offset else col


class _Series:
    """What :func:`analytic.sweep.find_events` and :func:`analytic.summary.summarise`
    read of a sweep's kinematics, for every point; nothing else."""

    def __init__(self, linkage, N: int, velocity, acceleration, forces: bool):
        topo = linkage.topo
        self.linkage = linkage
        self.value = np.empty(N)
        self.q = np.empty((N, topo.nq))
        self.qd = np.empty((N, topo.nq))
        self.determinant = np.empty(N)
        self.condition = np.empty(N)
        self.velocity = np.broadcast_to(np.asarray(velocity, float), (N,))
        self.acceleration = np.broadcast_to(np.asarray(acceleration, float), (N,))
        self.theta = _Columns(self.q, topo, True)
        self.omega = _Columns(self.qd, topo, False)
        self.transmission: dict[str, np.ndarray] = {}
        self.forces = _ForceSeries(N) if forces else None

    @property
    def n(self) -> int:
        return len(self.value)

    def slider(self, joint: str):
        topo = self.linkage.topo
        i = topo.n_groups + topo.slider_index[topo.joint_names.index(joint)]
        return self.q[:, i], self.qd[:, i], None

    def store(self, a: int, kin, frc) -> None:
        b = a + kin.n
        self.value[a:b] = kin.value
        self.q[a:b], self.qd[a:b] = kin.q, kin.qd
        self.determinant[a:b] = kin.determinant
        self.condition[a:b] = kin.condition
        for name, tr in kin.transmission.items():
            self.transmission.setdefault(name, np.empty(self.n))[a:b] = tr
        if self.forces is not None:
            self.forces.store(a, frc)


class _ForceSeries:
    """The drive effort and the power terms of every point (``Forces``' methods)."""

    def __init__(self, N: int):
        self.effort, self.power = np.empty(N), np.empty(N)
        self.kinetic_rate, self.load_power = np.empty(N), np.empty(N)
        self.power_residual = np.empty(N)

    def store(self, a: int, frc) -> None:
        b = a + len(frc.effort)
        for k in ("effort", "power", "kinetic_rate", "load_power", "power_residual"):
            getattr(self, k)[a:b] = getattr(frc, k)

    def power_balance_error(self) -> float:
        from .kinetostatics import Forces
        return Forces.power_balance_error(self)


def _blocks(N: int, block: int):
    for a in range(0, N, block):
        yield a, min(N, a + block)


def evaluate_blocked(linkage, values, velocity=None, acceleration=None, forces=None,
                     block: int = BLOCK, branch: str = "continued", on_singular="flag"):
    """Yield ``(start, Kinematics, Forces or None)`` for consecutive blocks of
    ``values``: the same numbers as one call over all values (the angles are unwrapped
    across blocks).  The fused kernel writes each block into the same preallocated
    outputs, so the yielded arrays are overwritten by the next block: copy what you
    keep."""
    values = np.asarray(values, float)
    if forces is None:
        forces = linkage.mech.has_mass
    fk = kernel_for(linkage)
    if fk is None:  # numpy path, block by block
        for a, b in _blocks(len(values), block):
            kin = linkage.kinematics(values[a:b], velocity, acceleration,
                                     on_singular=on_singular)
            yield a, kin, (linkage.forces(kin) if forces else None)
        return
    level = 3 if forces else 2
    out = fk.alloc(min(block, len(values)), level, full=True)
    carry = np.zeros(1 + 2 * linkage.topo.n_groups)
    for a, b in _blocks(len(values), block):
        kin, frc = fk.solve_block(values[a:b], velocity, acceleration, out, carry, level,
                                  branch, on_singular)
        yield a, kin, frc


def _sweep_values(linkage, points, start, input_range):
    """The sweep's input values as :func:`analytic.sweep.sweep` chooses them."""
    from .sweep import input_values
    if input_range is not None:
        return np.linspace(*input_range, points), False, linkage.feasible_ranges(), False
    values, full, feas = input_values(linkage, points, start)
    return values, full, feas, True


def sweep_csv(linkage, points: int, path, *, start=None, velocity=None, input_range=None,
              forces: bool | None = None, block: int = BLOCK):
    """:func:`analytic.sweep.sweep` written to the CSV ``path`` (or ``"-"``: standard
    output, or an open text file) block by block.

    Returns a :class:`analytic.sweep.SweepResult` whose ``frame`` is ``None`` (the table
    is in the file) and whose kinematics and forces hold only the series the events
    and the summary are computed from (see the module docstring for the memory).
    """
    from .summary import summarise
    from .sweep import SweepResult, find_events, grashof, to_frame
    if points < 2:
        raise ValueError(f"a sweep needs at least 2 points, got {points}")
    values, full, feas, auto = _sweep_values(linkage, points, start, input_range)
    if forces is None:
        forces = linkage.mech.has_mass
    d = linkage.mech.driver
    vel = d.velocity if velocity is None else velocity
    series = _Series(linkage, len(values), vel, d.acceleration, forces)
    if path == "-":
        ctx = nullcontext(sys.stdout)
    elif hasattr(path, "write"):
        ctx = nullcontext(path)
    else:
        ctx = open(path, "w", newline="")
    with ctx as fh:
        for a, kin, frc in evaluate_blocked(linkage, values, vel, None, forces, block):
            to_frame(linkage, kin, frc).to_csv(fh, index=False, header=(a == 0))
            series.store(a, kin, frc)
    notes = []
    if auto and not full and linkage.driver_is_revolute:
        notes.append("the input link cannot turn fully; the sweep covers the feasible range "
                     + ", ".join(f"[{math.degrees(a):.4f}, {math.degrees(b):.4f}] deg"
                                 for a, b in feas) + " on the assembled branch")
    crossings = linkage.branch_crossings(float(np.min(values)), float(np.max(values)))
    undecided = [c for c in crossings if c.rule.startswith("held: ")]
    if undecided:
        notes.append(f"{len(undecided)} change point(s) where continuity of velocity cannot "
                     "decide the branch: dyad signs held (Linkage(branch_rule='switch') or "
                     "xval sweep --branch-rule switch takes the other)")
    events = find_events(linkage, series, full, None if full else feas, crossings)
    res = SweepResult(series, series.forces, None, events, full, feas, grashof(linkage),
                      notes, crossings)
    from .sweep import nearest_event
    res.summary = summarise(res, nearest_event)
    res.written = True
    return res
