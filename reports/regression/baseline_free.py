"""Free-motion runs in a baseline file (:mod:`reports.regression.baseline`): an engine released from
the exact state, judged by :func:`reports.comparison.free_compare.compare_free`, recorded and
checked by the same record / check cycle as the prescribed runs (``xval baseline
record --free``, ``xval baseline check``, the pytest plugin).

A free run's record differs from a prescribed one in three places:

* ``request``: ``{"mode": "free", "duration": s, "samples": n}`` (``n`` sample times
  from 0 to the duration inclusive), each in the range ``xval simulate`` accepts
  (:data:`reports.comparison.free_cases.MIN_DURATION` to :data:`analytic.motion_spec.MAX_DURATION`
  s, 2 to :data:`analytic.motion_spec.MAX_SAMPLES`); a built-in case without
  ``[motion]`` is released as the report releases it (:func:`reports.comparison.free_cases.
  free_case`);
* ``settings``: the engine's free-motion settings class (``MujocoFreeSettings``, ...),
  every field present and in its range, as ``xval simulate --set`` checks them;
* each quantity (every joint coordinate and rate, body angle, rate and acceleration,
  joint reaction, and ``energy`` and ``loop.gap``: the energy drift and loop drift) is
  its error over its range (``error``), the time of its maximum (``at``, s), its
  tolerance (the named ones of :mod:`reports.comparison.free_compare`) and its trusted horizon
  (``horizon_s``: the first time its error exceeds the tolerance; null: never).

A free run may be recorded while a quantity exceeds its tolerance: the trusted horizon
is then what the record holds (PyBullet's first-order step loses the released seed
four-bar after 0.85 s; a baseline guards that it does not lose it sooner).  A run that
stopped or a quantity that is not finite is never recorded.

The check (:func:`reports.regression.baseline_check.judge_free`): a quantity's error may
not grow by more than the drift factor over its record (floored at
:data:`reports.regression.baseline.DRIFT_FLOOR`, as for the prescribed runs); a quantity
recorded within its tolerance must stay within it; and its trusted horizon may not
come earlier than the recorded one by more than :data:`HORIZON_SLACK_SAMPLES` sample
intervals.
"""

from __future__ import annotations

from dataclasses import replace

from reports.comparison.free_cases import free_request_problem as ranges_problem
from reports.comparison.free_cases import release_and_judge
from sim_models.builders.free_cases import released
from sim_models.runs.free import free_session_class

#: A baseline request's mode for a free-motion run.
FREE_MODE = "free"
#: Sample times of a free run recorded without ``--samples`` (the pytest plugin's
#: ``assert_free_agrees`` default, 200 intervals).
DEFAULT_SAMPLES = 201
#: How much earlier than recorded a trusted horizon may come, in sample intervals.  The
#: horizon is where the sampled error crosses its tolerance, interpolated linearly
#: between two samples: its resolution is one interval, and an error curve moved by the
#: round-off :data:`reports.regression.baseline.DRIFT_FLOOR` allows moves the crossing by far less
#: than one.  One interval: the horizon measured one sample earlier is a change.
HORIZON_SLACK_SAMPLES = 1.0


def is_free(request: dict) -> bool:
    """Whether a recorded request is a free-motion run."""
    return isinstance(request, dict) and request.get("mode") == FREE_MODE


def free_request(duration: float, samples: int | None = None) -> dict:
    """A free run's request as a baseline records it (``samples``: sample times,
    default :data:`DEFAULT_SAMPLES`)."""
    return {"mode": FREE_MODE, "duration": float(duration),
            "samples": int(DEFAULT_SAMPLES if samples is None else samples)}


def free_request_problem(request: dict) -> tuple[str, object, str] | None:
    """``(key, value, problem)`` when a free request is outside the command line's
    ranges (``xval simulate --duration`` and ``--samples``: one definition,
    :func:`reports.comparison.free_cases.free_request_problem`), else None."""
    for key in ("duration", "samples"):
        if key not in request:
            return key, None, "missing"
    bad = ranges_problem(request["duration"], request["samples"])
    if bad:
        return bad
    extra = sorted(set(request) - {"mode", "duration", "samples"})
    if extra:
        return extra[0], request[extra[0]], "is not a free-motion request key (duration, " \
                                            "samples)"
    return None


def free_settings_class(engine: str):
    """The free-motion settings class of ``engine`` (UnknownEngineError if none)."""
    return free_session_class(engine).settings_class


def free_mechanism(mech, request: dict):
    """``mech`` as a free run releases it: its own ``[motion]`` over the recorded
    duration, or, without one, released as the report does."""

    d = float(request["duration"])
    if mech.motion is None:
        return released(mech, d)
    return replace(mech, motion=replace(mech.motion, duration=d))


def run_and_compare_free(mech, engine: str, settings, request: dict):
    """Release ``mech`` in ``engine`` as ``request`` asks and judge it against the exact
    trajectory: ``(FreeEngineRun, [FreeComparison])`` (every judged quantity, the energy
    drift, and the loop drift where the mechanism has a loop)."""
    over = settings.as_dict() if settings is not None else None
    run, v = release_and_judge(free_mechanism(mech, request), engine,
                               float(request["duration"]), int(request["samples"]) - 1, over)
    comps = [c for c in v.judged if v.has_loop or c is not v.loop]
    return run, comps


def horizon_slack(request: dict) -> float:
    """The earliest a horizon may come before its record, s."""
    n = int(request["samples"])
    return HORIZON_SLACK_SAMPLES * float(request["duration"]) / max(n - 1, 1)


__all__ = ["DEFAULT_SAMPLES", "FREE_MODE", "HORIZON_SLACK_SAMPLES", "free_mechanism",
           "free_request", "free_request_problem", "free_settings_class", "horizon_slack",
           "is_free", "run_and_compare_free"]
