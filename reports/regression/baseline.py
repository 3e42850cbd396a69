"""Baselines: what each engine run's errors were, so a later run can tell when they drift.

A baseline file records, per (case, engine, quantity), the worst error relative to the
quantity's peak over the cycle, where in the cycle it occurs, the tolerance, and what is
needed to re-run the run exactly: the mechanism's source (a built-in case name, or a
TOML file path relative to the baseline file), with the parsed mechanism flattened to its
SI values and their SHA-256 (:mod:`reports.regression.model_identity`: a comment or CRLF is no
change, a real one is named), the run request and the engine's settings object in full.
It also records the versions the run was made with (engine, linkage-xval, Python,
numpy, platform).  :func:`reports.regression.baseline_check.check` re-runs every
recorded run and judges each quantity (:func:`reports.regression.baseline_check.judge`):
above its tolerance, grown by more than ``factor`` over its baseline (with the absolute
floor :data:`DRIFT_FLOOR`), or gone.

File format (``schema = "linkage-xval baseline"``, ``schema_version = 1``); plain JSON,
keys sorted, two-space indent, one line per quantity, so that a diff shows what moved::

    {
      "recorded": "2026-11-23T05:00:00Z",
      "runs": [
        {
          "case": "seed-four-bar",                 # the mechanism's name (a label)
          "engine": "mujoco",                      # a registry name
          "model": {"builtin": "seed-four-bar", "sha256": "...", "content": {...}}
                 | {"file": "linkages/four_bar.toml", "sha256": "...",
                    "content": {"bodies.coupler.mass": 0.6, ...}},   # one line
          "quantities": [
            {"at": 165.0, "at_unit": "deg", "error": 1.48e-08, "max_abs": ..., "peak": ...,
             "quantity": "B.force", "tolerance": 0.001},
            ...                                    # sorted by quantity
          ],
          "request": {"chords": "moving", "max_speed_error": 0.01, "max_violation": 0.001,
                      "mode": "run", "revolutions": 2, "samples": 36},
          "settings": {"class": "MujocoSettings", "engine": "mujoco", "fields": {...}},
          "versions": {"engine": "mujoco 3.3.7", "linkage-xval": "0.1.0", "numpy": "2.4.0",
                       "platform": "Linux-...", "python": "3.11.2"}
        }, ...                                     # sorted by case, then engine
      ],
      "schema": "linkage-xval baseline",
      "schema_version": 1
    }

``error`` is ``max |engine - analytic| / peak`` (:func:`reports.comparison.compare.compare`), stored
to :data:`ERROR_DIGITS` significant figures; ``at`` is the input value (deg for a
revolute driver, m for a prismatic one).  The engines' own unjudged readings
(``[engine]`` rows) are not recorded.  A file that cannot be read, is not this schema,
or lacks a key raises :class:`BaselineError` (the command line: one line, status 2).

This module holds the records (what a file holds, as frozen dataclasses) and the
constants of the check; the rest by concern:

* :mod:`reports.regression.baseline_store`: the file read (every value checked) and
  written;
* :mod:`reports.regression.baseline_settings`: a run's engine settings and their
  overrides (``--set``);
* :mod:`reports.regression.baseline_record`: running and recording (``xval baseline
  record``);
* :mod:`reports.regression.baseline_check`: re-running and judging (``xval baseline
  check``, the pytest plugin).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import platform
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np

from analytic.cases import case_names, case_path, free_case_names, hard_case_names
from analytic.errors import LinkageError
from analytic.mechanism import Prismatic

SCHEMA = "linkage-xval baseline"
SCHEMA_VERSION = 1

#: Default drift factor: a quantity fails when its error grows by more than this over
#: its baseline (issue 13: "MuJoCo's error grew from 1e-8 to 5e-4").
DEFAULT_FACTOR = 10.0

#: Absolute floor (relative to peak) under the drift check: a quantity fails for drift
#: only when its error exceeds ``factor * max(baseline, DRIFT_FLOOR)``.  Errors far
#: below the tolerance include pure round-off (a constant-speed crank's alpha reads 0 or
#: 1e-22), and a perturbation the size of round-off moves them.  Measured over every
#: built-in case in every engine, scaling every mass by (1 + 1e-14) changed the errors
#: below 1e-6 of peak by at most 5e-9 of peak (PyBullet six-bar output.alpha; MuJoCo
#: 8e-14, Exudyn 2e-15).  It changed larger errors by at most 7% of themselves (PyBullet
#: six-bar link.alpha; Exudyn six-bar 2%), and the largest growth over max(error, 1e-7)
#: was 1.07x.  With 1e-7 the smallest drift that fails (1e-6 at factor 10) is 200x the
#: largest jitter of a small error, and still a thousandth of the 1e-3 tolerance.
DRIFT_FLOOR = 1e-7

#: The range of a recorded tolerance (a fraction of the quantity's peak over the run),
#: through every door (``--tolerance``, a baseline file, the pytest plugin's
#: ``tolerance=``): above 1 an error larger than the quantity itself passes (a
#: hand-edited 1e300 judges nothing); below 1e-15 no float64 run can pass it.
MIN_TOLERANCE, MAX_TOLERANCE = 1e-15, 1.0


def tolerance_problem(value) -> str | None:
    """Why ``value`` is not an accepted tolerance (one phrase with the range), else None."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) \
        and math.isfinite(value) and MIN_TOLERANCE <= value <= MAX_TOLERANCE
    return None if ok else (f"{json_value(value)} is out of range: the accepted range is "
                            f"{MIN_TOLERANCE:g} to {MAX_TOLERANCE:g} of the quantity's peak")


#: Significant figures stored for errors (drift is judged by factors, not digits; fewer
#: digits keep a re-recorded file's diff to the errors that really moved).
ERROR_DIGITS = 4


class BaselineError(LinkageError):
    """A baseline file cannot be used: names the file, the entry and the problem."""


# ============================================================================ records
@dataclass(frozen=True)
class ModelSource:
    """Where a run's mechanism comes from: ``kind`` "builtin" (``name`` a case name) or
    "file" (``name`` a path relative to the baseline file's folder, POSIX separators);
    ``sha256`` of the parsed mechanism's canonical content when recorded
    (:func:`reports.regression.model_identity.digest`; files recorded before that hold the SHA-256
    of the file's bytes, still accepted); ``content`` the mechanism flattened
    (:func:`reports.regression.model_identity.content`), so a change can be named (None in older
    files)."""

    kind: str
    name: str
    sha256: str
    content: dict | None = field(default=None, compare=False)

    def as_json(self) -> dict:
        out = {self.kind: self.name, "sha256": self.sha256}
        return out if self.content is None else {**out, "content": self.content}

    def path(self, base_dir: Path) -> Path:
        """The description file this source names now."""
        if self.kind == "builtin":
            return Path(case_path(self.name))
        return base_dir / self.name

    def describe(self) -> str:
        return f"built-in case {self.name!r}" if self.kind == "builtin" else f"file {self.name}"


@dataclass(frozen=True)
class QuantityRecord:
    """One quantity's recorded diagnostic (see :class:`reports.comparison.compare.Comparison`)."""

    quantity: str
    error: float          # max |error| / peak
    at: float             # input value where it occurs (``at_unit``)
    at_unit: str          # "deg" or "m"
    tolerance: float      # relative to peak
    max_abs: float        # SI units of the quantity
    peak: float
    #: a free run's trusted horizon, s (inf: never exceeded; None: a prescribed run,
    #: whose error is relative to the peak and ``at`` an input value; a free run's is
    #: relative to the range over the run and ``at`` a time, s)
    horizon: float | None = None

    def as_json(self) -> dict:
        out = {"quantity": self.quantity, "error": _sig(self.error, ERROR_DIGITS),
               "at": _sig(self.at, 7), "at_unit": self.at_unit, "tolerance": self.tolerance,
               "max_abs": _sig(self.max_abs, ERROR_DIGITS), "peak": _sig(self.peak, 6)}
        if self.horizon is not None:  # null: never exceeded within the run
            out["horizon_s"] = _sig(self.horizon, 7)
        return out


@dataclass(frozen=True)
class RunRecord:
    """One recorded (case, engine) run: enough to re-run it exactly, and its errors."""

    case: str
    engine: str
    model: ModelSource
    request: dict
    settings: dict        # {"engine", "class", "fields": {name: value}}
    versions: dict
    quantities: tuple[QuantityRecord, ...]
    #: why a free run being recorded stopped early (not written: refused by
    #: :func:`reports.regression.baseline_record.record_problems`)
    stopped: str = field(default="", compare=False)

    @property
    def free(self) -> bool:
        """A free-motion run (:mod:`reports.regression.baseline_free`)."""
        return self.request.get("mode") == "free"

    @property
    def key(self) -> tuple[str, ...]:
        base = (self.model.kind, self.model.name, self.engine)
        return (*base, "free") if self.free else base

    @property
    def label(self) -> str:
        return f"{self.case} / {self.engine}" + (
            f" (free, {self.request['duration']:g} s)" if self.free else "")

    def as_json(self) -> dict:
        return {"case": self.case, "engine": self.engine, "model": self.model.as_json(),
                "request": dict(self.request), "settings": self.settings,
                "versions": dict(self.versions),
                "quantities": [q.as_json() for q in sorted(self.quantities,
                                                           key=lambda q: q.quantity)]}


@dataclass(frozen=True)
class Baseline:
    """A baseline file's content; ``path`` is where it was read from or written to."""

    runs: tuple[RunRecord, ...]
    path: Path
    recorded: str = ""

    @property
    def base_dir(self) -> Path:
        return self.path.resolve().parent

    def as_json(self) -> dict:
        runs = sorted(self.runs, key=lambda r: (r.case, r.engine, r.model.name))
        return {"schema": SCHEMA, "schema_version": SCHEMA_VERSION,
                "recorded": self.recorded, "runs": [r.as_json() for r in runs]}


def _sig(x: float, digits: int) -> float | None:
    """``x`` to ``digits`` significant figures (JSON has no inf/NaN: those become None)."""
    x = float(x)
    return float(f"{x:.{digits}g}") if math.isfinite(x) else None


def versions(engine: str) -> dict:
    """The versions a run depends on: the engine's library, this project, Python, numpy
    and the platform (read from package metadata; no engine library is imported)."""

    def ver(dist: str) -> str:
        try:
            return version(dist)
        except PackageNotFoundError:
            return "unknown"

    return {"engine": f"{engine} {ver(engine)}", "linkage-xval": ver("linkage-xval"),
            "python": platform.python_version(), "numpy": np.__version__,
            "platform": platform.platform()}



def file_sha256(path: str | os.PathLike) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def builtin_names() -> list[str]:
    """The names a baseline records as built-in: the cases, the hard cases and the
    free-motion cases."""
    return [*case_names(), *hard_case_names(), *free_case_names()]


def input_unit(mech) -> str:
    """The unit of a prescribed run's input value: "deg" for a revolute driver, "m" for a
    prismatic one."""
    return "m" if isinstance(mech.driver_joint, Prismatic) else "deg"


def json_value(v) -> str:
    """``v`` as the file spells it (``true``, ``NaN``, ``"bogus"``)."""
    try:
        return json.dumps(v)
    except (TypeError, ValueError):
        return repr(v)


__all__ = ["DEFAULT_FACTOR", "DRIFT_FLOOR", "ERROR_DIGITS", "SCHEMA", "SCHEMA_VERSION",
           "Baseline", "BaselineError", "ModelSource", "QuantityRecord", "RunRecord",
           "builtin_names", "file_sha256", "input_unit", "json_value", "tolerance_problem",
           "versions"]
