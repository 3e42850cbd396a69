"""Checking a baseline (``xval baseline check``, the pytest plugin): every recorded run
re-run (:func:`check`, :func:`check_run`) and each quantity judged against its record
(:func:`judge`, :func:`judge_free` for a free run): above its tolerance, grown by more
than ``factor`` over its baseline (with the absolute floor
:data:`reports.regression.baseline.DRIFT_FLOOR`), shrunk by more (a loose baseline), or
gone; and the run itself: its model changed or gone, its engine gone, the run refused or
failed.  :mod:`reports.regression.messages` says it in lines of text.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

from analytic import load_case
from analytic.errors import LinkageError
from analytic.input_display import format_input
from reports.regression import model_identity as mid
from reports.regression import own_model as own
from reports.regression.baseline import (
    DEFAULT_FACTOR,
    DRIFT_FLOOR,
    Baseline,
    BaselineError,
    QuantityRecord,
    RunRecord,
    builtin_names,
    file_sha256,
    input_unit,
    versions,
)
from reports.regression.baseline_free import horizon_slack
from reports.regression.baseline_record import Runner, run_and_compare
from reports.regression.baseline_settings import settings_from_json, settings_line
from sim_models.builders.tree import SimModelError
from sim_models.engines.registry import get_engine


@dataclass(frozen=True)
class QuantityCheck:
    """One quantity against its baseline.  ``status``: "ok", "over-tolerance", "drift",
    "not-finite", "missing" (recorded, no longer compared), "new" (not recorded;
    reported, not judged), "improved" (the error shrank by more than the factor: the
    baseline is loose, a warning) or "loose" (the same, failed: ``fail_loose``)."""

    quantity: str
    status: str
    error: float            # now, relative to peak (NaN when missing)
    base: float             # recorded (NaN when new)
    at: float
    at_unit: str
    tolerance: float
    factor: float
    #: free runs: the trusted horizon now and recorded, s (inf: never exceeded), and how
    #: much earlier it may come (``reports.regression.baseline_free.horizon_slack``)
    horizon: float = math.nan
    base_horizon: float = math.nan
    slack: float = math.nan

    @property
    def scale_word(self) -> str:
        """What the error is relative to: a free run's range, a prescribed run's peak."""
        return "of range" if self.at_unit == "s" else "of peak"

    @property
    def failed(self) -> bool:
        return self.status not in ("ok", "new", "improved")

    @property
    def ratio(self) -> float:
        """Growth over the baseline (inf from a zero baseline)."""
        if not (math.isfinite(self.error) and math.isfinite(self.base)):
            return math.nan
        return self.error / self.base if self.base > 0 else \
            (1.0 if self.error == 0 else math.inf)

    def message(self) -> str:
        """One line naming the quantity, what happened, by how much and where."""
        at = f" at {format_input(self.at, self.at_unit)}" if math.isfinite(self.at) else ""
        of = self.scale_word
        if self.status == "missing":
            return f"{self.quantity}: recorded (error {self.base:.3g} {of}) but no " \
                   "longer compared"
        if self.status == "new":
            return f"{self.quantity}: new, not in the baseline (error {self.error:.3g} {of})"
        if self.status == "not-finite":
            return f"{self.quantity}: error is not finite{at} (the run diverged or failed)"
        if self.status == "horizon":
            return f"{self.quantity}: trusted horizon {self.base_horizon:.4g} s -> " \
                   f"{self.horizon:.4g} s, earlier by more than one sample interval " \
                   f"({self.slack:.3g} s; error {self.error:.3g} {of}, tolerance " \
                   f"{self.tolerance:g})"
        grew = f"{self.base:.3g} -> {self.error:.3g} {of}{at} ({_times(self.ratio)})"
        if self.status in ("improved", "loose"):
            return f"{self.quantity}: improved {grew}, more than the factor " \
                   f"{self.factor:g}: the baseline is loose; re-record"
        if self.status == "over-tolerance":
            return f"{self.quantity}: error {self.error:.3g} {of}{at} exceeds its " \
                   f"tolerance {self.tolerance:g} (baseline {self.base:.3g}, {_times(self.ratio)})"
        if self.status == "drift":
            floor = "" if self.base >= DRIFT_FLOOR else \
                f"; baseline below the floor {DRIFT_FLOOR:g}, so the limit is " \
                f"{self.factor * DRIFT_FLOOR:.3g}"
            return f"{self.quantity}: drifted {grew}, more than the factor " \
                   f"{self.factor:g}{floor}"
        return f"{self.quantity}: {grew}"


def _times(r: float) -> str:
    if not math.isfinite(r):
        return "from zero"
    return f"{r:.3g}x" if r < 1e4 else f"{r:.2g}x"


def judge(q: QuantityRecord, error: float, at: float, factor: float,
          fail_loose: bool = False) -> QuantityCheck:
    """The verdict of one quantity now (``error`` relative to peak) against its record.
    An error that shrank by more than ``factor`` (both floored at :data:`DRIFT_FLOOR`)
    leaves the baseline loose: it would let the error grow back unnoticed."""
    if not math.isfinite(error):
        status = "not-finite"
    elif error > q.tolerance:
        status = "over-tolerance"
    elif error > factor * max(q.error, DRIFT_FLOOR):
        status = "drift"
    elif q.error > factor * max(error, DRIFT_FLOOR):
        status = "loose" if fail_loose else "improved"
    else:
        status = "ok"
    return QuantityCheck(q.quantity, status, error, q.error, at, q.at_unit, q.tolerance,
                         factor)


def judge_free(q, c, factor: float, fail_loose: bool, slack: float):
    """The check of one free quantity ``c`` (a :class:`FreeComparison`) against its
    record ``q``: the prescribed judge on its error (the tolerance only when the record
    was within it), then its trusted horizon (no earlier than recorded minus
    ``slack`` s)."""

    error, h = float(c.normalised), float(c.horizon)
    within = math.isinf(q.horizon)
    ref = q if within else replace(q, tolerance=math.inf)
    out = judge(ref, error, float(c.at), factor, fail_loose)
    out = replace(out, tolerance=q.tolerance, horizon=h, base_horizon=q.horizon)
    if out.status == "ok" and not within and h < q.horizon - slack:
        out = replace(out, status="horizon", slack=slack)
    return out


@dataclass
class RunCheck:
    """One recorded run re-run: its quantities' verdicts and the run-level problems
    (model changed or gone, engine gone, run refused or failed)."""

    record: RunRecord
    quantities: list[QuantityCheck] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    versions_now: dict = field(default_factory=dict)
    settings_text: str = ""
    wall: float = 0.0

    @property
    def passed(self) -> bool:
        return not self.problems and not any(q.failed for q in self.quantities)

    def failures(self) -> list[QuantityCheck]:
        """Failed quantities, worst first (by growth over the limit)."""
        bad = [q for q in self.quantities if q.failed]
        return sorted(bad, key=severity, reverse=True)

    def worst(self) -> QuantityCheck | None:
        """The failing quantity to name first, else the largest error."""
        bad = self.failures()
        if bad:
            return bad[0]
        done = [q for q in self.quantities if math.isfinite(q.error)]
        return max(done, key=lambda q: q.error, default=None)

    def loose(self) -> list[QuantityCheck]:
        """Quantities whose error shrank by more than the factor (warnings)."""
        return [q for q in self.quantities if q.status == "improved"]

    def versions_changed(self) -> dict[str, tuple[str, str]]:
        return {k: (str(v), str(self.versions_now.get(k, "unknown")))
                for k, v in self.record.versions.items()
                if self.versions_now and str(self.versions_now.get(k, "unknown")) != str(v)}


def severity(q: QuantityCheck) -> tuple:
    rank = {"not-finite": 4, "over-tolerance": 3, "missing": 2, "horizon": 2,
            "drift": 1}.get(q.status, 0)
    over = q.error / max(q.factor * max(q.base, DRIFT_FLOOR), 1e-300) \
        if math.isfinite(q.error) and math.isfinite(q.base) else math.inf
    return (rank, over)


def check(baseline: Baseline, factor: float = DEFAULT_FACTOR, runner: Runner | None = None,
          select: Callable[[RunRecord], bool] | None = None, fail_loose: bool = False,
          overrides: dict | None = None) -> list[RunCheck]:
    """Re-run every recorded run (those ``select`` keeps) and judge it (see the module
    docstring).  ``fail_loose``: an error that shrank by more than ``factor`` fails
    (default: a warning); ``overrides``: engine name -> {setting: value} applied over
    the recorded settings (``--set``; named in each run's settings text).  Raises
    :class:`BaselineError` only for a file that cannot be applied (e.g. settings the
    engine no longer accepts); everything about the runs themselves is in the returned
    :class:`RunCheck`."""
    if not (factor > 1 and math.isfinite(factor)):
        raise BaselineError(f"the drift factor must be a finite number above 1, got "
                            f"{factor!r}")
    runner = runner or run_and_compare
    return [check_run(rec, baseline, factor, runner, fail_loose, (overrides or {}).get(
        rec.engine)) for rec in baseline.runs if select is None or select(rec)]


def check_run(rec: RunRecord, baseline: Baseline, factor: float, runner: Runner,
              fail_loose: bool = False, overrides: dict | None = None) -> RunCheck:
    """One record: rebuild its mechanism and settings (with ``overrides``), run, judge."""
    out = RunCheck(rec)
    mech = _mechanism_now(rec, baseline, out)
    settings = _settings_now(rec, baseline, out, overrides)
    if mech is None or settings is None:
        return out
    out.settings_text = settings_line(rec.engine, settings) + (
        " (changed for this check: " + " ".join(f"{k}={v}" for k, v in overrides.items())
        + ")" if overrides else "")
    out.versions_now = versions(rec.engine)
    t0 = time.perf_counter()
    try:
        r, comps = runner(mech, rec.engine, settings, rec.request)
    except LinkageError as e:  # a refusal, or nothing left to compare
        out.problems.append(f"the run could not be compared: {e}")
        out.wall = time.perf_counter() - t0
        return out
    out.wall = time.perf_counter() - t0
    ran_as = getattr(r, "case", rec.case)
    if ran_as != rec.case:  # a record renamed by hand would pass under the wrong name
        out.problems.append(f"recorded as case {rec.case!r}, but its model "
                            f"{rec.model.describe()} runs as {ran_as!r}: the record is "
                            "under another case's name; re-record it")
    if own.is_model_file(getattr(mech, "source", None)):  # the user's file's own options
        out.settings_text = getattr(r, "settings_text", None) or r.settings.describe()
    if not r.ok:
        out.problems.append(f"the run failed: {r.reason}")
    now = {c.quantity: c for c in comps}
    for q in rec.quantities:
        c = now.get(q.quantity)
        if c is None:
            out.quantities.append(QuantityCheck(q.quantity, "missing", math.nan, q.error,
                                                math.nan, q.at_unit, q.tolerance, factor))
        elif rec.free:
            out.quantities.append(judge_free(q, c, factor, fail_loose,
                                             horizon_slack(rec.request)))
        else:
            out.quantities.append(judge(q, float(c.normalised), float(c.at), factor,
                                        fail_loose))
    recorded = {q.quantity for q in rec.quantities}
    unit = "s" if rec.free else input_unit(mech)
    for c in comps:
        if c.quantity not in recorded:
            out.quantities.append(QuantityCheck(c.quantity, "new", float(c.normalised),
                                                math.nan, float(c.at), unit, c.tolerance,
                                                factor))
    return out


def _mechanism_now(rec: RunRecord, baseline: Baseline, out: RunCheck):
    """The recorded model as it is now (None, with a problem, when it is gone)."""
    src = rec.model
    if src.kind == "builtin" and src.name not in builtin_names():
        out.problems.append(f"the built-in case {src.name!r} no longer exists")
        return None
    p = src.path(baseline.base_dir)
    if not p.is_file():
        out.problems.append(f"the model {src.describe()} is gone (looked for {p})")
        return None
    try:
        if own.is_model_file(p):  # a user's MJCF model: identity with its options
            mech, flat = own.own_content(str(p), recorded=src.content or {})
        else:
            mech = load_case(src.name if src.kind == "builtin" else str(p))
            flat = mid.content(mech)
    except LinkageError as e:
        out.problems.append(f"the model {src.describe()} changed since the baseline and "
                            f"no longer loads: {e}")
        return None
    # identity by content: the parsed mechanism, not the bytes (a comment or CRLF is no
    # change); a file recorded before content identity holds the bytes' SHA-256
    if mid.digest_of_content(flat) != src.sha256 and file_sha256(p) != src.sha256:
        what = mid.changes(src.content, flat) if src.content is not None \
            else f"sha256 {src.sha256[:12]}... (recorded from the file's bytes)"
        out.problems.append(f"the model {src.describe()} changed since the baseline "
                            f"(parsed mechanism): {what}; re-record the baseline if the "
                            "change is intended")
    return mech


def _settings_now(rec: RunRecord, baseline: Baseline, out: RunCheck,
                  overrides: dict | None = None):
    try:
        get_engine(rec.engine)
    except (SimModelError, ImportError) as e:  # not registered, or its library missing
        out.problems.append(f"engine {rec.engine!r} is not available: {e}")
        return None
    # every field is present: a missing one is refused where the file is read
    return settings_from_json(rec, str(baseline.path), overrides)



__all__ = ["QuantityCheck", "RunCheck", "check", "check_run", "judge", "judge_free",
           "severity"]
