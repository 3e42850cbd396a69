"""``tune``: the search (:mod:`reports.tune.search`), then its answer verified by a fresh
run, its CPU compared with the recommended settings' in one process, and the knob that
sets its error named.

::

    from reports.tune import tune, TuneCase
    res = tune(TuneCase("seed-four-bar"), "mujoco", tolerance=1e-3, budget=30)
    res.passed, res.settings, res.knob_text, res.cpu_ratio
"""

from __future__ import annotations

import dataclasses
import math
import statistics
import time
from dataclasses import dataclass, field

from reports.studies.speed_accuracy import executor
from reports.tune.measure import (
    FREE_FAMILIES,
    PRESCRIBED_FAMILIES,
    Measured,
    TuneCase,
    measure_task,
    settings_of,
)
from reports.tune.own import changed as own_changed
from reports.tune.own import own_knobs
from reports.tune.search import STEP_MATTERS, Point, Search, Tuner
from reports.tune.space import engine_knobs

#: CPU timing of the answer against the recommended settings: this many runs of each,
#: alternated in one process (the ratio of the medians; the spread is (max - min) / median).
TIMING_REPEATS = 3
#: Tolerances a search accepts: below 1e-12 no float64 run is judged that finely; at 1
#: or above every run that finishes passes.
MIN_TOLERANCE, MAX_TOLERANCE = 1e-12, 1.0
#: Budget (CPU s of the search's runs): at least one run; at most a day.
MIN_BUDGET, MAX_BUDGET = 1.0, 86400.0


class TuneInputError(ValueError):
    """A tolerance, budget or quantity family the search cannot take (one line)."""


@dataclass
class Sensitivity:
    """How the worst error at the answer moves when one knob moves: ``knob`` ("step" or
    a knob's name), ``change`` in words, the error before and after."""

    knob: str
    change: str
    before: float
    after: float

    @property
    def ratio(self) -> float:
        if self.before > 0 and math.isfinite(self.before) and math.isfinite(self.after):
            return self.after / self.before
        return math.inf


@dataclass
class TuneResult:
    """The outcome of :func:`tune` (see the module docstring)."""

    case: TuneCase
    engine: str
    tolerance: float
    family: str | None
    budget: float
    seed: int
    passed: bool                          # the verification run passes
    answer: Point | None                  # the chosen candidate (None: none passes)
    settings: object | None               # its settings object
    changed: dict                         # field -> (recommended, tuned) that differ
    verification: Measured | None
    verify_error: float
    verify_quantity: str
    cpu_tuned: float                      # median process CPU per unit, s
    cpu_recommended: float
    cpu_ratio: float
    cpu_spread: float                     # the larger (max - min) / median of the two
    recommended: Point | None
    knob_text: str
    sensitivities: list[Sensitivity]
    limit_text: str                       # when no candidate passes: what limits it
    best_reached: Point | None            # the least-error candidate
    front: list[Point]
    alternatives: list[Point]
    search: Search
    search_wall: float
    tuner: Tuner = field(repr=False)

    @property
    def unit(self) -> str:
        return "simulated s" if self.case.free else "revolution"

    def cost(self, p: Point) -> float:
        return self.tuner.cost(p)


def check_inputs(tc: TuneCase, tolerance: float, budget: float, family: str | None) -> None:
    """Raise :class:`TuneInputError` (one line) for a value the search cannot take."""
    if not (isinstance(tolerance, (int, float)) and math.isfinite(tolerance)
            and MIN_TOLERANCE <= tolerance < MAX_TOLERANCE):
        raise TuneInputError(f"argument --tolerance: {tolerance!r} is out of range: the "
                             f"accepted range is {MIN_TOLERANCE:g} to below "
                             f"{MAX_TOLERANCE:g} (a normalised error of peak)")
    if not (isinstance(budget, (int, float)) and math.isfinite(budget)
            and MIN_BUDGET <= budget <= MAX_BUDGET):
        raise TuneInputError(f"argument --budget: {budget!r} is out of range: the accepted "
                             f"range is {MIN_BUDGET:g} to {MAX_BUDGET:g} CPU seconds")
    fams = FREE_FAMILIES if tc.free else PRESCRIBED_FAMILIES
    if family is not None and family not in fams:
        raise TuneInputError(f"argument --quantity: {family!r} is not a quantity family "
                             f"of {'free' if tc.free else 'prescribed'} runs: use one of "
                             f"{', '.join(fams)} (default: all)")


def tune(tc: TuneCase, engine: str, tolerance: float = 1e-3, family: str | None = None,
         budget: float = 60.0, seed: int = 0, workers: int | None = None, pool=None,
         knob_limit: int | None = None, verify: bool = True) -> TuneResult:
    """Search, verify, time and explain (see the module docstring).  ``pool``: an
    executor (a Dask client's), None for local worker processes, False for serial;
    ``knob_limit``: search only the first knobs (to measure how the cost grows)."""
    check_inputs(tc, tolerance, budget, family)
    fields = settings_of(tc, engine, {}).as_dict()
    knobs = engine_knobs(engine, tc.free, knob_limit) if not tc.own else \
        own_knobs(tc, knob_limit)
    t0 = time.perf_counter()
    with executor(pool, workers) as ex:
        tuner = Tuner(tc, engine, tolerance, family, budget, knobs, ex,
                      wave=workers or 2, seed=seed, fields=fields)
        s = tuner.run()
        best = tuner.best()
        sens = sensitivities(tuner, best) if best is not None else []
    wall = time.perf_counter() - t0
    rec = next((p for (f, n), p in s.points.items() if n is None), None)
    res = _result(tc, engine, tolerance, family, budget, seed, tuner, best, rec, sens, wall)
    if verify and best is not None:
        _verify(res)
    return res


def _result(tc, engine, tolerance, family, budget, seed, tuner, best, rec, sens, wall):
    s = tuner.s
    finite = [p for p in s.points.values() if p.m.ok and math.isfinite(p.error)]
    reached = min(finite, key=lambda p: (p.error, tuner.rank_key(p)), default=None)
    settings = settings_of(tc, engine, tuner.overrides(best.family, best.steps)) \
        if best is not None else None
    changed = {} if settings is None else _changed(tc, engine, settings, tuner, best)
    alts = []
    seen = {best.family} if best is not None else set()
    for p in tuner.passing():
        if p.family not in seen:
            seen.add(p.family)
            alts.append(p)
    return TuneResult(
        tc, engine, tolerance, family, budget, seed, False, best, settings, changed, None,
        math.nan, "", math.nan, math.nan, math.nan, math.nan, rec,
        knob_text(tuner, best, sens), sens,
        "" if best is not None else limit_text(tuner, reached), reached,
        front(tuner), alts[:4], s, wall, tuner)


def _changed(tc: TuneCase, engine: str, settings, tuner: Tuner, best: Point) -> dict:
    """field -> (recommended, tuned) that differ (a user's model: (the file's, tuned));
    the step is the one the answer's run took (its steps per unit), as in ``settings``."""
    if tc.own:
        return own_changed(tc, tuner.overrides(best.family, best.steps))
    base = settings_of(tc, engine, {})
    return {k: (getattr(base, k), getattr(settings, k)) for k in base.as_dict()
            if getattr(base, k) != getattr(settings, k)}


def retarget(res: TuneResult, tolerance: float) -> TuneResult:
    """The answer at another ``tolerance`` read from the same search's runs, without a
    new search: the cheapest of those runs that passes it (a coarser step the search
    never ran may pass too: an upper bound on the cost); the sensitivity runs at the new
    answer are new (serial).  Takes over ``res``'s search: use ``res`` no more."""
    t = res.tuner
    t.tol = tolerance
    t.s.points = {k: dataclasses.replace(p, passed=bool(
        p.m.ok and math.isfinite(p.error) and p.error <= tolerance))
        for k, p in t.s.points.items()}
    with executor(False) as ex:
        t.ex = ex
        best = t.best()
        sens = sensitivities(t, best) if best is not None else []
    rec = next((p for (f, n), p in t.s.points.items() if n is None), None)
    return _result(res.case, res.engine, tolerance, res.family, res.budget, res.seed, t,
                   best, rec, sens, res.search_wall)


# ============================================================================ explain
def sensitivities(tuner: Tuner, best: Point) -> list[Sensitivity]:
    """The worst error at the answer with the step halved and with each knob at each of
    its other levels (same step), from the search's runs or new ones (counted in the
    budget, run even when it is spent: the explanation is part of the answer)."""
    batch = [(best.family, best.steps * 2)]
    for i, k in enumerate(tuner.knobs):
        for lv in k.levels:
            if lv != best.family[i]:
                batch.append((best.family[:i] + (lv,) + best.family[i + 1:], best.steps))
    budget, tuner.budget = tuner.budget, math.inf  # always explain
    try:
        pts = tuner.evaluate(batch)
    finally:
        tuner.budget = budget
    out = []
    for p in pts:
        if p.family == best.family:
            out.append(Sensitivity("step", f"step halved ({best.steps} -> {p.steps} steps)",
                                   best.error, p.error))
            continue
        i = next(j for j in range(len(p.family)) if p.family[j] != best.family[j])
        k = tuner.knobs[i]
        out.append(Sensitivity(k.name, f"{k.name} {best.family[i]} -> {p.family[i]}",
                               best.error, p.error))
    return out


def knob_text(tuner: Tuner, best: Point | None, sens: list[Sensitivity]) -> str:
    """One line: the knob that sets the error at the answer, and whether the step does."""
    if best is None or not sens:
        return ""
    step = next((x for x in sens if x.knob == "step"), None)
    others = [x for x in sens if x.knob != "step" and x.ratio < 1]
    low = min(others, key=lambda x: x.ratio, default=None)
    step_sets = step is not None and step.ratio <= STEP_MATTERS
    eng = tuner.engine
    # a knob sets the error when moving it lowers the error as much as a step that
    # matters would (a change within the runs' noise sets nothing)
    if low is not None and low.ratio <= STEP_MATTERS and \
            (not step_sets or low.ratio < step.ratio):
        i = [k.name for k in tuner.knobs].index(low.knob)
        k = tuner.knobs[i]
        tail = (f"; halving the step: {step.before:.2g} -> {step.after:.2g}" +
                (", not the step" if not step_sets else "")) if step else ""
        return (f"{eng}: error set by {k.name} {best.family[i]} ({k.why}): {low.change} "
                f"moves the worst error {low.before:.2g} -> {low.after:.2g}{tail}")
    if step_sets:
        order = math.log2(step.before / step.after) if step.after > 0 else math.inf
        rest = (f"; no other knob lowers it (best: {low.change}, x{low.ratio:.2g})"
                if low else "; no other knob lowers it" if tuner.knobs
                else " (the step alone searched)")
        return (f"{eng}: error set by the step ({best.steps} steps per "
                f"{'simulated s' if tuner.tc.free else 'revolution'}): halving it moves "
                f"the worst error {step.before:.2g} -> {step.after:.2g} (order "
                f"{order:.1f}){rest}")
    return (f"{eng}: no knob moves the worst error down at the answer (step halved: "
            f"x{step.ratio:.2g}); it sits at the engine's floor for this case"
            if step else f"{eng}: no knob moves the worst error down")


def limit_text(tuner: Tuner, reached: Point | None) -> str:
    """Why no candidate passes: the best error reached and where each family stopped."""
    if reached is None:
        fails = {p.m.reason for p in tuner.s.points.values() if not p.m.ok}
        return ("no run finished: " + "; ".join(sorted(fails))[:300]) if fails else \
            "no run finished"
    stops = [r.stop for r in tuner.s.families.values()]
    why = max(set(stops), key=stops.count) if stops else ""
    fl = reached.m.floor(tuner.qfamily)
    floor = (f"; the engine's float32 error floor there is {fl:.2g}" if fl >= tuner.tol
             else "")
    arith = getattr(settings_of(tuner.tc, tuner.engine, {}), "arithmetic", None)
    if not floor and arith is not None and arith.name != "float64":
        floor = f"; the engine computes in {arith.name} (an error floor no step removes)"
    budget = "; the budget was spent" if tuner.s.budget_hit else ""
    of = "of its scale" if tuner.tc.free else "of peak"
    tried = ", ".join(k.name for k in tuner.knobs if k.name not in tuner.s.not_tried)
    n = len(tuner.s.families)
    knobs = (f"; knobs tried besides the step: {tried} ({n} "
             f"famil{'y' if n == 1 else 'ies'} of levels)") if tried else ""
    return (f"best reached {reached.error:.3g} {of} ({reached.worst_quantity}) at "
            f"{reached.m.settings_text}; limit: {why} (the most common stop over the "
            f"families){floor}{budget}{knobs}{_drive_note(tuner.tc)}")


def _drive_note(tc: TuneCase) -> str:
    """A user's model driven: the drive xval compare adds is part of its error.  Measured
    on docs/examples/user-four-bar.xml (worst alpha, of peak, at steps 5e-4 / 2.5e-4 s):
    armature ratio 1e6 3.7e-4 / 3.1e-4 (the step stops mattering), 1e7 1.4e-4 / 3.4e-5,
    1e8 1.4e-4 / 8.7e-6."""
    if not tc.own or tc.free:
        return ""
    from sim_models.own.mujoco_own import DRIVE_RATIO
    return (f"; the driven run adds xval compare's drive, an armature of {DRIVE_RATIO:g} "
            "times the driver's inertia, whose finite stiffness no setting of the file "
            "removes: --free judges the model with nothing added")


def front(tuner: Tuner) -> list[Point]:
    """The Pareto front of the finished runs: no other run has both a lower model cost
    and a lower worst error (cheapest first)."""
    pts = sorted((p for p in tuner.s.points.values()
                  if p.m.ok and math.isfinite(p.error) and p.steps is not None),
                 key=lambda p: (tuner.cost(p), p.error))
    out, best_err = [], math.inf
    for p in pts:
        if p.error < best_err:
            out.append(p)
            best_err = p.error
    return out


# ============================================================================ verify
def _verify(res: TuneResult) -> None:
    """A fresh run of the answer in this process, judged at the tolerance; then the
    answer and the recommended settings timed alternately (process CPU per unit)."""
    tc, eng, over = res.case, res.engine, res.answer.m.overrides
    v = measure_task(tc, eng, over)
    q, err = v.worst(res.family)
    res.verification, res.verify_quantity, res.verify_error = v, q, err
    res.passed = bool(v.ok and math.isfinite(err) and err <= res.tolerance)
    measure_task(tc, eng, {})  # warm: the first runs in this process import and cache
    tuned, recd = [], []
    for _ in range(TIMING_REPEATS):
        r = measure_task(tc, eng, {})
        recd.append(r.cpu / r.units)
        t = measure_task(tc, eng, over)
        tuned.append(t.cpu / t.units)
    res.cpu_tuned, res.cpu_recommended = statistics.median(tuned), statistics.median(recd)
    res.cpu_ratio = res.cpu_tuned / res.cpu_recommended if res.cpu_recommended > 0 \
        else math.nan
    res.cpu_spread = max((max(x) - min(x)) / statistics.median(x) for x in (tuned, recd)
                         if statistics.median(x) > 0)


__all__ = ["MAX_BUDGET", "MAX_TOLERANCE", "MIN_BUDGET", "MIN_TOLERANCE", "Sensitivity",
           "TuneInputError", "TuneResult", "check_inputs", "front", "knob_text",
           "limit_text", "retarget", "sensitivities", "tune"]
