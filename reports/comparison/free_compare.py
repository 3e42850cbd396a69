"""Judging a free trajectory: one engine's free run against the exact trajectory.

An engine released from the exact state integrates on its own, so its error grows with
time (phase error) for any integrator; a verdict on free motion says what it judges:

* per quantity (every joint coordinate and rate, every moving body's angle, rate and
  acceleration, every joint reaction) the error at the same sample times, **normalised
  by the quantity's range over the run** (max minus min of the reference; for a vector,
  the norm of the per-component ranges), with the time of its maximum; a quantity whose
  range is below :data:`reports.comparison.compare.ZERO_PEAK` of its family's scale (a reaction
  that stays constant, a body that does not turn) is judged on the family's scale
  instead, and says so in ``normalisation``; a rate, acceleration or reaction is never
  judged on less than its family's **floor** (:func:`family_floor`): the family's peak
  magnitude times :data:`analytic.tolerances.ENGINE_RELATIVE` over the tolerance (an error
  within the prescribed runs' pointwise 1e-3 of the peak always passes: over a run of
  1e-6 s every range is ~1e-10 of the value, and dividing by it judges round-off), or,
  for a family that is identically zero over the run (a release at rest with nothing to
  move it), the scale its coordinates' family implies over the run's duration T (the
  angles' scale / T for a rate, / T^2 for an acceleration, times the moving mass and the
  size for a reaction), never 0;
* the **trusted horizon**: the first time each quantity's normalised error exceeds its
  tolerance (linear between samples; ``inf`` when it never does);
* the energy drift (engine total energy minus the reference's, over the energy scale
  ``max KE + range of PE`` of the reference) and the loop-closure drift (the largest gap
  at the cut joints over the mechanism's size), over time;
* for the IFToMM benchmark problems, the accuracy rule: the reference point's position
  error over the run against 1e-1 m and 1e-3 m
  (:func:`reports.comparison.iftomm.iftomm_accuracy`).

A failed verdict names the reference event (coordinate switch, singular position,
limit position) nearest to where the trust was lost, and the engine's step in time and
in the coordinate.  Results are frozen dataclasses (:class:`FreeComparison`,
:class:`reports.comparison.iftomm.IftommAccuracy`, :class:`FreeVerdict`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from analytic.mechanism import Revolute, mechanism_size
from analytic.tolerances import ENGINE_RELATIVE
from reports.comparison.compare import ZERO_PEAK, json_safe
from reports.comparison.free_advice import free_step_note, near_free_event
from reports.comparison.iftomm import IftommAccuracy, iftomm_accuracy

# --- tolerances (each relative to the scale named in FreeComparison.normalisation) ---

#: Joint coordinates and rates, body angles and rates, over their range in the run.  A
#: free run accumulates phase error, so the prescribed runs' pointwise 1e-3
#: (analytic.tolerances.ENGINE_RELATIVE) is not a property any fixed-step engine keeps
#: for seconds; 1e-2 of the range is the offset a person sees on a plotted trajectory
#: (one line width on a 10 cm axis), and the trusted horizon says when it is lost.
FREE_KINEMATIC = 1e-2
#: Body accelerations and joint reactions, over their range.  Constraint stabilisation
#: (MuJoCo's soft equalities, PyBullet's ERP, Exudyn's index-3 projection) acts on the
#: accelerations and reactions directly each step and on the positions only through two
#: integrations, so their error runs several times that of the positions they produce:
#: five times the kinematic tolerance.
FREE_DYNAMIC = 5e-2
#: Energy drift: |E_engine - E_reference| over the energy scale (max KE + range of PE of
#: the reference).  1e-2 is the same 1 % as the kinematic tolerance: an energy off by
#: more changes the amplitude of a swing by more than the kinematic tolerance allows.
ENERGY_DRIFT = 1e-2
#: Loop-closure drift: the largest gap at the cut joints over the mechanism's size
#: (its longest in-body point distance).  1e-3: a gap of a tenth of a percent of the
#: size moves a joint by a tenth of the kinematic tolerance; the engines' run ends at
#: sim_models.runs.free_run.FreeRequest.max_gap (1e-2), ten times more.
LOOP_DRIFT = 1e-3


@dataclass(frozen=True)
class FreeComparison:
    """One quantity of a free run against the reference.

    ``quantity``: e.g. ``"G0.x"`` (joint coordinate), ``"G0.xd"``, ``"crank.theta"``,
    ``"crank.omega"``, ``"crank.alpha"``, ``"G0.force"`` (vector), ``"energy"``,
    ``"loop.gap"``.  ``family``: ``coordinate``, ``rate``, ``angle``, ``angular rate``,
    ``angular acceleration``, ``reaction``, ``energy``, ``loop``.  ``unit``: the SI unit
    of ``max_abs`` and ``scale``.  ``max_abs``: the largest absolute error over the
    measured samples; ``scale``: what it is divided by, named in ``normalisation``;
    ``normalised = max_abs / scale``; ``at``: the time of the maximum, s;
    ``horizon``: the first time the normalised error exceeds ``tolerance`` (``inf``:
    never within the measured run); ``measured_until``: the last sample time with a
    finite engine value (the run's duration unless the run stopped); ``error``: the
    normalised error at each sample (NaN where not measured); ``unread``: samples before
    ``measured_until`` with no engine value (an engine that cannot read the quantity
    there, such as PyBullet's accelerations at t = 0), left out of the maximum."""

    quantity: str
    family: str
    unit: str
    max_abs: float
    scale: float
    normalisation: str
    normalised: float
    at: float
    tolerance: float
    horizon: float
    measured_until: float
    duration: float
    error: np.ndarray = field(repr=False, compare=False)
    unread: int = 0

    @property
    def measured(self) -> bool:
        """True when the engine has a value at every sample (the run did not stop)."""
        return self.measured_until >= self.duration

    @property
    def passed(self) -> bool:
        """Within tolerance over the whole run (a run that stopped early fails)."""
        return self.measured and self.normalised <= self.tolerance

    def as_json(self) -> dict:
        """For JSON: non-finite numbers as null; ``horizon`` null means never exceeded."""
        return json_safe({"quantity": self.quantity, "family": self.family,
                          "unit": self.unit, "max_abs": self.max_abs, "scale": self.scale,
                          "normalisation": self.normalisation,
                          "normalised": self.normalised, "at_s": self.at,
                          "tolerance": self.tolerance, "horizon_s": self.horizon,
                          "measured_until_s": self.measured_until, "unread": self.unread,
                          "measured": self.measured, "passed": self.passed})

    def __str__(self) -> str:
        verdict = "pass" if self.passed else "FAIL"
        hz = "never exceeded" if math.isinf(self.horizon) else f"exceeded from {self.horizon:.4g} s"
        stop = "" if self.measured else f"; not measured from {self.measured_until:.4g} s on"
        if self.unread:
            stop += f"; {self.unread} sample(s) not read by the engine"
        return (f"{self.quantity}: max error {self.max_abs:.3g} {self.unit} at {self.at:.4g} s "
                f"({self.normalised:.3g} of {self.normalisation} {self.scale:.4g}; tolerance "
                f"{self.tolerance:g}, {hz}{stop}) {verdict}")


def horizon_of(times: np.ndarray, error: np.ndarray, tolerance: float) -> float:
    """The first time ``error`` (normalised, per sample) exceeds ``tolerance``, linear
    between the last sample within it and the first beyond; 0 when the first sample is
    beyond; ``inf`` when no finite sample is.  A NaN sample (not measured) is not an
    excess: the measured span is reported apart (``measured_until``)."""
    over = np.flatnonzero(np.nan_to_num(error, nan=-1.0) > tolerance)
    if not over.size:
        return math.inf
    k = int(over[0])
    if k == 0:
        return float(times[0])
    e0, e1 = float(error[k - 1]), float(error[k])
    t0, t1 = float(times[k - 1]), float(times[k])
    if not math.isfinite(e0):
        return t1
    return t0 + (t1 - t0) * (tolerance - e0) / (e1 - e0)


def _range(ref: np.ndarray) -> float:
    """The range of a quantity over the run: max - min, for vectors the norm of the
    per-component ranges."""
    if not len(ref) or not np.isfinite(ref).any():
        return 0.0
    with np.errstate(invalid="ignore"):  # a reaction the reference leaves NaN (singular)
        r = np.nanmax(ref, axis=0) - np.nanmin(ref, axis=0)
    return float(np.linalg.norm(np.nan_to_num(np.atleast_1d(r))))


def judge(quantity: str, family: str, unit: str, times, reference, test, tolerance: float,
          family_scale: float, scale: float | None = None,
          normalisation: str = "range over the run",
          floor: tuple[float, str] | None = None) -> FreeComparison:
    """Compare ``test`` with ``reference`` at ``times`` (arrays ``(N,)`` or ``(N, k)``).

    The scale is ``scale`` when given (named by ``normalisation``), else the reference's
    range over the run, or ``family_scale`` when that range is at most
    :data:`reports.comparison.compare.ZERO_PEAK` of it (a quantity that does not change);
    never less than ``floor`` (``(value, its name)``: :func:`family_floor`)."""
    t = np.asarray(times, float)
    ref = np.asarray(reference, float)
    tst = np.asarray(test, float)
    if ref.shape != tst.shape:
        raise ValueError(f"{quantity}: reference shape {ref.shape} != test shape {tst.shape}")
    err = np.abs(ref - tst) if ref.ndim == 1 else \
        np.linalg.norm((ref - tst).reshape(len(ref), -1), axis=1)
    if scale is None:
        own = _range(ref)
        if own > ZERO_PEAK * family_scale:
            scale = own
        else:
            scale, normalisation = family_scale, f"{family} scale (own range {own:.3g})"
        if floor is not None and floor[0] > scale:
            scale, normalisation = floor[0], f"{floor[1]} (own range {own:.3g})"
    finite = np.isfinite(err)
    # trailing NaN rows: the run stopped (not measured from there on); a NaN before the
    # last finite sample is a value the engine does not read there (PyBullet's
    # accelerations at t = 0, from the last velocities): counted, not a stop
    idx = np.flatnonzero(finite)
    measured_until = float(t[idx[-1]]) if idx.size else float("-inf")
    unread = int(np.count_nonzero(~finite[:idx[-1] + 1])) if idx.size else 0
    with np.errstate(divide="ignore", invalid="ignore"):
        norm = err / scale if scale > 0 else np.where(err == 0, 0.0, np.inf)
    if finite.any():
        k = int(np.nanargmax(np.where(finite, err, -1.0)))
        max_abs, at = float(err[k]), float(t[k])
    else:
        max_abs, at = math.inf, float(t[0]) if len(t) else math.nan
    normalised = max_abs / scale if scale > 0 else (0.0 if max_abs == 0 else math.inf)
    return FreeComparison(quantity, family, unit, max_abs, float(scale), normalisation,
                          normalised, at, tolerance, horizon_of(t, norm, tolerance),
                          measured_until, float(t[-1]) if len(t) else 0.0, norm, unread)


@dataclass(frozen=True)
class FreeVerdict:
    """One engine's free run judged: every :class:`FreeComparison` (``comparisons``:
    the judged quantities; ``energy`` and ``loop`` the drifts), the IFToMM accuracy
    where the case is a benchmark problem, the run's own end, and for a failed verdict
    the nearest reference event and the engine's step (``near_event``, ``step_note``)."""

    case: str
    engine: str
    duration: float
    times: np.ndarray = field(repr=False, compare=False)
    comparisons: tuple[FreeComparison, ...]
    energy: FreeComparison
    loop: FreeComparison
    iftomm: IftommAccuracy | None
    run_ok: bool
    reason: str | None
    t_fail: float | None
    cpu_per_simulated_second: float
    timestep: float
    integrator: str
    settings: str
    near_event: str | None
    step_note: str | None
    #: quantities the engine does not read at all (no value at any sample of a run that
    #: did not stop): reported, not judged
    not_read: tuple[str, ...] = ()
    #: whether the mechanism has a loop (a pendulum has none: no loop drift to report)
    has_loop: bool = True

    @property
    def judged(self) -> tuple[FreeComparison, ...]:
        """Everything the verdict judges: the quantities and both drifts."""
        return (*self.comparisons, self.energy, self.loop)

    @property
    def passed(self) -> bool:
        return self.run_ok and all(c.passed for c in self.judged)

    @property
    def worst(self) -> FreeComparison:
        """The judged quantity furthest beyond (or nearest to) its tolerance."""
        return max(self.judged, key=_badness)

    @property
    def horizon(self) -> float:
        """The trusted horizon of the run: the earliest excess of any judged quantity
        (``inf``: none within the measured run), or where the run stopped if earlier."""
        h = min(c.horizon for c in self.judged)
        stop = min(c.measured_until for c in self.judged)
        return min(h, stop) if stop < self.duration else h

    @property
    def lost_by(self) -> FreeComparison | None:
        """The judged quantity whose error exceeds its tolerance first (None: none)."""
        first = min(self.judged, key=lambda c: c.horizon)
        return None if math.isinf(first.horizon) else first

    def as_json(self) -> dict:
        return json_safe({
            "case": self.case, "engine": self.engine, "duration_s": self.duration,
            "verdict": "pass" if self.passed else "fail", "run_ok": self.run_ok,
            "reason": self.reason, "t_fail_s": self.t_fail,
            "trusted_horizon_s": self.horizon,
            "lost_by": self.lost_by.quantity if self.lost_by else None,
            "worst": self.worst.quantity,
            "worst_normalised": self.worst.normalised,
            "energy_drift": self.energy.normalised,
            "loop_drift": self.loop.normalised if self.has_loop else None,
            "cpu_per_simulated_second": self.cpu_per_simulated_second,
            "timestep": self.timestep, "integrator": self.integrator,
            "settings": self.settings, "near_event": self.near_event,
            "step_note": self.step_note, "not_read": list(self.not_read),
            "iftomm": self.iftomm.as_json() if self.iftomm else None,
            "comparisons": [c.as_json() for c in self.judged]})


def _badness(c: FreeComparison) -> float:
    if not c.measured or not math.isfinite(c.normalised):
        return math.inf
    return c.normalised / c.tolerance


def _align_turns(ref: np.ndarray, test: np.ndarray) -> np.ndarray:
    """``test`` (angles, rad, continuous) shifted by the whole turns that make its first
    finite sample nearest the reference's: both start from the same state, so a
    difference of 2 pi k at t = 0 is a convention, not an error."""
    k = np.round((ref[0] - test[0]) / (2 * np.pi))
    return test + 2 * np.pi * np.where(np.isfinite(k), k, 0.0)


def _unwrap(a: np.ndarray) -> np.ndarray:
    """A reference angle made continuous over turns (the solver's body angles may wrap);
    the samples are far denser than half a turn per sample in every run judged."""
    return np.unwrap(a, axis=0)


def _family(out: list, family: str, unit: str, t, pairs, tol: float,
            not_read: list | None = None, still: float | None = None) -> float:
    """Append the comparisons of one family ``(name, ref, test)``; its scale is its
    largest range (for a family that does not change at all: the largest magnitude).
    With ``not_read`` (a run that did not stop): a quantity with no engine value at any
    sample is one the engine does not read (Exudyn's prismatic joint forces): named
    there, not judged.  ``still``: a family of physical magnitudes (rates,
    accelerations, reactions), judged on no less than :func:`family_floor`, ``still``
    being its scale when the whole family is identically zero.  Returns the family's
    scale (the floor where that is larger)."""
    if not_read is not None:
        gone = [n for n, _, x in pairs if not np.isfinite(x).any()]
        not_read += gone
        pairs = [p for p in pairs if p[0] not in gone]
    ranges = [_range(r) for _, r, _ in pairs]
    fam = max(ranges, default=0.0)
    peak = max((float(np.nanmax(np.abs(r))) for _, r, _ in pairs
                if np.isfinite(r).any()), default=0.0)
    if fam == 0.0:
        fam = peak
    floor = None if still is None else family_floor(family, peak, tol, still)
    for name, r, x in pairs:
        out.append(judge(name, family, unit, t, r, x, tol, fam, floor=floor))
    return max(fam, floor[0] if floor else 0.0)


def family_floor(family: str, peak: float, tol: float, still: float) -> tuple[float, str]:
    """The least scale a family of physical magnitudes (a rate, an acceleration, a
    reaction) is judged on, and its name: its largest magnitude over the run ``peak``
    times :data:`analytic.tolerances.ENGINE_RELATIVE` / ``tol`` (so that an error within
    the prescribed runs' pointwise tolerance of the peak passes whatever the run's
    length), or ``still`` (the scale the coordinates imply over the run, see
    :func:`_quantities`) when the family is identically zero."""
    if peak > 0 and math.isfinite(peak):
        k = ENGINE_RELATIVE / tol
        return peak * k, f"{family} floor ({k:g} of its peak {peak:.4g})"
    return still, f"at-rest {family} scale"


def reference_samples(traj, times, forces: bool = True):
    """The exact trajectory at a run's sample times (computed once per case and shared
    by every engine's verdict): :class:`analytic.free_motion.FreeSamples`."""
    t = np.clip(np.asarray(times, float), 0.0, traj.duration)
    return traj.at(t, forces=forces)


def energy_scale(ref) -> tuple[float, str]:
    """The energy scale of a run, J, and its name: the reference's largest kinetic
    energy plus the range of its potential energy (the energy that moves about); 1 J
    for a mechanism that neither moves nor changes height."""
    e = float(np.max(ref.kinetic) + np.ptp(ref.potential)) if len(ref.t) else 0.0
    if e > 0 and math.isfinite(e):
        return e, "energy scale (max KE + range of PE)"
    return 1.0, "1 J (the reference has no kinetic energy and no change of potential)"


def _quantities(run, ref, mech, not_read: list) -> list[FreeComparison]:
    t = run.times
    out: list[FreeComparison] = []
    nr = not_read if run.ok else None
    rev = {j.name: isinstance(j, Revolute) for j in mech.joints}
    ref_j = list(ref.joints)
    by_kind = {True: ([], []), False: ([], [])}
    for k, name in enumerate(run.joint_names):
        i = ref_j.index(name)
        xr, xe = ref.x[:, i], run.x[:, k]
        if rev[name]:
            xe = _align_turns(xr, xe)
        by_kind[rev[name]][0].append((f"{name}.x", xr, xe))
        by_kind[rev[name]][1].append((f"{name}.xd", ref.xd[:, i], run.xd[:, k]))
    T = float(t[-1] - t[0]) if len(t) > 1 and t[-1] > t[0] else 1.0  # s
    size = mechanism_size(mech.bodies) or 1.0
    for revolute, (xs, xds) in by_kind.items():
        u = ("rad", "rad/s") if revolute else ("m", "m/s")
        fam = ("joint angle", "joint rate") if revolute else ("slider", "slider rate")
        if xs:
            x_scale = _family(out, fam[0], u[0], t, xs, FREE_KINEMATIC)
            _family(out, fam[1], u[1], t, xds, FREE_KINEMATIC, still=x_scale / T)
    names = [b.name for b in mech.bodies]
    moving = [(k, b, names.index(b)) for k, b in enumerate(run.body_names) if b != mech.ground]
    a_scale = _family(out, "angle", "rad", t,
                      [(f"{b}.theta", _unwrap(ref.theta[:, i]),
                        _align_turns(_unwrap(ref.theta[:, i]), run.theta[:, k]))
                       for k, b, i in moving], FREE_KINEMATIC)
    _family(out, "angular rate", "rad/s", t,
            [(f"{b}.omega", ref.omega[:, i], run.omega[:, k]) for k, b, i in moving],
            FREE_KINEMATIC, still=a_scale / T)
    alpha_scale = _family(out, "angular acceleration", "rad/s^2", t,
                          [(f"{b}.alpha", ref.alpha[:, i], run.alpha[:, k])
                           for k, b, i in moving], FREE_DYNAMIC, nr, still=a_scale / T ** 2)
    if ref.reactions:
        # the force that gives the moving mass the angular acceleration scale at the size
        mass = sum(b.mass or 0.0 for b in mech.moving_bodies) or 1.0
        _family(out, "reaction", "N", t,
                [(f"{n}.force", ref.reactions[n], run.joint_force[:, k])
                 for k, n in enumerate(run.joint_names) if n in ref.reactions],
                FREE_DYNAMIC, nr, still=mass * size * alpha_scale)
    return out


def compare_free(run, traj, ref=None) -> FreeVerdict:
    """Judge :class:`sim_models.runs.free_run.FreeEngineRun` ``run`` against the exact
    trajectory ``traj`` (:class:`analytic.free_motion.FreeTrajectory`; ``ref``: its
    :func:`reference_samples` at the run's times when already computed)."""
    mech = traj.mech
    ref = reference_samples(traj, run.times) if ref is None else ref
    t = np.asarray(run.times, float)
    not_read: list[str] = []
    comps = _quantities(run, ref, mech, not_read)
    e_scale, e_name = energy_scale(ref)
    energy = judge("energy", "energy", "J", t, ref.kinetic + ref.potential,
                   np.asarray(run.kinetic) + np.asarray(run.potential), ENERGY_DRIFT,
                   e_scale, scale=e_scale, normalisation=e_name)
    size = mechanism_size(mech.bodies) or 1.0
    loop = judge("loop.gap", "loop", "m", t, np.zeros(len(t)), run.loop_gap, LOOP_DRIFT,
                 size, scale=size, normalisation="mechanism size")
    v = FreeVerdict(run.case, run.engine, float(t[-1]) if len(t) else 0.0, t, tuple(comps),
                    energy, loop, iftomm_accuracy(run, ref, mech), bool(run.ok), run.reason,
                    run.t_fail, float(run.cpu_per_simulated_second), float(run.timestep),
                    str(run.integrator), settings_text(run), None, None,
                    tuple(not_read), len(mech.joints) > len(mech.bodies) - 1)
    if v.passed:
        return v
    return replace(v, near_event=near_free_event(v, traj.events),
                   step_note=free_step_note(run, ref, mech))


def settings_text(run) -> str:
    """The run's settings line: the engine's settings, and where the step was chosen
    from the motion, that and why (:class:`sim_models.runs.free_step.StepChoice`)."""
    choice = getattr(run, "step_choice", None)
    text = run.settings.describe()
    return f"{text}; {choice.text}" if choice is not None else text


__all__ = ["ENERGY_DRIFT", "FREE_DYNAMIC", "FREE_KINEMATIC", "LOOP_DRIFT", "FreeComparison",
           "FreeVerdict", "compare_free", "energy_scale", "family_floor", "horizon_of",
           "judge", "reference_samples"]
