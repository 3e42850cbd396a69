"""The search of ``xval tune``: the cheapest settings of one engine whose verdict passes
at a stated tolerance, over measured runs.

Method (every point is a run, :func:`reports.tune.measure.measure_task`, submitted in
waves through the studies' executor):

1. **Step search per family** (:meth:`Tuner.step_search`): a family is one level of
   each discrete knob; its step is searched as steps per revolution (prescribed) or per
   simulated second (free), from the current best's step count: halving or doubling
   until a pass and a failure bracket the least passing count, then bisection in
   log(steps) to :data:`STEP_RESOLUTION`.  The search of a family stops early when the
   step stops mattering (halving it changes the worst error by less than
   :data:`STEP_MATTERS`: the error floor is another knob's) and when the family cannot
   beat the best found (branch and bound on the cost model).
2. **Screening**: one knob at a time moved from the recommended family (each other
   level, step searched); a knob whose levels change neither the error at the same
   step by :data:`ERROR_MATTERS` nor the per-step cost by :data:`COST_MATTERS` has
   stopped mattering and keeps its recommended level.
3. **Refinement along the Pareto front**: coordinate descent from the cheapest passing
   family over the knobs that matter (each other level of one knob at a time, step
   searched, bounded by the best cost) until a round improves nothing.

Everything stops when the CPU spent by the runs reaches the budget.

Cost model (deterministic, for ranking): a family's per-step CPU is the median over
its runs of run CPU / steps; a candidate's cost is that times its steps per unit
(revolution or simulated second).  Families whose per-step costs lie within
:data:`COST_CLASS` (25 %, above the timing noise on this shared machine) of each other
share one cost class; candidates are ranked by class cost x steps, then by fewer
steps, then by the lower error, then by the knobs' declared order, so a rerun with the
same seed and budget gives the same answer unless a family's per-step cost sits at a
class edge.  The answer (:meth:`Tuner.best`) is the candidate with the fewest steps, then
the fewest knobs moved, among those within :data:`COST_TIE` of the least model cost.
"""

from __future__ import annotations

import math
import random
import statistics
from dataclasses import dataclass, field

from reports.tune.measure import Measured, TuneCase, measure_task, unit_time
from reports.tune.space import Knob, finalize, steps_overrides

#: Stop bisecting the step when the least passing and the largest failing step counts
#: are within this factor (2**0.25: a step found to within 19 %).
STEP_RESOLUTION = 2 ** 0.25
#: The step stops mattering when doubling the steps leaves the worst error above this
#: fraction of what it was (a first-order method halves it, RK4 divides it by 16).
STEP_MATTERS = 0.7
#: A knob matters for the error when one of its levels changes the worst error at the
#: same step by this factor or more.
ERROR_MATTERS = 2.0
#: ... or for the cost when it changes the per-step CPU by 25 % or more.
COST_MATTERS = 1.25
#: Families whose per-step costs are within this factor share a cost class (ranking).
COST_CLASS = 1.25
#: Candidates whose model costs are within this factor of the least are equally cheap
#: (the per-step timings of one family spread by about 5 % on this shared machine).
COST_TIE = 1.15
#: Branch and bound: a family is searched on while it might cost less than this factor
#: times the best found.
COST_BIN = 1.1
#: Runs of a family that also time its bare stepping loop (the cost model's per-step
#: cost is their median).
TIMED_PER_FAMILY = 2
#: Most doublings of the steps above the recommended count (a family needing more is
#: out of reach: 2**6 = 64 times the recommended cost, minutes of runs).
MAX_DOUBLINGS = 6


@dataclass(frozen=True)
class Point:
    """A measured candidate: its family (one level label per knob), steps per unit, the
    run, its worst error over the judged family and whether it passes."""

    family: tuple[str, ...]
    steps: int
    m: Measured
    worst_quantity: str
    error: float
    passed: bool


@dataclass
class FamilyResult:
    """A family's step search: the least passing step count (None: none found) and why
    the search stopped."""

    family: tuple[str, ...]
    steps: int | None
    stop: str


@dataclass
class Search:
    """State and outcome of one search."""

    points: dict = field(default_factory=dict)        # (family, steps) -> Point
    spent: float = 0.0                                 # CPU s of the runs
    runs: int = 0
    budget_hit: bool = False
    families: dict = field(default_factory=dict)       # family -> FamilyResult
    not_mattering: list = field(default_factory=list)  # knob names
    mattering: list = field(default_factory=list)
    not_tried: list = field(default_factory=list)      # knobs the budget left unscreened


class Tuner:
    """One search (see the module docstring).  ``ex``: an executor (the studies'
    :func:`reports.studies.speed_accuracy.executor`); ``wave``: runs submitted at once."""

    def __init__(self, tc: TuneCase, engine: str, tolerance: float, family: str | None,
                 budget: float, knobs: tuple[Knob, ...], ex, wave: int = 2, seed: int = 0,
                 fields=()):
        self.tc, self.engine, self.tol, self.qfamily = tc, engine, tolerance, family
        self.budget, self.knobs, self.ex = budget, knobs, ex
        self.wave = max(2, int(wave))
        self.rng = random.Random(seed)
        self.fields = tuple(fields)
        self.unit = unit_time(tc)
        self.s = Search()
        self.rec_family = tuple(k.levels[0] for k in knobs)
        # the step range the settings accept: timestep within sim_models.engines.ranges.TIMESTEP
        from sim_models.engines.ranges import MAX_TIMESTEP, MIN_TIMESTEP
        self.min_steps = max(1, math.ceil(self.unit / MAX_TIMESTEP))
        self.max_steps = int(self.unit / MIN_TIMESTEP)
        self.rec_steps: int | None = None

    # ------------------------------------------------------------------ runs
    def overrides(self, family: tuple[str, ...], steps: int | None) -> dict:
        over: dict = {}
        for k, lv in zip(self.knobs, family, strict=True):
            over.update(k.apply(lv))
        if steps is not None:
            over.update(steps_overrides(self.engine, steps, self.unit, self.fields))
        return finalize(over)

    def left(self) -> float:
        return self.budget - self.s.spent

    def evaluate(self, batch) -> list[Point]:
        """Run the ``(family, steps)`` not yet measured, in parallel; all of them back."""
        todo = []
        timed = {}
        for fam, n in dict.fromkeys(batch):
            if (fam, n) not in self.s.points:
                if self.left() <= 0:
                    self.s.budget_hit = True
                    continue
                # the first TIMED_PER_FAMILY runs of a family also time its bare loop
                k = timed.setdefault(fam, self._timings(fam))
                timed[fam] = k + 1
                todo.append((fam, n, self.ex.submit(measure_task, self.tc, self.engine,
                                                    self.overrides(fam, n),
                                                    k < TIMED_PER_FAMILY)))
        for fam, n, f in todo:
            try:
                m = f.result()
            except Exception as e:  # noqa: BLE001 - a worker lost is a failed point
                m = Measured(self.overrides(fam, n), False, f"task failed: {e}")
            self.s.runs += 1
            self.s.spent += m.task_cpu
            q, err = m.worst(self.qfamily)
            passed = bool(m.ok and math.isfinite(err) and err <= self.tol)
            # the steps the run took: a run shortens its step so that every sample
            # falls on one (36 samples a revolution: 39 steps asked become 72)
            actual = int(round(m.unit_steps)) if math.isfinite(m.unit_steps) and \
                m.unit_steps > 0 else n
            self.s.points[(fam, n)] = Point(fam, actual, m, q, err, passed)
        return [self.s.points[x] for x in batch if x in self.s.points]

    def recommended(self) -> Point:
        """The recommended settings' run (its steps per unit start every step search)."""
        (p,) = self.evaluate([(self.rec_family, None)]) or (None,)
        if p is None:
            raise RuntimeError("no budget for the recommended run")
        n = p.m.unit_steps
        self.rec_steps = int(round(n)) if math.isfinite(n) and n > 0 else 1000
        return p

    # ------------------------------------------------------------------ cost model
    def _timings(self, family) -> int:
        return sum(1 for (f, _n), p in self.s.points.items()
                   if f == family and math.isfinite(p.m.step_cost))

    def step_cost(self, family) -> float:
        """Median s per step of the family's bare-loop timings; without one, of its
        runs' CPU per step (NaN: no finished run)."""
        v = [p.m.step_cost for (f, _n), p in self.s.points.items()
             if f == family and math.isfinite(p.m.step_cost)]
        if not v:
            v = [p.m.cpu / p.m.steps for (f, _n), p in self.s.points.items()
                 if f == family and p.m.ok and p.m.steps > 0 and math.isfinite(p.m.cpu)]
        return statistics.median(v) if v else math.nan

    def cost(self, p: Point) -> float:
        """Model CPU s per unit (revolution or simulated second)."""
        c = self.step_cost(p.family)
        return c * p.m.unit_steps if math.isfinite(c) else math.inf

    def class_cost(self, family) -> float:
        """The per-step cost of the family's cost class: families are sorted by their
        per-step cost and one within :data:`COST_CLASS` of the cheapest of a class joins
        it, taking that cheapest cost (timing noise then cannot reorder families whose
        steps cost the same, e.g. two solref levels of one integrator)."""
        costs = sorted((c, f) for f in {f for (f, _n) in self.s.points}
                       if math.isfinite(c := self.step_cost(f)))
        head = math.nan
        for c, f in costs:
            if not (c <= head * COST_CLASS):
                head = c
            if f == family:
                return head
        return math.inf

    def rank_key(self, p: Point):
        order = tuple(k.levels.index(lv) for k, lv in zip(self.knobs, p.family, strict=True))
        return (self.class_cost(p.family) * p.m.unit_steps, p.steps, p.error, order)

    def passing(self) -> list[Point]:
        return sorted((p for p in self.s.points.values() if p.passed and p.steps is not None),
                      key=self.rank_key)

    def best(self) -> Point | None:
        """The answer: among the passing candidates whose model cost is within
        :data:`COST_TIE` of the least (timing noise cannot order them), the one with the
        fewest steps, then the fewest knobs moved from the recommended levels, then the
        lower error."""
        ps = self.passing()
        if not ps:
            return None
        least = min(self.cost(p) for p in ps)
        tie = [p for p in ps if self.cost(p) <= least * COST_TIE]
        return min(tie, key=lambda p: (p.steps, self.moved(p), p.error, self.rank_key(p)))

    def moved(self, p: Point) -> int:
        """How many knobs ``p`` moves from their recommended levels."""
        return sum(lv != r for lv, r in zip(p.family, self.rec_family, strict=True))

    # ------------------------------------------------------------------ step search
    def step_search(self, family, start: int, cost_cap: float = math.inf) -> FamilyResult:
        """The least passing steps of ``family`` (see the module docstring)."""
        hi_cap = min(self.max_steps, (self.rec_steps or start) * 2 ** MAX_DOUBLINGS)
        start = min(max(start, self.min_steps), hi_cap)
        nxt = [start, max(self.min_steps, int(round(start / 2)))]
        while True:
            if all((family, n) in self.s.points for n in nxt):
                best = min((p.steps for (f, n), p in self.s.points.items()
                            if f == family and n is not None and p.passed), default=None)
                return self._done(family, "step resolved (the samples set the steps)",
                                  best)
            self.evaluate([(family, n) for n in nxt])
            if self.s.budget_hit:
                return self._done(family, "budget reached")
            mine = sorted(((p.steps, p) for (f, n), p in self.s.points.items()
                           if f == family and n is not None), key=lambda x: x[0])
            passes = [n for n, p in mine if p.passed]
            c = self.step_cost(family)
            if not passes:
                stop = self._why_no_pass(family, mine, hi_cap, c, cost_cap)
                if stop:
                    return self._done(family, stop)
                top = mine[-1][0]
                nxt = [n for n in (min(hi_cap, top * 2), min(hi_cap, top * 4)) if n > top]
                continue
            P = min(passes)
            fails = [n for n, p in mine if n < P]
            if not fails:
                if P <= self.min_steps:
                    return self._done(family, "coarsest step accepted", P)
                nxt = [max(self.min_steps, int(round(P / 2))),
                       max(self.min_steps, int(round(P / 4)))]
                continue
            F = max(fails)
            if math.isfinite(c) and c * F > cost_cap:
                return self._done(family, "cannot beat the best found (cost bound)", P)
            if P / F <= STEP_RESOLUTION or P - F <= 1:
                return self._done(family, "step resolved", P)
            k = self.wave
            nxt = sorted({int(round(F * (P / F) ** (i / (k + 1)))) for i in range(1, k + 1)}
                         - {F, P})
            if not nxt:
                return self._done(family, "step resolved", P)

    def _why_no_pass(self, family, mine, hi_cap, c, cost_cap) -> str | None:
        top, p_top = mine[-1]
        if top >= hi_cap:
            return (f"no pass up to {top} steps per unit ({2 ** MAX_DOUBLINGS}x the "
                    "recommended steps)" if hi_cap < self.max_steps
                    else f"no pass at the smallest step the settings accept ({top} steps)")
        if math.isfinite(c) and c * top > cost_cap:
            return "cannot beat the best found (cost bound)"
        if len(mine) >= 2:
            (n1, p1), (n2, p2) = mine[-2], mine[-1]
            if n2 >= 1.9 * n1 and p1.m.ok and p2.m.ok and math.isfinite(p1.error) \
                    and p1.error > 0 and p2.error / p1.error > STEP_MATTERS:
                return (f"the step stopped mattering: {n1} -> {n2} steps changes the worst "
                        f"error {p1.error:.2g} -> {p2.error:.2g}")
        return None

    def _done(self, family, stop: str, steps: int | None = None) -> FamilyResult:
        r = FamilyResult(family, steps, stop)
        self.s.families[family] = r
        return r

    # ------------------------------------------------------------------ the search
    def run(self) -> Search:
        self.recommended()
        self.step_search(self.rec_family, self.rec_steps)
        self.screen()
        self.refine()
        return self.s

    def _neighbours(self, base, knob_indices):
        out = []
        for i in knob_indices:
            lvls = [lv for lv in self.knobs[i].levels if lv != base[i]]
            self.rng.shuffle(lvls)  # the seed orders the waves, not the answer
            for lv in sorted(lvls, key=self.knobs[i].levels.index):
                out.append((i, base[:i] + (lv,) + base[i + 1:]))
        return out

    def _start_and_cap(self):
        b = self.best()
        if b is None:
            return self.rec_steps, math.inf
        return b.steps, self.cost(b) * COST_BIN

    def screen(self) -> None:
        """One knob at a time from the recommended family; knobs that change neither the
        error nor the per-step cost are dropped (:attr:`Search.not_mattering`)."""
        base = self.rec_family
        ref_err = {p.steps: p.error for (f, _n), p in self.s.points.items() if f == base}
        matters, tried = set(), set()
        for i, fam in self._neighbours(base, range(len(self.knobs))):
            if self.left() <= 0:
                self.s.budget_hit = True
                break
            start, cap = self._start_and_cap()
            self.step_search(fam, start, cap)
            tried.add(i)
            if self._differs(fam, base, ref_err):
                matters.add(i)
        self.s.mattering = [self.knobs[i].name for i in sorted(matters)]
        self.s.not_mattering = [k.name for i, k in enumerate(self.knobs)
                                if i in tried and i not in matters]
        self.s.not_tried = [k.name for i, k in enumerate(self.knobs) if i not in tried]
        self._matters = sorted(matters)

    def _differs(self, fam, base, ref_err) -> bool:
        cb, cf = self.step_cost(base), self.step_cost(fam)
        if math.isfinite(cb) and math.isfinite(cf) and cb > 0 and \
                max(cb, cf) / min(cb, cf) >= COST_MATTERS:
            return True
        for (f, _n), p in self.s.points.items():
            if f == fam and p.steps in ref_err:
                a, b = p.error, ref_err[p.steps]
                if not (math.isfinite(a) and math.isfinite(b)):
                    if math.isfinite(a) != math.isfinite(b):
                        return True
                    continue
                if a > 0 and b > 0 and max(a, b) / min(a, b) >= ERROR_MATTERS:
                    return True
        return False

    def refine(self) -> None:
        """Coordinate descent from the cheapest passing family over the knobs that
        matter, first trying the combination of each knob's best screened level."""
        b = self.best()
        if b is None or not getattr(self, "_matters", None):
            return
        combo = list(b.family)
        for i in self._matters:
            lv_best = min((p for p in self.passing()
                           if all(p.family[j] == self.rec_family[j]
                                  for j in range(len(self.knobs)) if j != i)),
                          key=self.rank_key, default=None)
            if lv_best is not None:
                combo[i] = lv_best.family[i]
        combo = tuple(combo)
        if combo not in self.s.families and self.left() > 0:
            start, cap = self._start_and_cap()
            self.step_search(combo, start, cap)
        improved = True
        while improved and self.left() > 0:
            improved = False
            cur = self.best()
            for _i, fam in self._neighbours(cur.family, self._matters):
                if fam in self.s.families:
                    continue
                if self.left() <= 0:
                    self.s.budget_hit = True
                    return
                start, cap = self._start_and_cap()
                self.step_search(fam, start, cap)
            if self.best().family != cur.family or self.best().steps != cur.steps:
                improved = True


__all__ = ["COST_BIN", "COST_CLASS", "COST_TIE", "ERROR_MATTERS", "FamilyResult", "Point",
           "STEP_MATTERS", "STEP_RESOLUTION", "Search", "Tuner"]
