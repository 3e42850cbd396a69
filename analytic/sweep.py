"""Full-cycle sweeps, singular and limit positions, Grashof classification.

Columns of :attr:`SweepResult.frame` (SI unless the name says otherwise)
-------------------------------------------------------------------------
``input``                     driver value: deg (revolute) or m (prismatic)
``input_velocity``            rad/s or m/s
``input_acceleration``        rad/s^2 or m/s^2
``<body>.angle_deg``          body angle, deg, wrapped to (-180, 180]
``<body>.omega``              rad/s, ccw positive
``<body>.alpha``              rad/s^2, ccw positive
``<body>.<point>.x|y``        m, world frame
``<body>.<point>.vx|vy``      m/s
``<body>.<point>.ax|ay``      m/s^2
``<joint>.s|v|a``             prismatic displacement m, velocity m/s, acceleration m/s^2
``<joint>.fx|fy``             joint force by body_a (the guide) on body_b (the slider), N
``<joint>.normal|moment``     prismatic normal force N and couple N m on the slider
``drive.torque`` or ``drive.force``   drive effort on body_b / the slider, N m or N
``drive.power``               W, positive when the driver does work
``power_residual``            drive power - (dKE/dt - load power), W (rounding level)
``jacobian_condition``        condition number of the loop Jacobian in the unknowns
``jacobian_det``              its determinant normalised by its column norms, [-1, 1]
``transmission_deg.<joint>``  transmission angle at a dyad's inner joint, deg
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .errors import AssemblyError
from .kinematics import Kinematics, Linkage
from .kinetostatics import Forces
from .mechanism import Prismatic, Revolute
from .positions import feasible_ranges
from .tolerances import SINGULAR_CONDITION


@dataclass
class SweepResult:
    """A sweep over input values: arrays, table, events and classification."""

    kinematics: Kinematics
    forces: Forces | None
    frame: pd.DataFrame
    events: pd.DataFrame
    full_cycle: bool
    feasible: list[tuple[float, float]]
    grashof: str | None = None
    notes: list[str] = field(default_factory=list)


def input_values(linkage: Linkage, points: int) -> tuple[np.ndarray, bool, list]:
    """The sweep's input values: a full turn from the reference angle when the
    crank can turn fully, else the feasible interval holding the reference value
    (the branch is held, so the sweep ends near the limit positions)."""
    v0 = linkage.mech.driver.value
    feas = feasible_ranges(linkage.topo, signs=getattr(linkage.positions, "signs", None))
    if linkage.driver_is_revolute and len(feas) == 1 and \
            feas[0][1] - feas[0][0] >= 2 * math.pi * (1 - 1e-9):
        return v0 + 2 * math.pi * np.arange(points) / points, True, feas
    for lo, hi in feas:
        if lo <= v0 <= hi:
            # stay a hair inside the limit positions, where the Jacobian is singular
            pad = 1e-6 * (hi - lo)
            return np.linspace(lo + pad, hi - pad, points), False, feas
    raise AssemblyError(f"mechanism {linkage.mech.name!r}: the reference input is not in a "
                        f"feasible range {feas}", v0, feas)


def _crossings(x: np.ndarray, y: np.ndarray, periodic: bool) -> list[float]:
    """Input values where ``y`` changes sign, linearly interpolated.

    Samples within 1e-9 of the series' peak of zero are round-off, not sign: a stretch
    of them (a parallelogram's translating coupler) yields at most one crossing, between
    the significant samples on either side.
    """
    n = len(y)
    peak = float(np.max(np.abs(y))) if n else 0.0
    sig = np.flatnonzero(np.abs(y) > 1e-9 * peak) if peak > 0 else np.array([], int)
    out = []
    if len(sig) < 2:
        return out
    pairs = list(zip(sig[:-1], sig[1:], strict=True))
    if periodic:
        pairs.append((sig[-1], sig[0]))
    period = (x[-1] - x[0]) + (x[1] - x[0]) if periodic else 0.0
    for i, k in pairs:
        y0, y1 = y[i], y[k]
        if y0 * y1 < 0:
            x1 = x[k] if k > i else x[k] + period
            v = x[i] + (x1 - x[i]) * y0 / (y0 - y1)
            out.append(float(v - period if periodic and v > x[-1] + (x[1] - x[0]) / 2
                             else v))
    return out


def find_events(linkage: Linkage, kin: Kinematics, periodic: bool) -> pd.DataFrame:
    """Singular (dead-centre / change-point) and limit positions over a sweep.

    * ``singular``: the loop Jacobian's determinant changes sign or its condition
      number exceeds :data:`SINGULAR_CONDITION`: the output cannot be driven
      there (dead centre) or the linkage may switch branch (change point);
    * ``limit``: a body's angular velocity or a slider's velocity changes sign: the
      extreme (toggle) positions of rockers and the dead centres of sliders;
    * ``min_transmission``: the least transmission angle of each dyad.
    """
    topo = linkage.topo
    rev = linkage.driver_is_revolute
    x = kin.value
    conv = np.degrees if rev else (lambda v: v)
    rows = []
    for v in _crossings(x, kin.determinant, periodic):
        rows.append(("singular", "loop Jacobian", float(conv(v)),
                     "determinant changes sign: dead centre or change point"))
    hi = np.flatnonzero(~(kin.condition < SINGULAR_CONDITION))
    for i in hi:
        rows.append(("singular", "loop Jacobian", float(conv(x[i])),
                     f"condition number {kin.condition[i]:.3g}"))
    djb = {linkage.mech.driver_joint.body_a, linkage.mech.driver_joint.body_b}
    for b, name in enumerate(topo.body_names):
        if topo.group_of[b] < 0 or name in djb:
            continue
        # one row per rotation group (bodies of a group share omega)
        if any(topo.group_of[o] == topo.group_of[b] for o in range(b)):
            continue
        for v in _crossings(x, kin.omega[:, b] * np.sign(kin.velocity), periodic):
            rows.append(("limit", name, float(conv(v)), "omega = 0 (extreme angle)"))
    for j in topo.prismatic:
        jn = topo.joint_names[j]
        if j == topo.driver_joint:
            continue
        _, sd, _ = kin.slider(jn)
        for v in _crossings(x, sd * np.sign(kin.velocity), periodic):
            rows.append(("limit", jn, float(conv(v)), "slider velocity = 0 (dead centre)"))
    for jn, tr in kin.transmission.items():
        dev = np.abs(90.0 - tr)
        i = int(np.argmax(dev))
        rows.append(("min_transmission", jn, float(conv(x[i])),
                     f"transmission angle {tr[i]:.3f} deg"))
    return pd.DataFrame(rows, columns=["kind", "where", "input", "detail"])


def grashof(linkage: Linkage) -> str | None:
    """Grashof classification of a four-bar (four bodies, four revolute joints).

    Returns e.g. ``"Grashof crank-rocker"``, ``"Grashof double-crank"``,
    ``"Grashof double-rocker"``, ``"change point"`` or ``"non-Grashof triple-rocker"``;
    ``None`` for other mechanisms.  The driven link is the *input*; "crank" names
    the links that turn fully.
    """
    mech, topo = linkage.mech, linkage.topo
    if len(mech.bodies) != 4 or len(mech.joints) != 4 or \
            not all(isinstance(j, Revolute) for j in mech.joints):
        return None
    lengths = {}
    for b, name in enumerate(topo.body_names):
        js = [k for k, j in enumerate(mech.joints) if name in j.bodies]
        p, q = (topo.attach(js[0], b), topo.attach(js[1], b))
        lengths[name] = float(np.hypot(*(p - q)))
    L = sorted(lengths.values())
    s, p_, q_, l_ = L
    shortest = min(lengths, key=lengths.get)
    tol = 1e-9 * l_
    if abs((s + l_) - (p_ + q_)) <= tol:
        return "change point"
    if s + l_ > p_ + q_:
        return "non-Grashof triple-rocker"
    if shortest == mech.ground:
        return "Grashof double-crank"
    ground_links = [j.body_b if j.body_a == mech.ground else j.body_a
                    for j in mech.joints if mech.ground in j.bodies]
    if shortest in ground_links:
        dj = mech.driver_joint
        driven = dj.body_b if dj.body_a == mech.ground else dj.body_a
        role = "crank-rocker" if shortest == driven else "rocker-crank (input rocks)"
        return f"Grashof {role}"
    return "Grashof double-rocker"


def _wrap_deg(a: np.ndarray) -> np.ndarray:
    d = np.degrees(a)
    return 180.0 - np.mod(180.0 - d, 360.0)


def to_frame(linkage: Linkage, kin: Kinematics, frc: Forces | None) -> pd.DataFrame:
    """The sweep table (columns in the module docstring)."""
    mech, topo = linkage.mech, linkage.topo
    rev = linkage.driver_is_revolute
    cols: dict[str, np.ndarray] = {
        "input": np.degrees(kin.value) if rev else kin.value,
        "input_velocity": kin.velocity, "input_acceleration": kin.acceleration}
    for b, body in enumerate(mech.bodies):
        if b == topo.ground:
            continue
        cols[f"{body.name}.angle_deg"] = _wrap_deg(kin.theta[:, b])
        cols[f"{body.name}.omega"] = kin.omega[:, b]
        cols[f"{body.name}.alpha"] = kin.alpha[:, b]
        for pn in body.points:
            p, v, a = kin.point(body.name, pn)
            for k, arr in (("x", p[:, 0]), ("y", p[:, 1]), ("vx", v[:, 0]), ("vy", v[:, 1]),
                           ("ax", a[:, 0]), ("ay", a[:, 1])):
                cols[f"{body.name}.{pn}.{k}"] = arr
    for j in topo.prismatic:
        jn = topo.joint_names[j]
        s, v, a = kin.slider(jn)
        cols[f"{jn}.s"], cols[f"{jn}.v"], cols[f"{jn}.a"] = s, v, a
    if frc is not None:
        for jt in mech.joints:
            F = frc.joint_force[jt.name]
            cols[f"{jt.name}.fx"], cols[f"{jt.name}.fy"] = F[:, 0], F[:, 1]
            if isinstance(jt, Prismatic):
                cols[f"{jt.name}.normal"] = frc.normal[jt.name]
                cols[f"{jt.name}.moment"] = frc.moment[jt.name]
        cols["drive.torque" if rev else "drive.force"] = frc.effort
        cols["drive.power"] = frc.power
        cols["power_residual"] = frc.power_residual
    cols["jacobian_condition"] = kin.condition
    cols["jacobian_det"] = kin.determinant
    for jn, tr in kin.transmission.items():
        cols[f"transmission_deg.{jn}"] = tr
    return pd.DataFrame(cols)


def sweep(linkage: Linkage, points: int = 360, forces: bool | None = None,
          values: np.ndarray | None = None) -> SweepResult:
    """Solve the mechanism over a full cycle (or its feasible input range).

    Parameters
    ----------
    points
        Number of input values (a full turn excludes its end, which equals its start).
    forces
        Compute kinetostatics; default: when every moving body has a mass.
    values
        Explicit input values (SI) instead of the automatic range.

    The driver's velocity and acceleration are the description's at every point
    (a constant-speed crank by default).  Singular points do not raise here:
    they are flagged in ``events`` and in ``jacobian_condition``.
    """
    if points < 2:
        raise ValueError(f"a sweep needs at least 2 points, got {points}")
    if values is None:
        values, full, feas = input_values(linkage, points)
    else:
        values, full, feas = np.asarray(values, float), False, []
    kin = linkage.kinematics(values, on_singular="flag")
    if forces is None:
        forces = linkage.mech.has_mass
    frc = linkage.forces(kin) if forces else None
    notes = []
    if not full and linkage.driver_is_revolute:
        notes.append("the input link cannot turn fully; the sweep covers the feasible range "
                     + ", ".join(f"[{math.degrees(a):.4f}, {math.degrees(b):.4f}] deg"
                                 for a, b in feas) + " on the assembled branch")
    return SweepResult(kin, frc, to_frame(linkage, kin, frc), find_events(linkage, kin, full),
                       full, feas, grashof(linkage), notes)
