"""The results of an engine run: the :class:`Recorder` sessions fill and the
:class:`EngineRun` it becomes (analytic conventions; see :mod:`sim_models.engines.protocol`)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from analytic import Linkage, Mechanism

from ..builders.tree import SimTree
from ..engines import ranges
from ..engines.settings import EngineSettings, SettingsError
from .sampling import Plan


# ============================================================================ recorder
class Recorder:
    """Sample arrays of a run, NaN until filled (shapes as :class:`EngineRun`).

    Besides the analytic-convention arrays it keeps the raw tree coordinates ``q, qd,
    qdd`` (N, nt) of each sample (for the long-run diagnostics)."""

    def __init__(self, tree: SimTree, plan: Plan):
        N = plan.n
        B = len(tree.body_names)
        J = len(tree.mech.joints)
        P = len(tree.prismatic)
        nt = len(tree.joints)
        nan = np.nan
        self.tree = tree
        self.times = plan.times
        self.theta = np.full((N, B), nan)
        self.omega = np.full((N, B), nan)
        self.alpha = np.full((N, B), nan)
        self.slider_acc = np.full((N, P), nan)
        self.effort = np.full(N, nan)
        self.effort_engine = np.full(N, nan)
        self.force = np.full((N, J, 2), nan)
        self.force_engine = np.full((N, J, 2), nan)
        self.normal = np.full((N, P), nan)
        self.moment = np.full((N, P), nan)
        self.viol = np.full(N, nan)
        self.speed = np.full(N, nan)
        self.measured = np.full(N, nan)
        self.q = np.full((N, nt), nan)
        self.qd = np.full((N, nt), nan)
        self.qdd = np.full((N, nt), nan)
        self.origin = np.full((N, B, 2), nan)  # body-frame origins, world (animations)

    def put_motion(self, rows, t: float, q, qd, qdd):
        """Fill the motion of ``rows`` from tree coordinates (SimTree conventions) at
        time ``t``: :meth:`put_motions` with one record.  Returns ``(theta, omega,
        alpha, origin, v_origin, a_origin)`` of :meth:`SimTree.propagate` (each with one
        row) for the force readout."""
        prop, _, _ = self.put_motions([rows], [t], np.asarray(q, float)[None],
                                      np.asarray(qd, float)[None], np.asarray(qdd, float)[None])
        return prop

    def put_motions(self, rows, times, q, qd, qdd):
        """Fill the motion of K records at once from tree coordinates ``q, qd, qdd`` (K,
        nt) (SimTree conventions): record ``k`` at time ``times[k]`` (s) goes to the
        sample rows ``rows[k]`` (a list, possibly empty).  Fills absolute
        theta/omega/alpha, slider accelerations, the measured driver value, the
        driver-rate deviation from the prescribed rate and the loop gap.

        Returns ``prop`` (``theta, omega, alpha, origin, v_origin, a_origin`` of
        :meth:`SimTree.propagate`, K rows each) and, per record, the loop gap (m) and
        the driver's rate (for the run's divergence check)."""
        st = self.tree
        q, qd, qdd = (np.asarray(x, float) for x in (q, qd, qdd))
        prop = st.propagate(q, qd, qdd)
        th, om, al, org = prop[:4]
        gap = loop_gaps(st, th, org)
        _, vel, _ = st.driver_path(np.asarray(times, float))
        rate = st.driver_sigma * qd[:, st.driver_tree]
        k, i = scatter_index(rows)
        if len(i):
            self.theta[i], self.omega[i], self.alpha[i] = th[k], om[k], al[k]
            self.q[i], self.qd[i], self.qdd[i] = q[k], qd[k], qdd[k]
            self.origin[i] = org[k]
            self.measured[i] = st.driver_value(q[k, st.driver_tree])
            self.viol[i] = gap[k]
            self.speed[i] = (rate - vel)[k]
            for p, kj in enumerate(st.prismatic):
                ti = st.tree_joint_indices.index(kj)
                self.slider_acc[i, p] = st.joints[ti].sigma * qdd[k, ti]
        return prop, gap, rate

    def put_absolute(self, rows, t: float, theta, omega, alpha, slider_acc, origin,
                     driver_value: float, driver_rate: float):
        """Fill the motion of ``rows`` from absolute body quantities, for engines in
        absolute coordinates: ``theta, omega, alpha`` (B,) rad, rad/s, rad/s^2 of every
        body's own frame (the description's body frame, ground included), ``slider_acc``
        (P,) m/s^2 of each prismatic joint's ``s''``, ``origin`` (B, 2) m the body-frame
        origins (for the loop gap), the engine's driver value (rad or m) and rate."""
        st = self.tree
        th = np.asarray(theta, float)[None]
        gap = loop_gap(st, th, np.asarray(origin, float)[None])
        _, vel, _ = st.driver_path(t)
        for i in np.atleast_1d(rows):
            self.theta[i], self.omega[i], self.alpha[i] = theta, omega, alpha
            self.slider_acc[i] = slider_acc
            self.origin[i] = origin
            self.measured[i] = driver_value
            self.viol[i] = gap
            self.speed[i] = driver_rate - float(vel)

    def put_absolutes(self, rows, times, theta, omega, alpha, slider_acc, origin,
                      driver_value, driver_rate):
        """:meth:`put_absolute` of K records at once (arrays with a leading K axis;
        record ``k`` at ``times[k]`` goes to the sample rows ``rows[k]``)."""
        k, i = scatter_index(rows)
        if not len(i):
            return
        st = self.tree
        th = np.asarray(theta, float)[k]
        _, vel, _ = st.driver_path(np.asarray(times, float)[k])
        self.theta[i], self.omega[i] = th, np.asarray(omega, float)[k]
        self.alpha[i] = np.asarray(alpha, float)[k]
        self.slider_acc[i] = np.asarray(slider_acc, float)[k]
        self.origin[i] = np.asarray(origin, float)[k]
        self.measured[i] = np.asarray(driver_value, float)[k]
        self.viol[i] = loop_gaps(st, th, np.asarray(origin, float)[k])
        self.speed[i] = np.asarray(driver_rate, float)[k] - vel

    def put_forces(self, rows, joint_force, effort, normal=None, moment=None,
                   force_engine=None, effort_engine=None):
        """Fill the forces of ``rows``: ``joint_force`` (J, 2) by body_a on body_b,
        ``effort`` (drive, on body_b), ``normal``/``moment`` (P,), and the engine's own
        unjudged readings when it has them."""
        for i in np.atleast_1d(rows):
            self.force[i] = joint_force
            self.effort[i] = effort
            if normal is not None:
                self.normal[i] = normal
            if moment is not None:
                self.moment[i] = moment
            if force_engine is not None:
                self.force_engine[i] = force_engine
            if effort_engine is not None:
                self.effort_engine[i] = effort_engine

    def put_forces_many(self, rows, joint_force, effort, normal=None, moment=None,
                        force_engine=None, effort_engine=None):
        """:meth:`put_forces` of K records at once: ``joint_force`` (K, J, 2), ``effort``
        (K,), ``normal``/``moment`` (K, P), engine readings (K, J, 2) / (K,); record
        ``k`` goes to the sample rows ``rows[k]``."""
        k, i = scatter_index(rows)
        if not len(i):
            return
        self.force[i] = np.asarray(joint_force)[k]
        self.effort[i] = np.asarray(effort)[k]
        for dest, src in ((self.normal, normal), (self.moment, moment),
                          (self.force_engine, force_engine),
                          (self.effort_engine, effort_engine)):
            if src is not None:
                dest[i] = np.asarray(src)[k]

    def drop(self, rows) -> None:
        """Samples ``rows`` were not reached (a run that ended before them): NaN in every
        array, the measured driver value included."""
        i = np.asarray(rows, dtype=int)
        for arr in self._arrays() + (self.measured,):
            arr[i] = np.nan

    def _arrays(self) -> tuple:
        return (self.theta, self.omega, self.alpha, self.slider_acc, self.effort,
                self.force, self.normal, self.moment, self.viol, self.speed,
                self.effort_engine, self.force_engine, self.q, self.qd, self.qdd,
                self.origin)

    def fail(self, t_stop: float, reason: str) -> tuple[str, float]:
        """End a run at ``t_stop``: samples at or after it become NaN.  Returns the
        reason naming the (prescribed) driver value there, and that value."""
        st = self.tree
        fail = float(st.driver_path(t_stop)[0])
        late = np.asarray(self.times) >= t_stop - 1e-15
        for arr in self._arrays():
            arr[late] = np.nan
        return f"{reason} at driver {st.mech.driver.joint!r} = {fmt_value(st, fail)}", fail


def loop_gap(tree: SimTree, theta, origin) -> float:
    """Largest distance (m) between the two points of a loop-closing joint."""
    gap = 0.0
    for ch in tree.chords:
        pa = tree.point_world(theta, origin, ch.body_a, ch.point_a)[0]
        pb = tree.point_world(theta, origin, ch.body_b, ch.point_b)[0]
        gap = max(gap, float(np.linalg.norm(pa - pb)))
    return gap


def loop_gaps(tree: SimTree, theta, origin) -> np.ndarray:
    """Largest distance (m) between the two points of a loop-closing joint, per row of
    ``theta`` (N, B) / ``origin`` (N, B, 2): (N,)."""
    gap = np.zeros(len(theta))
    for ch in tree.chords:
        d = tree.point_world(theta, origin, ch.body_a, ch.point_a) \
            - tree.point_world(theta, origin, ch.body_b, ch.point_b)
        gap = np.maximum(gap, np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]))
    return gap


def scatter_index(rows) -> tuple[np.ndarray, np.ndarray]:
    """``(k, i)``: record index and sample row of every row in ``rows`` (one list of
    sample rows per record), for filling sample arrays from per-record arrays."""
    k, i = [], []
    for r, rr in enumerate(rows):
        for x in (rr if isinstance(rr, (list, tuple)) else np.atleast_1d(rr).tolist()):
            k.append(r)
            i.append(int(x))
    return np.asarray(k, dtype=int), np.asarray(i, dtype=int)


def fmt_value(tree: SimTree, v: float) -> str:
    """A driver value (rad or m) in the one display convention of an input
    (:mod:`analytic.input_display`: a full turn wrapped to [0, 360) deg)."""
    from analytic.input_display import convention_of, input_text
    return input_text(v, convention_of(tree.linkage))


# ============================================================================ result
@dataclass(frozen=True)
class RunRequest:
    """How a run was asked for: enough, with the mechanism and settings, to re-run it
    exactly (:func:`rerun`)."""

    revolutions: int = 2
    samples: int = 36
    max_violation: float = 1e-3
    max_speed_error: float = 1e-2
    chords: str = "moving"
    mode: str = "run"               # "run" or "instantaneous"
    #: s of wall-clock stepping after which the run ends as a failed run that says so
    #: (``xval plot --wall-limit``); None: no limit (the report's and baselines' runs)
    wall_limit: float | None = None

    def __post_init__(self):
        """Every value within :mod:`sim_models.engines.ranges` (the command line's ranges):
        :class:`~sim_models.engines.settings.SettingsError` naming the key otherwise."""
        rngs = self.ranges()
        if self.wall_limit is not None:
            rngs["wall_limit"] = ranges.WALL_LIMIT
        for key, rng in rngs.items():
            value = getattr(self, key)
            problem = rng.problem(value)
            if problem:
                raise SettingsError(f"run request {key}={value!r}: {problem}", key, value,
                                    problem)

    def ranges(self) -> dict:
        """The accepted range of each field (samples: states in the instantaneous mode)."""
        return {"mode": ranges.MODES, "revolutions": ranges.REVOLUTIONS,
                "samples": ranges.STATES if self.mode == "instantaneous" else ranges.SAMPLES,
                "max_violation": ranges.MAX_VIOLATION,
                "max_speed_error": ranges.MAX_SPEED_ERROR, "chords": ranges.CHORDS}


@dataclass(frozen=True)
class EngineRun:
    """Engine results at the sampled driver values (SI, world axes, analytic conventions).

    Arrays have N rows, one per sample; B bodies (``body_names``, the description's
    order), J joints (``joint_names``), P prismatic joints (``prismatic_names``).
    ``mechanism``, ``settings`` (the settings object) and ``request`` re-run it exactly:
    :func:`rerun`.  ``settings_text`` is ``settings.describe()``.  ``linkage`` is the
    compiled analytic :class:`~analytic.Linkage` the run was made from (the
    :class:`~sim_models.builders.tree.SimTree`'s own object, ``linkage.mech is mechanism``): the
    comparison reads its reference from it and never builds another.
    """

    case: str
    engine: str
    mechanism: Mechanism
    linkage: Linkage                  # the compiled object (SimTree.linkage), not a copy
    settings: EngineSettings
    request: RunRequest
    ok: bool
    reason: str | None
    fail_value: float | None          # driver value (rad or m) where the run failed
    values: np.ndarray                # (N,) driver values at the samples
    times: np.ndarray                 # (N,) s from the start of the run (NaN: unreached)
    driver_velocity: np.ndarray       # (N,) prescribed driver rate at the sample
    driver_acceleration: np.ndarray   # (N,) prescribed driver acceleration
    measured_values: np.ndarray       # (N,) driver value in the engine at the sample
    body_names: tuple[str, ...]
    joint_names: tuple[str, ...]
    prismatic_names: tuple[str, ...]
    theta: np.ndarray                 # (N, B) rad
    omega: np.ndarray                 # (N, B) rad/s
    alpha: np.ndarray                 # (N, B) rad/s^2, absolute
    slider_acc: np.ndarray            # (N, P) m/s^2 (s'' of each prismatic joint)
    drive_effort: np.ndarray          # (N,) N m or N, on body_b / the slider
    joint_force: np.ndarray           # (N, J, 2) N, by body_a on body_b
    normal: np.ndarray                # (N, P) N
    moment: np.ndarray                # (N, P) N m
    loop_violation: np.ndarray        # (N,) m, largest gap at a loop-closing joint
    speed_deviation: np.ndarray       # (N,) driver rate minus prescribed rate
    wall_per_rev: float               # s of stepping per revolution (per run if not full)
    timestep: float
    steps_per_rev: float
    steps: int                        # steps taken (pre-roll included)
    wall: float                       # s of the whole stepping loop
    has_forces: bool                  # False: placeholder masses, forces not comparable
    by_time: bool = False             # sampled at equal times (not the sweep's inputs)
    notes: tuple[str, ...] = ()
    drive_effort_engine: np.ndarray | None = None      # engine's own drive reading
    joint_force_engine: np.ndarray | None = None       # engine's own pin-force reading
    q: np.ndarray | None = None       # (N, nt) raw tree coordinates (SimTree)
    qd: np.ndarray | None = None
    qdd: np.ndarray | None = None
    extra: dict = field(default_factory=dict)
    origin: np.ndarray | None = None  # (N, B, 2) m, body-frame origins (any engine)

    @property
    def n(self) -> int:
        return len(self.values)

    @property
    def settings_text(self) -> str:
        return self.settings.describe()

    def frame(self):
        """A DataFrame with the sweep's column names (see :mod:`analytic.sweep`)."""
        import pandas as pd
        revolute = not self.extra.get("prismatic_driver", False)
        cols = {"input": np.degrees(self.values) if revolute else self.values}
        for b, name in enumerate(self.body_names):
            cols[f"{name}.angle_deg"] = 180.0 - np.mod(180.0 - np.degrees(self.theta[:, b]),
                                                       360.0)
            cols[f"{name}.omega"] = self.omega[:, b]
            cols[f"{name}.alpha"] = self.alpha[:, b]
        for p, name in enumerate(self.prismatic_names):
            cols[f"{name}.a"] = self.slider_acc[:, p]
            cols[f"{name}.normal"] = self.normal[:, p]
            cols[f"{name}.moment"] = self.moment[:, p]
        for j, name in enumerate(self.joint_names):
            cols[f"{name}.fx"] = self.joint_force[:, j, 0]
            cols[f"{name}.fy"] = self.joint_force[:, j, 1]
        cols["drive.torque" if revolute else "drive.force"] = self.drive_effort
        cols["loop_violation"] = self.loop_violation
        cols["speed_deviation"] = self.speed_deviation
        return pd.DataFrame(cols)



#: Steps of the first bounded :func:`advance_bounded` call; later calls take as many
#: steps as :data:`WALL_CHUNK_S` of wall time allows at the rate measured, so a wall-clock
#: limit is honoured within about that much however many steps one stop holds
#: (``--samples 2 --timestep 1e-6``: 2e8 steps; 999 revolutions before the last).
WALL_CHUNK_STEPS = 256
WALL_CHUNK_S = 0.1


def advance_bounded(session, t: float, h: float, n: int, left: float,
                    chunk: list[int]) -> tuple[str | None, float, int]:
    """``session.advance(t, h, n)`` in calls of ``chunk[0]`` steps (adapted to take about
    :data:`WALL_CHUNK_S` each; the list carries it from stop to stop), stopping once
    ``left`` s of wall time are spent: ``(reason, wall, steps taken)``.  A stop within
    one chunk is one call, as before."""
    done, wall = 0, 0.0
    while done < n:
        m = min(chunk[0], n - done)
        t0 = time.perf_counter()
        reason = session.advance(t + done * h, h, m)
        dt = time.perf_counter() - t0
        wall, done = wall + dt, done + m
        if reason is not None or wall > left:
            return reason, wall, done
        chunk[0] = max(1, min(10 * chunk[0], int(m * WALL_CHUNK_S / max(dt, 1e-9))))
    return None, wall, done


__all__ = ["WALL_CHUNK_S", "WALL_CHUNK_STEPS", "EngineRun", "Recorder", "RunRequest",
           "advance_bounded", "fmt_value", "loop_gap", "loop_gaps", "scatter_index"]
