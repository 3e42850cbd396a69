"""One comparison helper shared by the tests and the report (cf. Drake's CompareMatrices).

Errors are normalised by the peak magnitude of the reference quantity over the
sampled cycle, so zero crossings do not blow them up.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd

from analytic import Linkage
from analytic.errors import LinkageError
from analytic.input_display import convention_of, display_input, format_input, input_number
from analytic.positions import size_of
from analytic.sweep import nearest_event
from analytic.tolerances import ENGINE_RELATIVE
from reports.comparison.quantities import engine_reading, is_engine_reading, judged
from reports.comparison.reference import MAX_CONDITION, analytic_reference
from sim_models.runs.sampling import near_limit


@dataclass(frozen=True)
class Comparison:
    """The diagnostic of one quantity: where and how far the test values stray.

    Attributes
    ----------
    quantity : str
        What was compared, e.g. ``"rocker.alpha"`` or ``"B.force"``.
    max_abs : float
        Largest absolute error over the samples (SI units of the quantity; for vectors
        the Euclidean norm of the error).
    peak : float
        Peak magnitude of the reference over the samples.
    normalised : float
        ``max_abs / peak`` (``inf`` when the test values hold NaN).
    at : float
        The input value (deg or m) where ``max_abs`` occurs.
    tolerance : float
        The normalised tolerance applied.
    passed : bool
        Within the tolerance.
    floor : float
        The engine's arithmetic error floor at ``at`` (normalised like ``normalised``;
        :meth:`sim_models.engines.settings.EngineSettings.error_floor`), 0.0 for float64.
    precision : str
        The engine's arithmetic (``"float64"``, ``"float32"``).
    """

    quantity: str
    max_abs: float
    peak: float
    normalised: float
    at: float
    tolerance: float
    passed: bool
    floor: float = 0.0
    precision: str = "float64"

    def as_dict(self) -> dict:
        return asdict(self)

    @property
    def limited(self) -> bool:
        """Over the tolerance but within the engine's arithmetic floor (a measured error):
        a precision limit of the engine, not a failure."""
        return (not self.passed) and self.measured and self.normalised <= self.floor

    @property
    def accepted(self) -> bool:
        """Passed, or a precision limit: what the verdict's exit status counts."""
        return self.passed or self.limited

    @property
    def status(self) -> str:
        """``"pass"``, ``"precision limit (float32)"`` or ``"FAIL"``."""
        if self.passed:
            return PASS
        return limit_word(self.precision) if self.limited else FAIL

    @property
    def measured(self) -> bool:
        """False when the test values were not finite at some sample (a failed run's
        samples after it stopped): ``max_abs`` and ``normalised`` are then ``inf``, a
        failure, not a measured error, and ``at`` is the first such sample."""
        return math.isfinite(self.max_abs)

    def as_json(self) -> dict:
        """:meth:`as_dict` for JSON (RFC 8259 has no infinity): ``max_abs`` and
        ``normalised`` are ``null`` where not measured, and ``measured`` says so."""
        d = json_safe(asdict(self))
        d["measured"] = self.measured
        d["judged"] = not is_engine_reading(self.quantity)  # an engine's own reading: no
        d["verdict"] = self.status
        return d

    def __str__(self) -> str:
        verdict = self.status
        if self.limited:
            verdict += f": within the {self.precision} floor {self.floor:.2g}"
        if not self.measured:
            return (f"{self.quantity}: not measured from {input_number(self.at)} on (no finite "
                    f"engine value there: the run stopped) {verdict}")
        return (f"{self.quantity}: max error {self.max_abs:.3g} at "
                f"{input_number(self.at)} "
                f"({self.normalised:.3g} of peak {self.peak:.4g}; tolerance "
                f"{self.tolerance:.1g}) {verdict}")


#: The verdict words: within tolerance, and not.
PASS, FAIL = "pass", "FAIL"


def limit_word(precision: str) -> str:
    """The verdict word of an error over the tolerance but within the engine's arithmetic
    floor: ``"precision limit (float32)"``."""
    return f"precision limit ({precision})"


def json_safe(obj):
    """``obj`` (dicts, lists, numbers, strings) with every non-finite float as ``None``:
    JSON (RFC 8259) has no NaN or infinity, and ``json.dumps`` would write ``Infinity``,
    which strict parsers reject."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_safe(v) for v in obj]
    return obj


def compare(quantity: str, reference, test, at, tolerance: float,
            peak_floor: float = 0.0) -> Comparison:
    """Compare ``test`` with ``reference`` sample by sample.

    Parameters
    ----------
    reference, test
        Arrays ``(N,)`` or ``(N, k)`` (vectors per sample, e.g. forces ``(N, 2)``).
    at
        ``(N,)`` input values labelling the samples (deg or m).
    tolerance
        Allowed ``max error / peak``.
    peak_floor
        Lower bound for the peak (a quantity identically zero is compared with this
        scale instead of its own round-off).
    """
    ref = np.asarray(reference, float)
    tst = np.asarray(test, float)
    if ref.shape != tst.shape:
        raise ValueError(f"{quantity}: reference shape {ref.shape} != test shape {tst.shape}")
    err = ref - tst
    if err.ndim > 1:
        err = np.linalg.norm(err.reshape(len(err), -1), axis=1)
        mag = np.linalg.norm(ref.reshape(len(ref), -1), axis=1)
    else:
        err, mag = np.abs(err), np.abs(ref)
    peak = max(float(np.max(mag)) if mag.size else 0.0, peak_floor)
    if not np.all(np.isfinite(err)):
        k = int(np.flatnonzero(~np.isfinite(err))[0])
        return Comparison(quantity, float("inf"), peak, float("inf"), float(at[k]),
                          tolerance, False)
    k = int(np.argmax(err)) if err.size else 0
    max_abs = float(err[k]) if err.size else 0.0
    norm = max_abs / peak if peak > 0 else (0.0 if max_abs == 0 else float("inf"))
    return Comparison(quantity, max_abs, peak, norm, float(np.asarray(at)[k]) if err.size
                      else float("nan"), tolerance, bool(norm <= tolerance))


# --- an engine run against the analytic solution ---------------------------------------

# MAX_CONDITION (samples near a limit position left out) and the analytic reference come
# from reports.comparison.reference, the one reference the verdicts and the figures share


def analytic_at(run_, linkage: Linkage | None = None):
    """The analytic kinematics (and forces, when the case has masses) at a run's samples,
    with the driver rates the engine was given: ``(linkage, kin, frc)``, of the
    compiled ``run_.linkage`` (or of ``linkage``, another one to compare with)."""
    return analytic_reference(run_, linkage)  # the one reference: figures read it too


#: A reference quantity whose peak is below this fraction of the mechanism's scale for
#: it is identically zero up to round-off, and is judged on that scale instead.
ZERO_PEAK = 1e-9


def _zero_floor(reference, scale: float) -> float:
    """The peak floor for :func:`compare`: ``scale`` when the reference is identically
    zero up to round-off (its peak at most :data:`ZERO_PEAK` of ``scale``), else 0."""
    return scale if float(np.max(np.abs(reference))) <= ZERO_PEAK * scale else 0.0


class NothingToCompare(LinkageError):
    """No sample of a run can be compared (every one unreached or at a limit position);
    the message says why.  The command line reports it like a refusal (status 2)."""


def compare_run(run_, *, linkage: Linkage | None = None, tolerance: float | None = None,
                max_condition: float = MAX_CONDITION) -> list[Comparison]:
    """Every compared quantity of an :class:`sim_models.engines.protocol.EngineRun`.

    The reference is the solution of ``run_.linkage``, the compiled analytic
    :class:`Linkage` the run was made from (nothing is rebuilt); ``linkage``: another
    Linkage to compare the run with instead (a study judging a run against a
    neighbouring description).  Quantities: ``<body>.alpha`` for each moving body
    (one whose exact alpha is identically zero, such as a constant-speed crank or a
    piston, is judged against the largest body's peak), ``<joint>.a`` for each slider,
    ``drive.effort``, ``<joint>.force`` for each joint (vector error), ``<joint>.normal`` and
    ``<joint>.moment`` for each prismatic joint, and, where the engine has its own
    reading, ``<joint>.force[engine]`` and ``drive.effort[engine]``.  ``at`` is in
    degrees for a revolute driver, m for a prismatic one.  A failed run's NaN samples
    make every quantity fail at the first such sample.  Raises
    :class:`NothingToCompare` when no sample is comparable.
    """
    tol = ENGINE_RELATIVE if tolerance is None else tolerance
    lk, kin, frc = analytic_at(run_, linkage)
    mech = lk.mech
    keep = ~near_limit(kin.condition, max_condition)
    if run_.ok:
        # a limited-range driver runs forward from its reference value only: samples
        # behind it are NaN by design (counted in ``skipped_samples``), not failures
        keep &= np.all(np.isfinite(run_.alpha), axis=1)
    if not keep.any():
        why = run_.reason or ("every sample is within a limit or singular position "
                              f"(loop condition number above {max_condition:g}) or unreached")
        raise NothingToCompare(f"{run_.case} / {run_.engine}: no sample can be compared: "
                               f"{why}")
    # the one display convention of an input (degrees in [0, 360) for a full turn, as
    # the figures, tables and JUnit show it): reports.input_display
    at = display_input(run_.values, convention_of(lk))[keep]
    out = []
    moving = [b for b, n in enumerate(run_.body_names) if n != mech.ground]
    # the mechanism's angular-acceleration scale: its largest body alpha, or, when every
    # body's alpha is identically zero (a parallelogram at constant input speed), the
    # input's own rate scale (w^2 + |a| of a crank; (v/L)^2 + |a|/L of a slider)
    size = size_of(lk.topo)  # m: the mechanism's largest point distance in one body
    L = 1.0 if lk.driver_is_revolute else size
    rate_scale = float(np.max((kin.velocity[keep] / L) ** 2
                              + np.abs(kin.acceleration[keep]) / L))
    alpha_peak = float(np.max(np.abs(kin.alpha[keep][:, moving]))) if moving else 0.0
    alpha_scale = alpha_peak if alpha_peak > ZERO_PEAK * rate_scale else rate_scale
    for b in moving:
        # a body whose exact alpha is identically zero (a constant-speed crank, a piston)
        # has no peak of its own: judge it on the mechanism's angular-acceleration scale
        out.append(compare(f"{run_.body_names[b]}.alpha", kin.alpha[keep, b],
                           run_.alpha[keep, b], at, tol,
                           peak_floor=_zero_floor(kin.alpha[keep, b], alpha_scale)))
    # a slider whose exact acceleration is identically zero (a prismatic input at constant
    # speed) is judged on the mechanism's linear-acceleration scale, its rate scale times
    # its size, not on its own round-off peak
    acc_scale = rate_scale * size
    for p, name in enumerate(run_.prismatic_names):
        a_ref = kin.slider(name)[2][keep]
        out.append(compare(f"{name}.a", a_ref, run_.slider_acc[keep, p], at, tol,
                           peak_floor=_zero_floor(a_ref, acc_scale)))
    if frc is not None:
        # an effort identically zero (no load, no gravity, no inertia torque: the
        # parallelogram) is judged on the joint forces' scale times the lever arm
        f_peak = max((float(np.max(np.linalg.norm(frc.joint_force[n][keep], axis=1)))
                      for n in run_.joint_names), default=0.0)
        e_scale = f_peak * (size if lk.driver_is_revolute else 1.0)
        out.append(compare("drive.effort", frc.effort[keep], run_.drive_effort[keep], at, tol,
                           peak_floor=_zero_floor(frc.effort[keep], e_scale)))
        for j, name in enumerate(run_.joint_names):
            out.append(compare(f"{name}.force", frc.joint_force[name][keep],
                               run_.joint_force[keep, j], at, tol))
        out += _prismatic_reactions(run_, frc, keep, at, tol, f_peak, size)
        if run_.joint_force_engine is not None:
            for j, name in enumerate(run_.joint_names):
                out.append(compare(engine_reading(f"{name}.force"), frc.joint_force[name][keep],
                                   run_.joint_force_engine[keep, j], at, tol))
        if run_.drive_effort_engine is not None:
            out.append(compare(engine_reading("drive.effort"), frc.effort[keep],
                               run_.drive_effort_engine[keep], at, tol))
    return with_floors(out, run_, at, kin.condition[keep])


def with_floors(comparisons: list[Comparison], run_, at, condition) -> list[Comparison]:
    """Each comparison with the engine's arithmetic floor at its worst sample
    (``run_.settings.error_floor(run_.steps, condition there)``: the settings say what
    their arithmetic can reach; :mod:`sim_models.runs.precision`) and the arithmetic's name.
    A run that stopped claims no floor (its failure is not rounding).  ``at`` and
    ``condition``: the compared samples' inputs and loop condition numbers."""
    settings = run_.settings
    arith = getattr(settings, "arithmetic", None)
    if arith is None:
        return comparisons
    at, condition = np.asarray(at, float), np.asarray(condition, float)
    out = []
    for c in comparisons:
        floor = 0.0
        if run_.ok and c.measured and at.size and math.isfinite(c.at):
            k = int(np.argmin(np.abs(at - c.at)))
            floor = float(settings.error_floor(int(run_.steps), float(condition[k])))
        out.append(dataclasses.replace(c, floor=floor, precision=arith.name))
    return out


def _prismatic_reactions(run_, frc, keep, at, tol: float, f_peak: float,
                         size: float) -> list[Comparison]:
    """``<joint>.normal`` (N) and ``<joint>.moment`` (N m) of each prismatic joint: the
    guide's normal force on the slider and its couple about the slider point.  Either may
    be identically zero (a piston carries no couple): it is then judged on the joint
    forces' scale (times the mechanism's size for the couple) instead of its round-off."""
    out = []
    for p, name in enumerate(run_.prismatic_names):
        for what, ref_all, test_all, scale in (
                ("normal", frc.normal, run_.normal, f_peak),
                ("moment", frc.moment, run_.moment, f_peak * size)):
            ref = ref_all[name][keep]
            out.append(compare(f"{name}.{what}", ref, test_all[keep, p], at, tol,
                               peak_floor=_zero_floor(ref, scale)))
    return out


#: A failed verdict whose worst error sits within this many degrees (revolute driver) of
#: a limit or singular position says so: the mechanism, not the engine, may be at fault.
NEAR_EVENT_DEG = 5.0
#: The same for a prismatic driver, as a fraction of its feasible stroke.
NEAR_EVENT_STROKE = 0.02


def near_event(comparisons: list[Comparison], linkage) -> str | None:
    """For a failed verdict: where the worst failing quantity's error sits relative to
    the nearest limit position, singular position or change point of the linkage's sweep
    (:func:`analytic.sweep.nearest_event`), when within :data:`NEAR_EVENT_DEG` (or
    :data:`NEAR_EVENT_STROKE` of the stroke); else None."""
    bad = [c for c in judged(comparisons) if not c.accepted]
    if not bad:
        return None
    worst = max(bad, key=lambda c: c.normalised if math.isfinite(c.normalised) else math.inf)
    if not math.isfinite(worst.at):
        return None
    try:
        res = linkage.sweep(720, forces=False)
        # input limits, singular positions and change points; not a rocker's extreme
        # angle (a "limit" of an output, where nothing is singular)
        e = res.events
        keep = (e["kind"] != "limit") | e["detail"].str.contains("input limit")
        ev = nearest_event(dataclasses.replace(res, events=e[keep]), worst.at)
    except LinkageError:  # events are advice; a linkage whose sweep fails gives none
        return None
    if ev is None:
        return None
    if linkage.driver_is_revolute:
        if ev.distance > NEAR_EVENT_DEG:
            return None
        unit, where = "deg", format_input(display_input(math.radians(ev.input),
                                                        convention_of(linkage)), "deg")
    else:
        x = res.frame["input"].to_numpy(float)
        stroke = float(np.nanmax(x) - np.nanmin(x)) if len(x) else 0.0
        if stroke <= 0 or ev.distance > NEAR_EVENT_STROKE * stroke:
            return None
        unit, where = "m", format_input(ev.input, "m")
    kind = {"limit": "limit position", "singular": "singular position",
            "change_point": "change point"}.get(ev.kind, ev.kind.replace("_", " "))
    return (f"the worst error ({worst.quantity} at {format_input(worst.at, unit)}) is "
            f"{ev.distance:.3g} {unit} from the {kind} at {where} ({ev.detail}): "
            "the mechanism itself is singular or at a limit there, so a small engine offset "
            "is a large error")


def step_note(run_, revolute: bool) -> str | None:
    """For a failed verdict: how far the input moves in one engine step at its fastest.

    A fixed-step engine's error grows with that increment, and the recommended steps are
    absolute times measured on the built-in cases (seed-slider-crank, the fastest, turns
    0.05 rad per MuJoCo step), so a much faster input (the fast-accelerating reproducer
    reaches about 1100 rad/s) needs a smaller step; halving ``--timestep`` then tells the
    engine's step (the error falls as a power of dt) from a model or solver fault (it does
    not).  None when the rate is unknown."""
    rate = np.abs(np.asarray(run_.driver_velocity, float))
    rate = rate[np.isfinite(rate)]
    if not rate.size or not math.isfinite(run_.timestep) or run_.timestep <= 0:
        return None
    k = float(np.max(rate))
    inc = k * run_.timestep
    if revolute:
        return (f"the input turns up to {inc:.3g} rad ({math.degrees(inc):.3g} deg) per engine "
                f"step at its fastest ({k:.4g} rad/s x dt {run_.timestep:.3g} s): rerun with "
                f"--timestep {run_.timestep / 4:.2g} to see whether the error falls with the "
                "step (the engine's step) or not (the model or the solver)")
    return (f"the input moves up to {inc:.3g} m per engine step at its fastest ({k:.4g} m/s "
            f"x dt {run_.timestep:.3g} s): rerun with --timestep {run_.timestep / 4:.2g} to see "
            "whether the error falls with the step (the engine's step) or not")


def comparison_frame(run_, comparisons: list[Comparison]) -> pd.DataFrame:
    """One row per quantity: case, engine, settings and the diagnostic."""
    rows = []
    for c in comparisons:
        d = c.as_dict()
        d.update(case=run_.case, engine=run_.engine, settings=run_.settings_text,
                 run_ok=run_.ok, run_reason=run_.reason or "",
                 engine_reading=is_engine_reading(c.quantity),
                 verdict=c.status)
        rows.append(d)
    cols = ["case", "engine", "quantity", "max_abs", "peak", "normalised", "at", "tolerance",
            "passed", "engine_reading", "run_ok", "run_reason", "settings", "precision",
            "floor", "verdict"]
    return pd.DataFrame(rows, columns=cols)


def verdict(comparisons: list[Comparison]) -> bool:
    """Pass when every quantity computed by this project passes or sits within the
    engine's arithmetic floor (a precision limit; the engines' own readings known to be
    wrong are reported, not judged)."""
    return all(c.accepted for c in judged(comparisons))


def verdict_word(comparisons: list[Comparison], run_ok: bool = True) -> str:
    """The verdict in words: ``"FAIL"`` (a run that stopped, or a judged quantity over
    its tolerance and its floor), ``"precision limit (float32)"`` (every judged quantity
    passes or is within the floor, one at least within the floor only) or ``"pass"``."""
    js = judged(comparisons)
    if not run_ok or not all(c.accepted for c in js):
        return FAIL
    lim = [c for c in js if c.limited]
    return limit_word(lim[0].precision) if lim else PASS
