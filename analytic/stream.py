"""Blocked evaluation and the streamed sweep: flat cost and memory at any size.

:func:`evaluate_blocked` runs the solver over the input values in blocks of
:data:`BLOCK` configurations into preallocated outputs (the fused kernel where the
mechanism has one, else the numpy path block by block): the outputs of one block are
reused by the next, so memory does not grow with the point count.

:func:`sweep_csv` is :func:`analytic.sweep.sweep` for tables too large to hold: the
input values are made block by block (:class:`analytic.sweep.InputGrid`), each
block's table (:func:`analytic.sweep.to_frame`, the same columns and numbers) is
written to the CSV (pyarrow's writer) or Parquet file as it is solved, and the same
block feeds :class:`analytic.sweep_facts.StreamFacts`, which gathers what the events
and the summary read (sign changes with the carry-over between blocks, extremes and
their neighbours, maxima) and holds nothing per point.  The events and the summary are
then computed by the sweep's own functions from those facts.

Memory of :func:`sweep_csv`: one block (:data:`BLOCK` configurations of the full
tables and their text, a few tens of MB) and the events, whatever the point count.
Where the first blocks of a series are so small that a sample counted significant
falls below 1e-9 of the series' final peak (:attr:`analytic.sweep_facts.SignTracker.exact`),
one more pass of the kinematics (no table, no forces) finds the sign changes again.
"""

from __future__ import annotations

import math
import sys

import numpy as np

from .errors import OutputError
from .fused import kernel_for

#: configurations per block: the fused kernel's outputs for a block of a four-bar
#: (~600 B each) stay within a few MB; the CSV of a block is written in one go
BLOCK = 1 << 15
#: ``xval sweep --csv`` streams above this many points (below, the table is built in
#: memory and written by pandas)
STREAM_POINTS = 200_000


class StreamedKinematics:
    """A streamed sweep's :attr:`analytic.sweep.SweepResult.kinematics`: the point
    count and the facts gathered block by block
    (:class:`analytic.sweep_facts.StreamFacts`); its arrays were written to the file,
    not held."""

    def __init__(self, linkage, n: int, facts):
        self.linkage, self.n, self.facts = linkage, n, facts

    def __getattr__(self, name):
        raise AttributeError(f"a streamed sweep holds no per-point {name!r}: its table is "
                             "in the file written")


class StreamedForces:
    """A streamed sweep's forces: the power balance over every point (the peaks
    :meth:`analytic.kinetostatics.Forces.power_balance_error` reads, gathered block
    by block)."""

    def __init__(self):
        self.peaks = np.zeros(4)  # |power|, |kinetic rate|, |load power|, |residual|

    def feed(self, frc) -> None:
        for k, a in enumerate((frc.power, frc.kinetic_rate, frc.load_power,
                               frc.power_residual)):
            if len(a):
                self.peaks[k] = np.maximum(self.peaks[k], np.max(np.abs(a)))

    def power_balance_error(self) -> float:
        p, k, ld, r = self.peaks
        return float(r / max(p, k, ld, 1e-300))


def _blocks(N: int, block: int):
    for a in range(0, N, block):
        yield a, min(N, a + block)


def evaluate_blocked(linkage, values, velocity=None, acceleration=None, forces=None,
                     block: int = BLOCK, branch: str = "continued", on_singular="flag"):
    """Yield ``(start, Kinematics, Forces or None)`` for consecutive blocks of
    ``values`` (an array, or an :class:`analytic.sweep.InputGrid`): the same numbers
    as one call over all values (the angles are unwrapped
    across blocks).  The fused kernel writes each block into the same preallocated
    outputs, so the yielded arrays are overwritten by the next block: copy what you
    keep."""
    if hasattr(values, "block"):  # an InputGrid: the values made block by block
        grid, N = values, values.n
    else:
        values = np.asarray(values, float)
        grid, N = None, len(values)

    def part(a, b):
        return grid.block(a, b) if grid is not None else values[a:b]
    if forces is None:
        forces = linkage.mech.has_mass
    fk = kernel_for(linkage)
    if fk is None:  # numpy path, block by block
        for a, b in _blocks(N, block):
            kin = linkage.kinematics(part(a, b), velocity, acceleration,
                                     on_singular=on_singular)
            yield a, kin, (linkage.forces(kin) if forces else None)
        return
    level = 3 if forces else 2
    out = fk.alloc(min(block, N), level, full=True)
    carry = np.zeros(1 + 2 * linkage.topo.n_groups)
    for a, b in _blocks(N, block):
        x = part(a, b)
        kin, frc = fk.solve_block(x, velocity, acceleration, out, carry, level,
                                  branch, on_singular)
        if kin.fused.singular:  # a singular sample: the numpy path treats the block
            kin = linkage.kinematics(x, velocity, acceleration,
                                     on_singular=on_singular)
            frc = linkage.forces(kin) if forces else None
        yield a, kin, frc


class _Writer:
    """A table written block by block: CSV through pyarrow's writer (C++; numbers in
    the shortest form that reads back exactly; the header as the columns are named) to
    a path, ``"-"`` (standard output) or an open text file; or Parquet (``parquet=True``,
    a path: one row group per block)."""

    def __init__(self, path, parquet: bool = False):
        self.path, self.parquet = path, parquet
        self._pq = None
        self._ctx = None

    def __enter__(self):
        if self.parquet:
            return self
        if self.path == "-":
            self.fh, self.binary = sys.stdout, False
        elif hasattr(self.path, "write"):
            self.fh, self.binary = self.path, False
        else:
            self._ctx = self.fh = open(self.path, "wb")
            self.binary = True
        return self

    def write(self, frame, first: bool) -> None:
        import pyarrow as pa
        table = pa.Table.from_pandas(frame, preserve_index=False)
        if self.parquet:
            import pyarrow.parquet as pq
            if self._pq is None:
                # no dictionary: the columns are floats, nearly all distinct (8x faster)
                self._pq = pq.ParquetWriter(self.path, table.schema, use_dictionary=False)
            self._pq.write_table(table)
            return
        import pyarrow.csv as pacsv
        buf = pa.BufferOutputStream()
        if first:
            buf.write((",".join(frame.columns) + "\n").encode())
        pacsv.write_csv(table, buf, pacsv.WriteOptions(include_header=False,
                                                       quoting_style="none"))
        data = buf.getvalue()
        if self.binary:
            self.fh.write(data)
        else:
            self.fh.write(data.to_pybytes().decode())

    def __exit__(self, *exc):
        if self._pq is not None:
            self._pq.close()
        if self._ctx is not None:
            self._ctx.close()
        return False


def sweep_csv(linkage, points: int, path, *, start=None, velocity=None, input_range=None,
              forces: bool | None = None, block: int = BLOCK, convert=lambda frame: frame,
              parquet: bool = False):
    """:func:`analytic.sweep.sweep` written to the CSV ``path`` (or ``"-"``: standard
    output, or an open text file; ``parquet``: a Parquet file) block by block.

    ``convert`` maps each block's table before it is written (display units and the
    round-off snapping of :func:`reports.figures.display_units.convert_frame`, which reads each
    row alone: the block size changes no cell).

    Returns a :class:`analytic.sweep.SweepResult` whose ``frame`` is ``None`` (the table
    is in the file), whose kinematics and forces are :class:`StreamedKinematics` and
    :class:`StreamedForces`, with the events and summary of the in-memory sweep (see
    the module docstring for the memory).
    """
    from .summary import _power_terms, summarise
    from .sweep import (
        SweepResult,
        find_events,
        grashof,
        nearest_event,
        singular_notes,
        unbounded_events,
    )
    from .sweep_facts import StreamFacts
    if points < 2:
        raise ValueError(f"a sweep needs at least 2 points, got {points}")
    grid, full, feas, auto = _stream_grid(linkage, points, start, input_range)
    if forces is None:
        forces = linkage.mech.has_mass
    d = linkage.mech.driver
    vel = d.velocity if velocity is None else velocity
    ends = [e for r in feas for e in r] if not full else []
    facts = StreamFacts(linkage, grid, vel, d.acceleration, forces, ends, _power_terms)
    balance = StreamedForces() if forces else None
    records = _write_blocks(linkage, grid, vel, forces, block, path, parquet, convert,
                            facts, balance)
    facts.finish()
    again = facts.refeed_keys()
    if again:  # a series' first blocks were below its final round-off level
        facts.start_refeed(again)
        for _, kin, _ in evaluate_blocked(linkage, grid, vel, None, False, block):
            facts.refeed(kin)
        facts.finish_refeed()
    lo, hi = facts.bounds
    notes = singular_notes(linkage, records, forces)
    crossings = linkage.branch_crossings(lo, hi)
    notes += _range_notes(linkage, auto and not full, feas, crossings)
    kin = StreamedKinematics(linkage, facts.n, facts)
    events = unbounded_events(linkage, records, find_events(
        linkage, kin, full, None if full else feas, crossings, facts))
    res = SweepResult(kin, balance, None, events, full, feas, grashof(linkage), notes,
                      crossings)
    res.summary = summarise(res, nearest_event)
    res.written = True
    return res


def _stream_grid(linkage, points: int, start, input_range):
    """``(grid, full cycle, feasible ranges, range chosen by the sweep)``: the input
    values as :func:`analytic.sweep.sweep` chooses them, made block by block."""
    from .sweep import input_grid, range_grid
    if input_range is not None:
        return (range_grid(linkage, input_range, points), False, linkage.feasible_ranges(),
                False)
    grid, full, feas = input_grid(linkage, points, start)
    return grid, full, feas, True


def _write_blocks(linkage, grid, vel, forces: bool, block: int, path, parquet: bool,
                  convert, facts, balance) -> list:
    """Solve and write the table block by block, feeding each block to ``facts`` and
    ``balance``; returns the singular samples
    (:func:`analytic.sweep.singular_records`)."""
    from .sweep import singular_records, to_frame
    records = []
    try:
        with _Writer(path, parquet) as out:
            for a, kin, frc in evaluate_blocked(linkage, grid, vel, None, forces, block):
                out.write(convert(to_frame(linkage, kin, frc)), a == 0)
                facts.feed(kin, frc)
                records += singular_records(kin, frc)
                if frc is not None:
                    balance.feed(frc)
    except BrokenPipeError:  # the reader stopped (| head): xval ends quietly, not an error
        raise
    except OSError as e:  # a full disk or a vanished folder, mid-way
        raise OutputError(f"cannot write {path!r}: {e.strerror or e}") from None
    return records


def _range_notes(linkage, partial: bool, feas: list, crossings: list) -> list[str]:
    """Notes on the range swept (``partial``: the input cannot turn fully, the sweep
    covers the feasible range) and on change points whose branch was held."""
    notes = []
    if partial and linkage.driver_is_revolute:
        notes.append("the input link cannot turn fully; the sweep covers the feasible range "
                     + ", ".join(f"[{math.degrees(a):.4f}, {math.degrees(b):.4f}] deg"
                                 for a, b in feas) + " on the assembled branch")
    undecided = [c for c in crossings if c.rule.startswith("held: ")]
    if undecided:
        notes.append(f"{len(undecided)} change point(s) where continuity of velocity cannot "
                     "decide the branch: dyad signs held (Linkage(branch_rule='switch') or "
                     "xval sweep --branch-rule switch takes the other)")
    return notes
