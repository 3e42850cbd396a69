"""The one analytic reference of an engine run: what the verdict, the error figures and
the case plots all read.

:func:`analytic_reference` is the analytic solution at the run's own sampled inputs,
with the driver rate and acceleration the engine was given there (branch-continued:
:meth:`analytic.Linkage.kinematics_along`); :func:`reports.comparison.compare.analytic_at`, which
the verdict calls, returns it.  :func:`analytic_line` is the same solution on a dense
set of times along the same prescribed motion, passing through every sample, for the
lines of the case plots.  :func:`sample_errors` is each judged quantity's error at each
sample, normalised as the verdict normalises it (:func:`reports.comparison.compare.compare_run`):
its largest value is that quantity's verdict error.

Axes: a run sampled at the sweep's inputs is plotted against its sampled input values
(``run.values``: rad or m; one turn from the reference value for a full-turn crank); a
run sampled at equal times (a reversing or accelerating input,
``run.by_time``) against time, s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from analytic import Linkage
from analytic.input_display import convention_of, display_input
from analytic.mechanism import Prismatic
from reports.comparison import quantities
from sim_models.runs.sampling import LIMITED_RANGE_CONDITION, near_limit

#: Points of the dense analytic line per plotted span (the samples are added to them).
LINE_POINTS = 361


@dataclass(frozen=True)
class Reference:
    """The analytic solution at a run's samples.

    ``linkage`` the analytic Linkage; ``kin``/``frc`` Kinematics and Forces (``frc``
    None without masses or comparable forces) at ``run.values`` with the run's driver
    rates; ``judged`` (N,) the samples the verdict compares (reached, finite, loop
    condition number at most :data:`reports.comparison.compare.MAX_CONDITION`); ``u`` (N,) the
    plotted axis value of each sample (deg or m of input, or s for a time-sampled run).
    """

    linkage: object
    kin: object
    frc: object | None
    judged: np.ndarray
    u: np.ndarray


#: Samples where the analytic loop Jacobian's condition number exceeds this are left
#: out of engine comparisons: only the ends of a limited-range sweep, 1e-6 of the range
#: from a limit position, where the exact accelerations reach ~1e9 and a sample-time
#: offset of one ulp changes them by percent.  Every full-cycle case stays below 20.
#: The same number at which a limited-range engine run stops
#: (:data:`sim_models.runs.sampling.LIMITED_RANGE_CONDITION`): one decision, in
#: :func:`sim_models.runs.sampling.near_limit`.
MAX_CONDITION = LIMITED_RANGE_CONDITION


def _kinematics(lk, values, velocity, acceleration):
    """Branch-continued kinematics at arbitrary inputs (the solver's ``kinematics_along``
    when present; ``kinematics`` continues the branch by default otherwise)."""
    along = getattr(lk, "kinematics_along", None)
    if along is not None:
        return along(values, velocity, acceleration, on_singular="flag")
    return lk.kinematics(values, velocity, acceleration, on_singular="flag")


def analytic_reference(run_, linkage: Linkage | None = None):
    """``(linkage, kin, frc)``: the analytic solution at ``run_``'s sampled inputs with
    the driver rate and acceleration the engine was given at each (the prescribed
    motion; the description's rate where a sample has none).  The solution is
    ``run_.linkage``'s, the compiled object the run was made from (never rebuilt);
    ``linkage``: another Linkage to compare the run with instead (a study comparing a
    run against a neighbouring description)."""
    lk = run_.linkage if linkage is None else linkage
    mech = lk.mech
    vel = np.where(np.isfinite(run_.driver_velocity), run_.driver_velocity,
                   mech.driver.velocity)
    kin = _kinematics(lk, run_.values, vel, run_.driver_acceleration)
    frc = lk.forces(kin) if run_.has_forces and mech.has_mass else None
    return lk, kin, frc


def axis_of(run_, linkage) -> tuple[np.ndarray, str]:
    """The plotted axis of a run's samples and its label with units: time (s) for a
    run sampled by time, else the input in the one display convention of
    :mod:`analytic.input_display` (a full turn in degrees wrapped to [0, 360), as the
    verdict's ``at``)."""
    if run_.by_time:
        return np.asarray(run_.times, float), "time (s)"
    u = display_input(run_.values, convention_of(linkage))
    if linkage.driver_is_revolute:
        return u, "input angle (deg)"
    return u, "input (m)"


def reference_of(run_, linkage: Linkage | None = None) -> Reference:
    """:func:`analytic_reference` (``run_.linkage``'s solution, or ``linkage``'s) with
    the judged samples and the plotted axis."""
    lk, kin, frc = analytic_reference(run_, linkage)
    judged = ~near_limit(kin.condition, MAX_CONDITION)
    if run_.ok:
        judged &= np.all(np.isfinite(run_.alpha), axis=1)
    u, _ = axis_of(run_, lk)
    return Reference(lk, kin, frc, judged, u)


def _line_inputs(runs, linkage, points: int):
    """The inputs of :func:`analytic_line`, sorted by the plotted axis: ``(u, t, value,
    velocity, acceleration)``, or None when no sample was reached."""
    d = linkage.mech.driver
    r0 = runs[0]
    ts = np.concatenate([np.asarray(r.times, float) for r in runs])
    ts = ts[np.isfinite(ts)]
    if not ts.size:
        return None
    t = np.linspace(ts.min(), ts.max(), points)
    value = d.value + d.velocity * t + 0.5 * d.acceleration * t * t
    vel = d.velocity + d.acceleration * t
    acc = np.full_like(t, d.acceleration)
    if r0.by_time:
        u = t
    else:
        conv = convention_of(linkage)
        if conv.full_turn:  # the sampled turn's values: one turn from the first sample
            v0 = float(np.min(r0.values))
            value = v0 + np.mod(value - v0, 2 * math.pi)
        # the axis: the input as every table and title shows it (a full turn wrapped to
        # [0, 360) deg); a turn that does not start at 0 is drawn in two stretches
        # (line_breaks), each sample on the stretch of its own time
        u = display_input(value, conv)
    # the samples themselves, exactly as the reference has them
    us, tt, vals, vels, accs = [u], [t], [value], [vel], [acc]
    for r in runs:
        ok = np.isfinite(r.times)
        ur, _ = axis_of(r, linkage)
        us.append(ur[ok])
        tt.append(np.asarray(r.times, float)[ok])
        vals.append(np.asarray(r.values, float)[ok])
        vels.append(np.where(np.isfinite(r.driver_velocity), r.driver_velocity,
                             d.velocity)[ok])
        accs.append(np.asarray(r.driver_acceleration, float)[ok])
    u, t, value, vel, acc = (np.concatenate(z) for z in (us, tt, vals, vels, accs))
    order = np.argsort(u, kind="stable")
    return u[order], t[order], value[order], vel[order], acc[order]


def analytic_line(runs, linkage, points: int = LINE_POINTS):
    """The analytic solution along the prescribed motion between the first and last
    reached sample of ``runs`` (engine runs of one case on one plan), at ``points``
    equal times plus every run's sample times: ``(u, kin, frc)`` sorted by ``u`` (the
    plotted axis, :func:`axis_of`).  At a sample's own time the values are those of
    :func:`analytic_reference` (same input, rate and acceleration)."""
    inputs = _line_inputs(runs, linkage, points)
    if inputs is None:
        return None
    u, _, value, vel, acc = inputs
    kin = _kinematics(linkage, value, vel, acc)
    frc = linkage.forces(kin) if runs[0].has_forces and linkage.mech.has_mass else None
    return u, kin, frc


def line_breaks(runs, linkage, points: int = LINE_POINTS) -> np.ndarray:
    """Indices of :func:`analytic_line`'s points that start a new stretch of the line:
    neighbours on the plotted axis far apart in time (a sample of another turn, reached
    at another speed), which a drawn line must not join."""
    inputs = _line_inputs(runs, linkage, points)
    if inputs is None:
        return np.zeros(0, int)
    t = inputs[1]
    step = (np.max(t) - np.min(t)) / max(points - 1, 1)
    return np.flatnonzero(np.abs(np.diff(t)) > 3 * step) + 1 if step > 0 else np.zeros(0, int)


def engine_slider_positions(run_, tree) -> dict[str, np.ndarray]:
    """Each prismatic joint's displacement ``s`` (m, (N,)) in the engine at the run's
    samples, from its tree coordinates (:meth:`sim_models.builders.tree.SimTree.propagate`): the
    slider point's distance along the line from the guide's origin point, as
    :meth:`analytic.Kinematics.slider` measures it.  Empty when the run kept no tree
    coordinates; NaN where the engine has no sample."""
    if getattr(run_, "q", None) is None or tree is None:
        return {}
    q = np.asarray(run_.q, float)
    ok = np.all(np.isfinite(q), axis=1)
    th, _, _, org = tree.propagate(np.nan_to_num(q), np.zeros_like(q), np.zeros_like(q))[:4]
    mech = tree.mech
    names = [b.name for b in mech.bodies]

    def world(b: int, local) -> np.ndarray:
        c, s = np.cos(th[:, b]), np.sin(th[:, b])
        x, y = float(local[0]), float(local[1])
        return org[:, b] + np.stack([c * x - s * y, s * x + c * y], axis=1)

    out = {}
    for jt in mech.joints:
        if not isinstance(jt, Prismatic):
            continue
        g, s_ = names.index(jt.guide), names.index(jt.slider)
        o = world(g, mech.bodies[g].points[jt.origin])
        p = world(s_, mech.bodies[s_].points[jt.point])
        ang = th[:, g] + jt.direction
        s = (p[:, 0] - o[:, 0]) * np.cos(ang) + (p[:, 1] - o[:, 1]) * np.sin(ang)
        out[jt.name] = np.where(ok, s, np.nan)
    return out


def family_of(quantity: str) -> str:
    """The family a judged quantity belongs to (the error plots draw one line each)."""
    if quantity.endswith(".alpha"):
        return "body alpha"
    if quantity.endswith(".a"):
        return "slider s''"
    if quantity == "drive.effort":
        return "drive effort"
    if quantity.endswith(".force"):
        return "joint forces"
    if quantity.endswith((".normal", ".moment")):
        return "prismatic normal, moment"
    return quantity


def sample_errors(run_, ref: Reference, comparisons) -> dict[str, np.ndarray]:
    """Each judged quantity's ``|engine - analytic|`` at each sample (vector norm for a
    force), divided by the peak the verdict divided it by (``comparisons``:
    :func:`reports.comparison.compare.compare_run` of this run), NaN at samples the verdict does
    not judge: the largest value of each is that quantity's verdict error.  Keys are the
    verdict's quantity names (the engines' own ``[engine]`` readings left out)."""
    kin, frc, keep = ref.kin, ref.frc, ref.judged
    peaks = {c.quantity: c.peak for c in quantities.judged(comparisons)}
    raw: dict[str, np.ndarray] = {}
    for b, name in enumerate(run_.body_names):
        raw[f"{name}.alpha"] = np.abs(run_.alpha[:, b] - kin.alpha[:, b])
    for p, name in enumerate(run_.prismatic_names):
        raw[f"{name}.a"] = np.abs(run_.slider_acc[:, p] - kin.slider(name)[2])
    if frc is not None:
        for p, name in enumerate(run_.prismatic_names):
            raw[f"{name}.normal"] = np.abs(run_.normal[:, p] - frc.normal[name])
            raw[f"{name}.moment"] = np.abs(run_.moment[:, p] - frc.moment[name])
        raw["drive.effort"] = np.abs(run_.drive_effort - frc.effort)
        for j, name in enumerate(run_.joint_names):
            raw[f"{name}.force"] = np.linalg.norm(run_.joint_force[:, j]
                                                  - frc.joint_force[name], axis=1)
    out = {}
    for q, peak in peaks.items():
        if q not in raw:
            continue
        e = np.where(keep, raw[q], np.nan)
        out[q] = e / peak if peak > 0 else np.where(e == 0, 0.0, np.inf)
    return out


def wrap_deg(d):
    """Angles (deg) to [-180, 180)."""
    return np.mod(np.asarray(d, float) + 180.0, 360.0) - 180.0


__all__ = ["LINE_POINTS", "Reference", "analytic_line", "analytic_reference", "axis_of",
           "line_breaks", "engine_slider_positions",
           "family_of", "reference_of", "sample_errors", "wrap_deg"]
