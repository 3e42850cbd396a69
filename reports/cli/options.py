"""Command-line option types of ``xval``: every number and path is checked where it enters.

Each type either returns the parsed value or raises
:class:`argparse.ArgumentTypeError` with the accepted range and why; the parser
(:class:`OneLineParser`) turns that into one line on standard error and exit
status 2.  The physical ranges are the ones a description file must satisfy
(:mod:`analytic.mechanism`), so an input value is accepted on the command line
exactly when it would be accepted in a file.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import re
import tempfile
from pathlib import Path

from analytic.errors import LinkageError
from analytic.mechanism import MAX_ACCEL, MAX_ANGLE, MAX_LENGTH, MAX_RATE, RANGE_ROUND_OFF


class UsageError(LinkageError):
    """A command-line option or argument is malformed or out of range."""


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (no usage block) and a
    :class:`UsageError`, so that ``main`` reports them like every other user error."""

    def error(self, message: str):  # noqa: D401 - argparse's hook
        raise UsageError(f"{message} (see '{self.prog} --help')")


def choices_text(choices) -> str:
    """The choices of an option whose metavar names them (``--engine ENGINE``), for its
    help: the usage line stays short and every choice is listed once."""
    *head, last = list(choices)
    return f"{', '.join(head)} or {last}" if head else str(last)


# --- sizes ---------------------------------------------------------------------

#: Most points a sweep may have.  A sweep holds about 190-200 bytes per point for
#: each body and joint (measured peak with forces, every built-in case: 1.2 kB a
#: point for the four-bars, 2.6 kB for the six-bar), so 1e6 points of a six-bar take
#: 2.6 GB; a finer sweep resolves nothing more, since events are located between
#: samples anyway.
MAX_SWEEP_POINTS = 1_000_000
#: Bytes a sweep holds per point for each body and joint (the measured ~200 B with
#: a 25% margin), and the memory a sweep may take: together they lower
#: MAX_SWEEP_POINTS for descriptions with many bodies.
SWEEP_BYTES_PER_ELEMENT = 250
SWEEP_MEMORY_BUDGET = 4 * 2 ** 30
#: Most points of a sweep written to CSV in blocks (``--csv`` and more than
#: analytic.stream.STREAM_POINTS): its memory does not grow with the points
#: (analytic/stream.py), so only time bounds it.
MAX_STREAMED_SWEEP_POINTS = 1_000_000_000

#: Engine run ranges (samples, revolutions, time step) are defined once, in
#: :mod:`sim_models.engines.ranges`, and checked by the settings and the run request themselves;
#: read lazily (module ``__getattr__``) so that ``xval solve`` imports no engine code.
_SIM_RANGES = ("MAX_SAMPLES", "MAX_REVOLUTIONS", "MIN_TIMESTEP", "MAX_TIMESTEP")


def __getattr__(name: str):
    if name in _SIM_RANGES:
        from sim_models.engines import ranges
        return getattr(ranges, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


#: Report worker processes: each holds both engines (a few hundred MB).
MAX_WORKERS = 64


def int_range(lo: int, hi: int, why: str = ""):
    """An argparse type: an integer in ``[lo, hi]``."""
    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
        if not lo <= v <= hi:
            raise argparse.ArgumentTypeError(
                f"{v} is out of range: the accepted range is {lo} to {hi}"
                + (f" ({why})" if why else ""))
        return v
    return parse


def _shown(v: float) -> str:
    """``v`` short (``1e+09``) unless that hides digits the user typed (``360000.001``)."""
    return f"{v:g}" if float(f"{v:g}") == v else f"{v:.12g}"


def finite_number(text: str) -> float:
    """An argparse type: any finite float (its range checked where it is used)."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"{text} is not a finite number")
    return v


def finite_float(limit: float, unit: str, lo: float | None = None, why: str = "",
                 scale: float = 1.0):
    """An argparse type: a finite float with ``|x| <= limit`` (or ``lo <= x <= limit``).

    ``limit``/``lo`` are SI; ``scale`` converts the typed value to SI (degrees)."""
    def parse(text: str) -> float:
        v = finite_number(text)
        si = v * scale
        top = limit * (1 + RANGE_ROUND_OFF)  # the printed bound itself is accepted
        if (abs(si) <= top) if lo is None else (lo <= si <= top):
            return v
        rng = (f"|x| <= {limit / scale:g} {unit}" if lo is None
               else f"{lo / scale:g} to {limit / scale:g} {unit}")
        raise argparse.ArgumentTypeError(f"{_shown(v)} is out of range: the accepted range is {rng}"
                                         + (f" ({why})" if why else ""))
    return parse


# the solver's input values: the ranges of a description file (analytic.mechanism)
angle_deg = finite_float(MAX_ANGLE, "deg", scale=math.pi / 180, why="1000 turns")
length_m = finite_float(MAX_LENGTH, "m")
rate = finite_float(MAX_RATE, "rad/s or m/s")
accel = finite_float(MAX_ACCEL, "rad/s^2 or m/s^2")
sweep_points = int_range(2, MAX_STREAMED_SWEEP_POINTS, f"more than {MAX_SWEEP_POINTS} only "
                         "with --csv, written block by block")


#: MuJoCo's integrators (``--integrator`` of ``xval compare`` and ``xval simulate``: the same
#: as ``--set mujoco.integrator=...``; any letter case, as every word setting).
MUJOCO_INTEGRATORS = ("RK4", "implicitfast", "implicit", "Euler")


def word_choice(values: tuple[str, ...]):
    """An argparse type: one of the words ``values`` in any letter case, returned in its
    listed spelling (:class:`sim_models.engines.ranges.Choice`, the settings' own check; imported
    when the option is given)."""
    def parse(text: str) -> str:
        from sim_models.engines.ranges import Choice
        choice = Choice(tuple(values))
        problem = choice.problem(text)
        if problem:
            raise argparse.ArgumentTypeError(problem)
        return choice.canonical(text)
    return parse


def sim_range(name: str, whole: bool = False):
    """An argparse type checked against ``sim_models.engines.ranges.<name>`` (the range the
    settings and run requests check too; imported when the option is given)."""
    def parse(text: str):
        from sim_models.engines import ranges
        try:
            v = int(text) if whole else float(text)
        except ValueError:
            kind = "an integer" if whole else "a number"
            raise argparse.ArgumentTypeError(f"{text!r} is not {kind}") from None
        problem = getattr(ranges, name).problem(v)
        if problem:
            raise argparse.ArgumentTypeError(problem)
        return v
    return parse


samples = sim_range("SAMPLES", whole=True)
revolutions = sim_range("REVOLUTIONS", whole=True)
timestep = sim_range("TIMESTEP")
workers = int_range(1, MAX_WORKERS, "each worker is a process holding both engines")


def drift_factor(text: str) -> float:
    """An argparse type: a baseline drift factor, a finite number above 1 (an error may
    grow by this factor over its baseline; 1 or less fails an unchanged run)."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (math.isfinite(v) and v > 1):
        raise argparse.ArgumentTypeError(f"{text} is out of range: the drift factor must be a "
                                         "finite number above 1")
    return v


def check_input_range(values, revolute: bool) -> None:
    """``--range FROM TO``: each value within the input's range, as ``--angle`` (deg) or
    ``--value`` (m) checks it; raises :class:`UsageError` naming the option."""
    for v in values:
        try:
            (angle_deg if revolute else length_m)(repr(float(v)))
        except argparse.ArgumentTypeError as e:
            raise UsageError(f"argument --range: {e}") from None


def check_sweep_points(points: int, n_elements: int, streamed: bool = False) -> None:
    """Raise :class:`UsageError` when a sweep of ``points`` over a mechanism with
    ``n_elements`` bodies and joints would exceed :data:`SWEEP_MEMORY_BUDGET` (a
    ``streamed`` sweep holds one block: no limit but the option's)."""
    if streamed:
        return
    if points > MAX_SWEEP_POINTS:
        raise UsageError(f"argument --points: {points} is out of range: the accepted range is "
                         f"2 to {MAX_SWEEP_POINTS} (more only with --csv, written block by "
                         "block)")
    cap = min(MAX_SWEEP_POINTS,
              SWEEP_MEMORY_BUDGET // (SWEEP_BYTES_PER_ELEMENT * max(n_elements, 1)))
    if points > cap:
        raise UsageError(f"argument --points: {points} is out of range for a mechanism of "
                         f"{n_elements} bodies and joints: the accepted range is 2 to {cap} "
                         f"(about {SWEEP_BYTES_PER_ELEMENT} bytes a point per body and joint, "
                         f"{SWEEP_MEMORY_BUDGET / 2 ** 30:g} GiB at most)")


# --- paths ---------------------------------------------------------------------

def _probe_dir(d: Path, what: str) -> None:
    """Raise ArgumentTypeError unless a file can be created in directory ``d``
    (a real probe: a permission check alone is wrong for root and read-only mounts)."""
    try:
        with tempfile.TemporaryFile(dir=d):
            pass
    except OSError as e:
        raise argparse.ArgumentTypeError(f"cannot write {what} in folder {str(d)!r}: "
                                         f"{e.strerror}") from None


#: Folders the output options of the running command created (deepest last): removed again,
#: when still empty, if the command is refused (:func:`remove_created_folders`), so that a
#: refused command leaves nothing behind.
_CREATED: list[Path] = []


def _make_folder(folder: Path) -> None:
    """``folder.mkdir(parents=True)``, each folder it creates noted in :data:`_CREATED`."""
    missing = [d for d in (folder, *folder.parents) if not d.exists()]
    folder.mkdir(parents=True, exist_ok=True)
    _CREATED.extend(reversed(missing))


def remove_created_folders() -> None:
    """Remove the folders :data:`_CREATED` lists that are still empty (deepest first):
    ``xval`` calls it when a command is refused, after its options made them."""
    while _CREATED:
        d = _CREATED.pop()
        with contextlib.suppress(OSError):  # not empty (a file written), or gone
            d.rmdir()


def forget_created_folders() -> None:
    """Start a command with no folder noted (``main`` may run many times in one process)."""
    _CREATED.clear()


def output_file(text: str) -> str:
    """An argparse type: a file to (over)write, or ``-`` for standard output.  The
    folders it is in are created when missing (the README's ``--out ci/base.json``)."""
    if text == "-":
        return text
    p = Path(text)
    if p.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a folder; give a file name")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        try:
            _make_folder(parent)
        except OSError as e:
            raise argparse.ArgumentTypeError(f"cannot create folder {str(parent)!r}: "
                                             f"{e.strerror}") from None
    if p.exists() and not os.access(p, os.W_OK):
        raise argparse.ArgumentTypeError(f"file {text!r} is not writable")
    _probe_dir(parent, "a file")
    return text


def output_dir(text: str) -> str:
    """An argparse type: a folder to write into (created if missing)."""
    p = Path(text)
    if p.exists() and not p.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} exists and is not a folder")
    try:
        _make_folder(p)
    except OSError as e:
        raise argparse.ArgumentTypeError(f"cannot create folder {text!r}: "
                                         f"{e.strerror}") from None
    _probe_dir(p, "files")
    return text


def scheduler_address(text: str) -> str:
    """An argparse type: a Dask scheduler address, ``[PROTOCOL://]HOST:PORT``."""
    m = re.fullmatch(r"(?:(tcp|tls|inproc|ucx|ws|wss)://)?([^:/\s]+|\[[0-9a-fA-F:]+\]):(\d+)",
                     text)
    if not m or not 0 < int(m.group(3)) < 65536:
        raise argparse.ArgumentTypeError(f"{text!r} is not a scheduler address; expected "
                                         "HOST:PORT or tcp://HOST:PORT (port 1 to 65535)")
    return text


def case_or_file(text: str) -> str:
    """An argparse type: a built-in case name, or a readable TOML file (returned as
    an absolute path, so that worker processes and file names do not depend on the
    current folder)."""
    from analytic.cases import case_names, hard_case_names
    if text in case_names() or text in hard_case_names():
        return text
    p = Path(text)
    if p.is_file():
        return str(p.resolve())
    if text.lower().endswith((".toml", ".xml", ".urdf", ".sdf")) or os.sep in text:
        raise argparse.ArgumentTypeError(f"no such file {text!r}")
    raise argparse.ArgumentTypeError(f"no built-in case {text!r}; cases are {case_names()}, "
                                     f"hard cases {hard_case_names()}")


# --- display units and CI outputs ------------------------------------------------

def units_option(text: str):
    """The type of ``--units``: a :class:`~reports.figures.display_units.DisplayUnits` (an error
    is one line, status 2)."""
    from reports.figures.display_units import DisplayUnits, UnitsError
    try:
        return DisplayUnits.parse(text)
    except UnitsError as e:
        raise argparse.ArgumentTypeError(str(e).removeprefix("option --units: ")) from None


UNITS_HELP = ("display units, e.g. mm,deg,rpm: a length m|cm|mm|in, an angle deg|rad, an "
              "angular speed rad/s|rpm (default m,deg,rad/s)")


def add_ci_outputs(parser) -> None:
    """``--junit FILE`` and ``--summary FILE`` on a command (:mod:`reports.regression.ci_formats`
    writes them)."""
    parser.add_argument("--junit", type=output_file, metavar="FILE",
                        help="write JUnit XML: one test case per case x engine")
    parser.add_argument("--summary", type=output_file, metavar="FILE",
                        help="write a Markdown summary (e.g. a CI job summary)")
