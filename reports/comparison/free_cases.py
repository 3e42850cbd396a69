"""The free-motion cases the verdicts, studies and report run: the IFToMM problems and
the built-in cases released under gravity.

A built-in case has no ``[motion]`` table (it is driven): the engines' own
:func:`sim_models.builders.free_cases.released` gives it one (released at rest from its driver's
reference value under 9.81 m/s^2 in -y, named ``<case>-released``), so the verdicts
judge exactly the mechanism the engines run.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path

from analytic import Mechanism, load_case
from analytic.errors import DescriptionError
from analytic.free_motion import simulate
from analytic.free_motion.iftomm import n_four_bar_toml
from analytic.mechanism import Revolute
from analytic.motion_spec import MAX_DURATION
from analytic.toml_io import mechanism_from_dict
from reports.comparison.free_compare import compare_free, reference_samples
from sim_models.builders.free_cases import G, released
from sim_models.engines.ranges import Range
from sim_models.engines.settings import SettingsError
from sim_models.runs.free import free_settings, run_free
from sim_models.runs.free_run import FreeRequest

#: Shortest free-motion duration accepted through every door (``xval simulate
#: --duration``, baseline files), s: one microsecond (the IFToMM A03 run is 0.03 s).
MIN_DURATION = 1e-6
#: The accepted range of a free run's duration (s) and of its sample times, through
#: every door: ``xval simulate --duration/--samples``, a baseline file's ``request``,
#: the pytest plugin's ``assert_free_agrees(duration=, samples=)`` (sample intervals
#: there: one fewer).  :func:`free_request_problem` checks both.
FREE_DURATION = Range(MIN_DURATION, MAX_DURATION, unit="s", why="the range of --duration")
#: Most sample times at which an engine's free run is judged (``xval simulate --engine
#: --samples``, ``baseline record --free --samples``, a baseline file, the Python API):
#: each costs an engine readout and an exact one with the forces, about 2.5 + 2 ms on a
#: loaded 2-core machine (20001 samples of the turn-4 four-bar: 51 s engine, 39 s
#: exact), so 1e6 (the exact table's maximum, ``xval simulate --csv``) ran for an hour.
#: 10001 resolve a trusted horizon to 1e-4 of the duration.
MAX_JUDGED_SAMPLES = 10_001
FREE_SAMPLES = Range(2, MAX_JUDGED_SAMPLES, whole=True,
                     why="sample times at which an engine is judged, from 0 to the duration; "
                         "the range of --samples with an engine")
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

    return mechanism_from_dict(tomllib.loads(n_four_bar_toml()), A02)


@dataclass(frozen=True)
class Release:
    """How a built-in case without ``[motion]`` was released (for the command's output):
    ``joint`` at ``value`` (rad or m) at rest, under ``gravity`` m/s^2 in -y, for
    ``duration`` s; ``text``: the same in one sentence."""

    case: str
    joint: str
    value: float
    revolute: bool
    gravity: float
    duration: float

    @property
    def text(self) -> str:
        v = (f"{math.degrees(self.value):.6g} deg" if self.revolute
             else f"{self.value * 1e3:.6g} mm")
        return (f"{self.case} has no [motion] table: released as the report's free-motion "
                "section releases it (reports/comparison/free_cases.py): "
                f"joint {self.joint} at its "
                f"driver's reference value {v}, at rest, under {self.gravity:g} m/s^2 in -y, "
                f"{self.duration:g} s")

    def as_json(self) -> dict:
        return {"case": self.case, "joint": self.joint,
                "value": self.value, "value_unit": "rad" if self.revolute else "m",
                "rate": 0.0, "gravity_m_s2": [0.0, -self.gravity],
                "duration_s": self.duration}


def command_case(name: str, duration: float | None = None
                 ) -> tuple[Mechanism, Release | None]:
    """``xval simulate``'s case: a file or a case with ``[motion]`` as it is; a built-in
    case without one released by :func:`free_case`'s rule (the report's), with the
    :class:`Release` to state.  Raises :class:`DescriptionError` (one line) for a
    file without ``[motion]`` (the command line, baselines and the Python API do not
    guess a release for a user's description) or a built-in case that cannot be
    released: one whose moving bodies have no mass (the kinetostatic textbook cases:
    nothing for gravity to act on), or one without a driver to release."""
    mech = load_case(name)
    if mech.motion is not None:
        return mech, None
    if _is_file(name):  # a user's file is not guessed at: every door refuses it alike
        raise DescriptionError("no [motion] table: free motion needs the initial joint, "
                               "value, rate and duration", mech.source)
    massless = [b.name for b in mech.moving_bodies if not b.mass]
    if len(massless) == len(mech.moving_bodies):
        raise DescriptionError(
            f"case {name!r} cannot be released under gravity: no moving body has mass "
            f"({', '.join(massless)}); it is a prescribed-motion case (xval compare, "
            "xval solve); give a file with masses and a [motion] table")
    if mech.driver is None:
        raise DescriptionError(f"case {name!r} cannot be released: it has no [driver] "
                               "joint to release and no [motion] table")
    mech = free_case(name, duration)
    m = mech.motion
    return mech, Release(name, m.joint, float(m.value),
                         isinstance(mech.joint(m.joint), Revolute), G, float(m.duration))


def free_request_problem(duration, samples) -> tuple[str, object, str] | None:
    """``(key, value, problem)`` of the first of ``duration`` (s; None: the
    description's) and ``samples`` (sample times) outside :data:`FREE_DURATION` /
    :data:`FREE_SAMPLES`, else None."""
    for key, value, rng in (("duration", duration, FREE_DURATION),
                            ("samples", samples, FREE_SAMPLES)):
        if value is None and key == "duration":
            continue
        problem = rng.problem(value)
        if problem:
            return key, value, problem
    return None


def check_free_request(duration, intervals, where: str = "free run") -> None:
    """:class:`SettingsError` (one line, ``where`` first) unless :func:`free_request_problem`
    accepts ``duration`` and ``intervals + 1`` sample times (the Python API counts
    sample intervals, the command line sample times: one range for both)."""
    whole = isinstance(intervals, int) and not isinstance(intervals, bool)
    bad = free_request_problem(duration, intervals + 1 if whole else intervals)
    if bad:
        key, value, problem = bad
        shown = (f"samples={intervals!r} sample intervals ({value} sample "
                 f"time{'s' if value != 1 else ''})"
                 if key == "samples" and whole else f"{key}={value!r}")
        raise SettingsError(f"{where} {shown}: {problem}", key, value, problem)


def release_and_judge(mech: Mechanism, engine: str, duration: float | None = None,
                      samples: int = 200, settings=None):
    """One engine's free run of ``mech`` (a Mechanism with ``[motion]``, or a driven
    one, released by :func:`free_case`'s rule) judged against the exact trajectory:
    ``(FreeEngineRun, FreeVerdict)``.  ``samples``: sample intervals; ``settings``:
    overrides of the engine's recommended free settings (typed values or
    ``key=value`` strings); without a ``timestep`` among them the step is chosen from
    the motion (:mod:`sim_models.runs.free_step`).  ``duration`` and ``samples + 1``
    (sample times) within :data:`FREE_DURATION` and :data:`FREE_SAMPLES`, the command line's ranges
    (:class:`SettingsError` otherwise, before anything runs)."""
    check_free_request(duration, samples)
    if mech.motion is None:
        mech = released(mech, RELEASE_DURATION if duration is None else duration)
    traj = simulate(mech, duration, wall_limit=FreeRequest.wall_limit)  # bounded, as the CLI
    req = FreeRequest(duration=traj.duration, samples=samples)
    run = run_free(mech, engine, free_settings(engine, settings), req, traj,
                   step_from_motion="timestep" not in (settings or {}))  # a set step wins
    return run, compare_free(run, traj, reference_samples(traj, req.times()))


def _is_file(name: str) -> bool:
    return str(name).endswith(".toml") or Path(str(name)).is_file()
