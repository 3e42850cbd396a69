"""Blocked evaluation and the streamed sweep: flat cost and memory at any size.

:func:`evaluate_blocked` runs the solver over the input values in blocks of
:data:`BLOCK` configurations into preallocated outputs (the fused kernel where the
mechanism has one, else the numpy path block by block): the outputs of one block are
reused by the next, so memory does not grow with the point count.

:func:`sweep_csv` is :func:`analytic.sweep.sweep` for tables too large to hold: each
block's table (:func:`analytic.sweep.to_frame`, the same columns and numbers) is
appended to the CSV as it is solved.  The events and the summary are then computed by
the sweep's own functions (:func:`analytic.sweep.find_events`,
:func:`analytic.summary.summarise`) from :class:`LazyKinematics`: every series they
read is recomputed by one more pass of the solver and only that series is held.

Memory ceiling of :func:`sweep_csv`: the input values (8 B per configuration), the
determinant and condition number of the Jacobian and the transmission angles that the
events read more than once (8 B each per configuration), one or two series of 8-16 B
per configuration at a time while the events and summary run, and one block
(:data:`BLOCK` configurations of the full tables, a few tens of MB) whatever the
point count: under 100 B per configuration for a four-bar.
"""

from __future__ import annotations

import math
import sys
from contextlib import nullcontext

import numpy as np

from .errors import OutputError
from .fused import kernel_for

#: configurations per block: the fused kernel's outputs for a block of a four-bar
#: (~600 B each) stay within a few MB; the CSV of a block is written in one go
BLOCK = 1 << 15
#: ``xval sweep --csv`` streams above this many points (below, the table is built in
#: memory and written by pandas)
STREAM_POINTS = 200_000


class _Lazy:
    """A streamed sweep's results for every point, computed on demand: each series
    asked for is recomputed by one more pass of the solver over the input values
    (block by block) and only that series is kept.  The events and the summary read
    a handful of series, so memory stays a few arrays of the point count whatever
    they read, and they read the same numbers the CSV holds."""

    def __init__(self, linkage, values, velocity, acceleration, forces: bool, block: int):
        self.linkage, self.value = linkage, values
        self._rates = (velocity, acceleration)
        self._forces, self._block = forces, block
        self._cache: dict[str, np.ndarray] = {}

    @property
    def n(self) -> int:
        return len(self.value)

    def _collect(self, pick, forces: bool = False) -> np.ndarray:
        """One pass: ``pick(kin, frc)`` of every block, into one array."""
        res = None
        for a, kin, frc in evaluate_blocked(self.linkage, self.value, *self._rates,
                                            forces=forces, block=self._block):
            part = np.asarray(pick(kin, frc))
            if res is None:
                res = np.empty((self.n,) + part.shape[1:], part.dtype)
            res[a:a + len(part)] = part
        return res if res is not None else np.zeros(0)

    def series(self, pick) -> np.ndarray:
        """``pick(kinematics)`` of every block, into one array (as
        :meth:`analytic.kinematics.Kinematics.series`): a per-sample quantity built from
        several arrays holds only its result, not the arrays."""
        return self._collect(lambda k, f: pick(k), False)

    def _cached(self, key, pick, forces=False):
        if key not in self._cache:
            self._cache[key] = self._collect(pick, forces)
        return self._cache[key]


class _LazyArray:
    """A per-configuration array of a :class:`_Lazy`: ``[:, k]`` computes one column."""

    def __init__(self, owner: _Lazy, name: str, forces: bool):
        self.owner, self.name, self.forces = owner, name, forces

    def _get(self, kin, frc):
        return getattr(frc if self.forces else kin, self.name)

    def __getitem__(self, key):
        if isinstance(key, tuple) and len(key) == 2:
            rows, col = key
            return self.owner._collect(lambda k, f: self._get(k, f)[:, col], self.forces)[rows]
        return np.asarray(self)[key]

    def __array__(self, dtype=None, copy=None):
        a = self.owner._collect(self._get, self.forces)
        return a if dtype is None else a.astype(dtype)

    def __len__(self):
        return self.owner.n


class LazyKinematics(_Lazy):
    """:class:`analytic.kinematics.Kinematics` of a streamed sweep (see :class:`_Lazy`)."""

    _ARRAYS = ("q", "qd", "qdd", "theta", "omega", "alpha", "E", "zO", "zv", "za",
               "jacobian")

    def __getattr__(self, name):
        if name in LazyKinematics._ARRAYS:
            return _LazyArray(self, name, False)
        raise AttributeError(f"a streamed sweep's kinematics have no {name!r}")

    @property
    def velocity(self):
        return np.broadcast_to(np.asarray(self._rates[0], float), (self.n,))

    @property
    def acceleration(self):
        return np.broadcast_to(np.asarray(self._rates[1], float), (self.n,))

    @property
    def determinant(self):
        return self._collect(lambda k, f: k.determinant)

    @property
    def condition(self):
        return self._cached("condition", lambda k, f: k.condition)

    @property
    def transmission(self):
        first = next(evaluate_blocked(self.linkage, self.value[:2], *self._rates, forces=False))
        names = list(first[1].transmission)
        return {n: self._cached("tr " + n, lambda k, f, n=n: k.transmission[n]) for n in names}

    def point_c(self, body, point):
        """As :meth:`Kinematics.point_c`, in one pass (position, velocity and
        acceleration of the point, complex ``(N,)`` each)."""
        out = [np.empty(self.n, complex) for _ in range(3)]
        for a, kin, _ in evaluate_blocked(self.linkage, self.value, *self._rates,
                                          forces=False, block=self._block):
            for o, z in zip(out, kin.point_c(body, point), strict=True):
                o[a:a + kin.n] = z
        return tuple(out)

    def point(self, body, point):
        from .positions import as_xy
        return tuple(as_xy(z) for z in self.point_c(body, point))

    def com_c(self, b):
        return self.point_c(b, self.linkage.mech.bodies[b].com)

    def com(self, b):
        from .kinematics import Kinematics
        return Kinematics.com(self, b)

    def slider(self, joint):
        from .kinematics import Kinematics
        return Kinematics.slider(self, joint)


class LazyForces:
    """:class:`analytic.kinetostatics.Forces` of a streamed sweep (see :class:`_Lazy`)."""

    _ARRAYS = ("effort", "power", "kinetic_rate", "load_power", "power_residual")

    def __init__(self, owner: _Lazy):
        self._owner = owner

    def __getattr__(self, name):
        if name in LazyForces._ARRAYS:
            return self._owner._collect(lambda k, f: getattr(f, name), True)
        raise AttributeError(f"a streamed sweep's forces have no {name!r}")

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
        if kin._fused_singular:  # a singular sample: the numpy path treats the block
            kin = linkage.kinematics(values[a:b], velocity, acceleration,
                                     on_singular=on_singular)
            frc = linkage.forces(kin) if forces else None
        yield a, kin, frc


def _csv_writer():
    """``write(frame, fh, header)``: pyarrow's CSV writer where installed (C++, about
    15x pandas' ``to_csv``; numbers in the shortest form that reads back exactly),
    else pandas'."""
    try:
        import pyarrow as pa
        import pyarrow.csv as pacsv
    except ImportError:  # pragma: no cover - pyarrow is a dependency
        def write(frame, fh, header):
            frame.to_csv(fh, index=False, header=header)
        return write

    def write(frame, fh, header):
        table = pa.Table.from_pandas(frame, preserve_index=False)
        if header:
            fh.write(",".join(frame.columns) + "\n")
        buf = pa.BufferOutputStream()
        pacsv.write_csv(table, buf, pacsv.WriteOptions(include_header=False,
                                                       quoting_style="none"))
        fh.write(buf.getvalue().to_pybytes().decode())
    return write


def _sweep_values(linkage, points, start, input_range):
    """The sweep's input values as :func:`analytic.sweep.sweep` chooses them."""
    from .sweep import input_values, range_values
    if input_range is not None:
        return range_values(linkage, input_range, points), False, linkage.feasible_ranges(), \
            False
    values, full, feas = input_values(linkage, points, start)
    return values, full, feas, True


def sweep_csv(linkage, points: int, path, *, start=None, velocity=None, input_range=None,
              forces: bool | None = None, block: int = BLOCK, convert=lambda frame: frame):
    """:func:`analytic.sweep.sweep` written to the CSV ``path`` (or ``"-"``: standard
    output, or an open text file) block by block.

    ``convert`` maps each block's table before it is written (display units and the
    round-off snapping of :func:`reports.display_units.convert_frame`, which reads each
    row alone: the block size changes no cell).

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
    if path == "-":
        ctx = nullcontext(sys.stdout)
    elif hasattr(path, "write"):
        ctx = nullcontext(path)
    else:
        ctx = open(path, "w", newline="")
    write = _csv_writer()
    try:
        with ctx as fh:
            for a, kin, frc in evaluate_blocked(linkage, values, vel, None, forces, block):
                write(convert(to_frame(linkage, kin, frc)), fh, a == 0)
    except BrokenPipeError:  # the reader stopped (| head): xval ends quietly, not an error
        raise
    except OSError as e:  # a full disk or a vanished folder, mid-way
        raise OutputError(f"cannot write {path!r}: {e.strerror or e}") from None
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
    kin = LazyKinematics(linkage, values, vel, d.acceleration, forces, block)
    frc = LazyForces(kin) if forces else None
    events = find_events(linkage, kin, full, None if full else feas, crossings)
    res = SweepResult(kin, frc, None, events, full, feas, grashof(linkage), notes, crossings)
    from .sweep import nearest_event
    res.summary = summarise(res, nearest_event)
    res.written = True
    return res
