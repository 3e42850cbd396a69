"""Run a mechanism in MuJoCo or PyBullet and read it out in the analytic conventions.

One interface for both engines::

    r = run(mech, "mujoco", MujocoSettings(), revolutions=2, samples=36)
    r = run(mech, "pybullet", PybulletSettings(), revolutions=2, samples=36)
    r = mujoco_instantaneous(mech, MujocoSettings(), values)

Sampling
--------
Results are sampled at the analytic sweep's input values
(:func:`analytic.sweep.input_values`): for a full-cycle driver, the last of
``revolutions`` turns is sampled at ``value_ref + 2 pi k / samples`` (the
first turn starts from the exactly assembled reference state and the earlier
ones let start-up transients of the constraint stabilisation die out).  The
step is shortened so that every sample time is a step boundary, and each
quantity is taken at the **start** of the step (MuJoCo: ``mj_forward`` at that
state; PyBullet: finite differences ``(v_{n+1} - v_n) / dt`` of its
semi-implicit step, exact for it).  A driver that cannot turn fully (limited
range) is run once from its reference value in the direction of its velocity;
samples it does not reach are NaN.

Conventions (as :mod:`analytic.kinetostatics`)
----------------------------------------------
``joint_force[:, j]`` is the force by body_a on body_b of joint j, world axes;
for a prismatic joint it is the full force by the guide on the slider (its
along-line part is the drive force or ~0), ``normal``/``moment`` its normal
component and the couple on the slider about the slider point.  ``drive_effort``
is the torque (force) the driver applies to body_b (the slider).  Absolute
angular accelerations, never the engines' relative joint coordinates.

Divergence (non-finite state, loop violation above ``max_violation``, driver
speed off by more than ``max_speed_error``) ends the run: the result has
``ok = False``, the ``reason`` and the driver value where it happened
(``fail_value``); samples after it are NaN.  Nothing raises for a diverging
simulation.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from analytic import Mechanism, Prismatic, Revolute
from analytic.sweep import input_values

from .mjcf import MujocoSettings, build_mjcf, compile_spec, require_mujoco, site_name
from .tree import SimModelError, SimTree


@dataclass(frozen=True)
class EngineRun:
    """Engine results at the sampled driver values (SI, world axes, analytic conventions).

    Arrays have N rows, one per sample; B bodies (``body_names``, the
    description's order), J joints (``joint_names``), P prismatic joints
    (``prismatic_names``).
    """

    case: str
    engine: str
    settings: str
    ok: bool
    reason: str | None
    fail_value: float | None          # driver value (rad or m) where the run failed
    values: np.ndarray                # (N,) requested driver values (the sweep's)
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
    wall_per_rev: float               # s of stepping per revolution (per run if limited)
    timestep: float
    steps_per_rev: float
    has_forces: bool                  # False: placeholder masses, forces not comparable
    notes: tuple[str, ...] = ()
    drive_effort_engine: np.ndarray | None = None      # engine's own drive reading
    joint_force_engine: np.ndarray | None = None       # engine's own pin-force reading
    extra: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(self.values)

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


# ----------------------------------------------------------------------------- sampling
def _time_of(d, u: float) -> float:
    """Smallest t >= 0 with value(t) = u for value(t) = v0 + w t + a t^2 / 2 (NaN if none)."""
    c = d.value - u
    if d.acceleration == 0.0:
        if d.velocity == 0.0:
            return 0.0 if c == 0 else math.nan
        t = -c / d.velocity
        return t if t >= -1e-12 else math.nan
    disc = d.velocity ** 2 - 2 * d.acceleration * c
    if disc < 0:
        return math.nan
    r = math.sqrt(disc)
    ts = sorted(((-d.velocity - r) / d.acceleration, (-d.velocity + r) / d.acceleration))
    for t in ts:
        if t >= -1e-12:
            return max(t, 0.0)
    return math.nan


#: A limited-range run stops before the first sample whose analytic loop-Jacobian
#: condition number exceeds this (near a limit position).
LIMITED_RANGE_CONDITION = 100.0


@dataclass
class _Plan:
    values: np.ndarray       # requested values (sweep)
    targets: np.ndarray      # unwrapped driver values to hit
    times: np.ndarray        # sample times (NaN: unreachable)
    full: bool
    t_end: float
    rev_time: float          # duration of one revolution (or of the run)
    revolutions: int
    velocity: np.ndarray     # prescribed driver rate at the samples (NaN: unreachable)


def _plan(st: SimTree, revolutions: int, samples: int) -> _Plan:
    lk, d = st.linkage, st.mech.driver
    vals, full, _ = input_values(lk, samples)
    sgn = math.copysign(1.0, d.velocity if d.velocity != 0 else d.acceleration)
    if full:
        R = max(int(revolutions), 1)
        off = 2 * math.pi * (R - 1) if sgn > 0 else -2 * math.pi * R
        targets = vals + off
        if sgn < 0:  # value v0 itself is reached after R full turns backwards
            targets = np.where(np.isclose(vals, d.value), d.value - 2 * math.pi * (R - 1),
                               targets)
        t_rev = [_time_of(d, d.value + sgn * 2 * math.pi * r) for r in range(R + 1)]
    else:
        R = 1
        targets = vals.copy()
        t_rev = [0.0]
    times = np.array([_time_of(d, u) for u in targets])
    if not full:
        # stop before the first sample near a limit position (the ends of the range sit
        # 1e-6 of it from the toggle, where no finite drive effort moves the linkage)
        kin = lk.kinematics(vals, on_singular="flag")
        bad = np.isfinite(times) & ~(kin.condition <= LIMITED_RANGE_CONDITION)
        if bad.any():
            times[times >= np.min(times[bad])] = np.nan
    ok = np.isfinite(times)
    t_end = float(np.nanmax(times)) if ok.any() else 0.0
    if full:
        rev_time = (t_rev[-1] - t_rev[0]) / R
    else:
        rev_time = t_end
    vel = np.where(ok, d.velocity + d.acceleration * np.nan_to_num(times), np.nan)
    return _Plan(vals, targets, times, full, t_end, rev_time, R, vel)


def _step_schedule(times: np.ndarray, dt_max: float):
    """Step sizes so that every finite sample time is a step boundary."""
    order = np.argsort(np.where(np.isfinite(times), times, np.inf))
    stops = [0.0]
    steps = []  # (dt, n) per interval between consecutive stops; n = 0 for a sample at t = 0
    if np.any(np.asarray(times)[np.isfinite(times)] <= 1e-15):
        stops.append(0.0)
        steps.append((dt_max, 0))
    for i in order:
        if np.isfinite(times[i]) and times[i] > stops[-1] + 1e-15:
            stops.append(float(times[i]))
    lengths = np.diff(stops[len(steps):]) if len(stops) > len(steps) + 1 else np.array([])
    # one common step when every interval is a whole multiple of it (constant-speed
    # drivers: the samples are evenly spaced in time); PyBullet's finite differences
    # need equal steps on both sides of a sample
    h_common = None
    if len(lengths):
        lmin = float(np.min(lengths))
        h = lmin / max(1, math.ceil(lmin / dt_max - 1e-9))
        k = lengths / h
        if np.all(np.abs(k - np.round(k)) < 1e-6 * np.maximum(k, 1.0)):
            h_common = h
    for a, b in zip(stops[len(steps):-1], stops[len(steps) + 1:], strict=True):
        if h_common is not None:
            n = max(1, int(round((b - a) / h_common)))
        else:
            n = max(1, math.ceil((b - a) / dt_max - 1e-9))
        steps.append(((b - a) / n, n))
    return order, stops, steps


# ----------------------------------------------------------------------------- results
class _Recorder:
    def __init__(self, st: SimTree, plan: _Plan):
        N = len(plan.values)
        B = len(st.body_names)
        J = len(st.mech.joints)
        P = len(st.prismatic)
        nan = np.nan
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
        self.times = plan.times

    def fail(self, st: SimTree, t_stop: float, reason: str) -> tuple[str, float]:
        """End a run at ``t_stop``: samples at or after it become NaN.  Returns the
        reason naming the driver value there (the prescribed one: the engine's own may
        be anywhere once it has diverged) and that value."""
        fail = float(st.driver_path(t_stop)[0])
        late = np.asarray(self.times) >= t_stop - 1e-15
        for arr in (self.theta, self.omega, self.alpha, self.slider_acc, self.effort,
                    self.force, self.normal, self.moment, self.viol, self.speed):
            arr[late] = np.nan
        return f"{reason} at driver {st.mech.driver.joint!r} = {_fmt_value(st, fail)}", fail


def _finish(st: SimTree, plan: _Plan, rec: _Recorder, engine: str, settings: str,
            reason: str | None, fail_value: float | None, wall: float, dt: float,
            notes=(), engine_readings=False, extra=None) -> EngineRun:
    mech = st.mech
    steps_per_rev = plan.rev_time / dt if dt > 0 else math.nan
    ex = {"prismatic_driver": isinstance(mech.driver_joint, Prismatic),
          "tree": st.tree_names, "chords": [c.name for c in st.chords],
          "analytic_chords": st.analytic_chords()}
    ex.update(extra or {})
    return EngineRun(
        case=mech.name, engine=engine, settings=settings, ok=reason is None, reason=reason,
        fail_value=fail_value, values=plan.values, driver_velocity=plan.velocity,
        driver_acceleration=np.full(len(plan.values), mech.driver.acceleration),
        measured_values=rec.measured,
        body_names=tuple(st.body_names), joint_names=tuple(j.name for j in mech.joints),
        prismatic_names=tuple(mech.joints[k].name for k in st.prismatic),
        theta=rec.theta, omega=rec.omega, alpha=rec.alpha, slider_acc=rec.slider_acc,
        drive_effort=rec.effort, joint_force=rec.force, normal=rec.normal, moment=rec.moment,
        loop_violation=rec.viol, speed_deviation=rec.speed,
        wall_per_rev=wall / plan.revolutions if plan.full else wall, timestep=dt,
        steps_per_rev=steps_per_rev, has_forces=st.has_mass, notes=tuple(notes),
        drive_effort_engine=rec.effort_engine if engine_readings else None,
        joint_force_engine=rec.force_engine if engine_readings else None, extra=ex)


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _fmt_value(st: SimTree, v: float) -> str:
    if isinstance(st.mech.driver_joint, Revolute):
        return f"{math.degrees(v):.4g} deg"
    return f"{v:.6g} m"


# ----------------------------------------------------------------------------- MuJoCo
class _MujocoSim:
    """A compiled MuJoCo model plus index tables and the analytic-convention readout."""

    def __init__(self, st: SimTree, settings: MujocoSettings, spec_hook=None):
        mujoco = require_mujoco()
        self.mj = mujoco
        self.st = st
        self.settings = settings
        spec = build_mjcf(st.mech, settings, tree=st)
        if spec_hook is not None:
            spec_hook(spec, st)
        self.model, self.compile_warnings = compile_spec(spec, settings)
        m = self.model
        self.data = mujoco.MjData(m)
        self.qadr = np.array([m.joint(tj.name).qposadr[0] for tj in st.joints])
        self.dadr = np.array([m.joint(tj.name).dofadr[0] for tj in st.joints])
        self.jid = np.array([m.joint(tj.name).id for tj in st.joints])
        self.bid = {b: (0 if b == st.ground else m.body(name).id)
                    for b, name in enumerate(st.body_names)}
        self.eq = [m.equality(ch.name).id for ch in st.chords]
        self.sites = [(m.site(site_name(ch.name, st.body_names[ch.body_b])).id,
                       m.site(site_name(ch.name, st.body_names[ch.body_a])).id)
                      for ch in st.chords]
        self.drive_dof = int(self.dadr[st.driver_tree])
        self.A = float(settings.armature)
        self.loads = [(self.bid[st.body_names.index(ld.body)], ld) for ld in st.mech.loads]

    # state ----------------------------------------------------------------
    def set_state(self, q, qd):
        d = self.data
        d.qpos[self.qadr] = q
        d.qvel[self.dadr] = qd

    def set_drive(self, a_prescribed: float):
        self.data.qfrc_applied[self.drive_dof] = self.A * self.st.driver_sigma * a_prescribed

    def apply_loads(self):
        d = self.data
        if not self.loads:
            return
        d.xfrc_applied[:] = 0.0
        for bid, ld in self.loads:
            F = np.array([ld.force[0], ld.force[1], 0.0])
            c = d.xipos[bid]
            if ld.point is not None:
                b = self.st.body_names.index(ld.body)
                p = self.st.mech.bodies[b].points[ld.point]
                P = d.xpos[bid] + d.xmat[bid].reshape(3, 3) @ np.array([p[0], p[1], 0.0])
            else:
                P = c
            d.xfrc_applied[bid, :3] = F
            d.xfrc_applied[bid, 3:] = np.cross(P - c, F) + np.array([0, 0, ld.torque])

    def loads_move(self) -> bool:
        """True when a load's moment about its body's centre of mass changes with the pose."""
        st = self.st
        for _, ld in self.loads:
            b = st.body_names.index(ld.body)
            if ld.point is None or np.allclose(st.mech.bodies[b].points[ld.point], st.com[b]):
                continue
            return True
        return False

    def driver_rate(self) -> float:
        return self.st.driver_sigma * float(self.data.qvel[self.drive_dof])

    def driver_value(self) -> float:
        return float(self.st.driver_value(self.data.qpos[self.qadr[self.st.driver_tree]]))

    def loop_violation(self) -> float:
        d = self.data
        v = 0.0
        for sb, sa in self.sites:
            v = max(v, float(np.linalg.norm(d.site_xpos[sb] - d.site_xpos[sa])))
        return v

    # readout --------------------------------------------------------------
    def readout(self, rec: _Recorder, i: int, a_prescribed: float):
        """Fill sample i from the current ``data`` (after ``mj_forward``)."""
        mj, st, m, d = self.mj, self.st, self.model, self.data
        mj.mj_rnePostConstraint(m, d)
        q = d.qpos[self.qadr]
        qd = d.qvel[self.dadr]
        qdd = d.qacc[self.dadr]
        th, om, al, org, _, _ = st.propagate(q[None], qd[None], qdd[None])
        rec.theta[i], rec.omega[i], rec.alpha[i] = th[0], om[0], al[0]
        rec.measured[i] = st.driver_value(q[st.driver_tree])
        tau = self.A * (st.driver_sigma * a_prescribed - qdd[st.driver_tree])
        rec.effort[i] = st.driver_sigma * tau
        mech = st.mech
        # tree joints: cfrc_int of the child = wrench by the parent on the child's subtree
        for t, tj in enumerate(st.joints):
            bc = self.bid[tj.child]
            c = d.subtree_com[m.body_rootid[bc]]
            torque, f = d.cfrc_int[bc, :3], d.cfrc_int[bc, 3:]
            k = tj.joint
            jt = mech.joints[k]
            if tj.kind == "hinge":
                rec.force[i, k] = tj.sigma * f[:2]
            else:
                sb = st.body_names.index(jt.slider)
                P = st.point_world(th, org, sb, st.mech.bodies[sb].points[jt.point])[0]
                mz = torque[2] - _cross(P - c[:2], f[:2])
                F = tj.sigma * f[:2]
                gb = st.body_names.index(jt.guide)
                ang = th[0, gb] + jt.direction
                n = np.array([-math.sin(ang), math.cos(ang)])
                p = st.prismatic.index(k)
                rec.force[i, k] = F
                rec.normal[i, p] = F @ n
                rec.moment[i, p] = tj.sigma * mz
                rec.slider_acc[i, p] = tj.sigma * qdd[t]
        for e, ch in zip(self.eq, st.chords, strict=True):
            rows = np.flatnonzero((d.efc_type == mj.mjtConstraint.mjCNSTR_EQUALITY)
                                  & (d.efc_id == e))
            rec.force[i, ch.joint] = d.efc_force[rows[:2]]
        rec.viol[i] = self.loop_violation()


def mujoco_instantaneous(mech: Mechanism, settings: MujocoSettings | None = None,
                         values=None, chords: str = "moving") -> EngineRun:
    """``mj_forward`` at the analytic state for each driver value (SI).

    Positions and velocities (and the driver's prescribed acceleration) come
    from :meth:`Linkage.kinematics`; MuJoCo supplies the accelerations and
    forces.  ``values`` default: the description's reference value.
    """
    settings = settings or MujocoSettings()
    st = SimTree(mech, chords=chords)
    sim = _MujocoSim(st, settings)
    lk = st.linkage
    vals = np.atleast_1d(np.asarray(mech.driver.value if values is None else values, float))
    kin = lk.kinematics(vals, on_singular="flag")
    q, qd, _ = st.coords(kin)
    plan = _Plan(vals, vals, np.zeros(len(vals)), False, 0.0, 0.0, 1, kin.velocity)
    rec = _Recorder(st, plan)
    t0 = time.perf_counter()
    for i in range(len(vals)):
        sim.set_state(q[i], qd[i])
        sim.set_drive(float(kin.acceleration[i]))
        sim.mj.mj_kinematics(sim.model, sim.data)
        sim.apply_loads()
        sim.mj.mj_forward(sim.model, sim.data)
        sim.readout(rec, i, float(kin.acceleration[i]))
        rec.speed[i] = sim.driver_rate() - kin.velocity[i]
    wall = time.perf_counter() - t0
    return _finish(st, plan, rec, "mujoco-instantaneous", settings.describe(), None, None,
                   wall, 0.0, notes=tuple(sim.compile_warnings))


#: Velocities above this (MuJoCo's own "huge value" threshold) count as divergence.
HUGE = 1e10


def _run_mujoco(st: SimTree, settings: MujocoSettings, plan: _Plan, max_violation: float,
                max_speed_error: float, spec_hook=None) -> EngineRun:
    mujoco = require_mujoco()
    msgs: list[str] = []
    old = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(msgs.append)  # no stderr noise, no MUJOCO_LOG.TXT
    try:
        r = _run_mujoco_inner(st, settings, plan, max_violation, max_speed_error, spec_hook)
    finally:
        mujoco.set_mju_user_warning(old)
    if msgs:
        from dataclasses import replace
        r = replace(r, notes=r.notes + tuple(f"MuJoCo warning: {x.strip()}" for x in msgs))
    return r


def _run_mujoco_inner(st: SimTree, settings: MujocoSettings, plan: _Plan,
                      max_violation: float, max_speed_error: float,
                      spec_hook=None) -> EngineRun:
    sim = _MujocoSim(st, settings, spec_hook)
    mj, m, d = sim.mj, sim.model, sim.data
    rec = _Recorder(st, plan)
    kin0 = st.kin_ref
    _, qd0, _ = st.coords(kin0)
    sim.set_state(np.zeros(len(st.joints)), qd0[0])
    dmech = st.mech.driver
    order, stops, steps = _step_schedule(plan.times, settings.timestep)
    sample_at = {}
    for i in order:
        if np.isfinite(plan.times[i]):
            sample_at.setdefault(max(float(plan.times[i]), 0.0) if plan.times[i] > 1e-15
                                 else 0.0, []).append(int(i))
    reason = fail = None
    t = 0.0
    dt_used = max((s[0] for s in steps), default=settings.timestep)
    vmax = max_violation * st.size
    wmax = max_speed_error

    def sample(tnow):
        _, vel, acc = st.driver_path(tnow)
        sim.set_drive(float(acc))
        sim.apply_loads()
        mj.mj_forward(m, d)
        for i in sample_at.get(tnow, ()):
            sim.readout(rec, i, float(acc))
            rec.speed[i] = sim.driver_rate() - float(vel)
        return float(vel)

    def check(tnow, vel) -> str | None:
        if not (np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.qvel))):
            return "non-finite state (simulation diverged)"
        if d.warning[mj.mjtWarning.mjWARN_BADQACC].number:
            return "MuJoCo reported bad qacc (simulation diverged)"
        v = sim.loop_violation()
        if v > vmax:
            return f"loop violation {v:.3g} m > {vmax:.3g} m"
        err = abs(sim.driver_rate() - vel)
        if err > wmax * max(abs(vel), abs(dmech.velocity), 1e-12):
            return f"driver rate off by {err:.3g} (> {wmax:g} relative)"
        return None

    # the prescribed driver acceleration is constant: qfrc_applied is set once
    sim.set_drive(float(dmech.acceleration))
    moving_loads = sim.loads_move()
    sim.apply_loads()
    step = mj.mj_step
    t0 = time.perf_counter()
    mj.mj_forward(m, d)
    for (h, n), t_stop in zip(steps, stops[1:], strict=True):
        m.opt.timestep = h
        qvel, qacc = d.qvel, d.qacc
        for _ in range(n):
            if moving_loads:
                sim.apply_loads()
            step(m, d)
            t += h
            if not (abs(qvel.sum()) < HUGE and abs(qacc.sum()) < HUGE):  # NaN, inf, huge
                reason = "non-finite or huge velocities (simulation diverged)"
                break
        if reason is None:
            t = t_stop  # remove the rounding of the summed steps
            vel = sample(t_stop)
            reason = check(t_stop, vel)
        if reason is not None:
            reason, fail = rec.fail(st, t_stop, reason)
            break
    wall = time.perf_counter() - t0
    m.opt.timestep = settings.timestep
    return _finish(st, plan, rec, "mujoco", settings.describe(), reason, fail, wall, dt_used,
                   notes=tuple(sim.compile_warnings))


# ----------------------------------------------------------------------------- front door
def run(mech: Mechanism, engine: str, settings=None, revolutions: int = 2, samples: int = 36,
        max_violation: float = 1e-3, max_speed_error: float = 1e-2,
        chords: str = "moving", spec_hook=None) -> EngineRun:
    """Simulate ``mech`` and sample it at the analytic sweep's input values.

    Parameters
    ----------
    engine
        ``"mujoco"`` or ``"pybullet"``.
    settings
        :class:`MujocoSettings` / :class:`PybulletSettings` (default: their defaults).
    revolutions
        Full turns to simulate (the last is sampled); ignored for a
        limited-range driver.
    samples
        Number of sweep points (``analytic.sweep.input_values(linkage, samples)``).
    max_violation
        Largest loop-closure gap tolerated, relative to the mechanism's size.
    max_speed_error
        Largest driver-rate error tolerated, relative to the driver's speed.
    chords
        Where loops are closed (:class:`sim_models.tree.SimTree`): ``"moving"``
        (default; revolute joints between two moving bodies where possible,
        PyBullet's loop forces then converge with dt^2) or ``"analytic"`` (the
        analytic tree's order, prismatic joints still kept in the tree).
    spec_hook
        MuJoCo only: ``hook(spec, sim_tree)`` edits the ``MjSpec`` after it is built
        and before it is compiled (e.g. to add contacts or geometry for a study).
    """
    st = SimTree(mech, chords=chords)
    if spec_hook is not None and engine.lower() != "mujoco":
        raise SimModelError("spec_hook edits an MjSpec: it applies to engine 'mujoco' only")
    plan = _plan(st, revolutions, samples)
    eng = engine.lower()
    if eng == "mujoco":
        return _run_mujoco(st, settings or MujocoSettings(), plan, max_violation,
                           max_speed_error, spec_hook)
    if eng == "pybullet":
        from .pybullet_sim import PybulletSettings, run_pybullet
        return run_pybullet(st, settings or PybulletSettings(), plan, max_violation,
                            max_speed_error)
    raise SimModelError(f"unknown engine {engine!r}; use 'mujoco' or 'pybullet'")


# ----------------------------------------------------------------------------- comparison
__all__ = ["EngineRun", "MujocoSettings", "mujoco_instantaneous", "run"]
