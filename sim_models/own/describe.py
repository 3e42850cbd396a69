"""The planar description (:class:`analytic.mechanism.Mechanism`) of a compiled MJCF
model, with the table that maps each model element to a description element and the
list of what the description does not model.

Body frames: a description body's frame has its origin at the root MuJoCo body's origin
(projected on the plane) and, at the reference configuration, the angle ``phi`` about
the plane's normal that makes each hinge's description angle equal ``s q`` (``q`` the
model's joint coordinate, ``s`` = +1 when the hinge axis points along the normal, -1
against): ``phi_child = phi_parent + s q_ref``.  A slide's displacement in the
description is the model's ``q`` (its line's origin set ``q_ref`` behind the slider's
reference point).  Points, centres and lines are given in those frames (m, rad).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from analytic.mechanism import Assembly, Body, Driver, Mechanism, Prismatic, Revolute
from analytic.motion_spec import FreeMotion, JointDamper, JointSpring, Motor

from .mjcf_read import Compiled, TreeJoint
from .plane import Plane
from .unmodelled import not_modelled as _not_modelled

#: Free-motion duration written into ``[motion]`` when the user gives none, s.
DEFAULT_DURATION = 1.0
#: The driver's rate written into ``[driver]`` when the model's state has none (rad/s or
#: m/s): a prescribed run needs a non-zero input rate; the user edits it.
DEFAULT_RATE = 1.0


@dataclass(frozen=True)
class Imported:
    """A user's model read: the description, the model-to-description table (rows of
    ``(model element, description element)``), what is not modelled (with its possible
    effect), notes (numbers the user should know), and the plane."""

    mechanism: Mechanism
    table: tuple[tuple[str, str], ...]
    not_modelled: tuple[str, ...]
    notes: tuple[str, ...]
    plane: Plane
    compiled: Compiled
    driver: TreeJoint
    signs: dict


def _rot(phi: float, v) -> tuple[float, float]:
    c, s = math.cos(phi), math.sin(phi)
    return (c * v[0] + s * v[1], -s * v[0] + c * v[1])


class _Frames:
    """Each group's frame: origin (plane coordinates) and reference angle ``phi``."""

    def __init__(self, c: Compiled, plane: Plane):
        self.plane = plane
        self.origin = {g.name: plane.xy(g.origin) for g in c.groups}
        self.origin["world"] = (0.0, 0.0)
        self.phi = {"world": 0.0}
        for j in c.joints:  # MuJoCo orders joints parent before child
            turn = plane.sign(j.axis) * j.q_ref if j.kind == "hinge" else 0.0
            self.phi[j.child] = self.phi[j.parent] + turn

    def local(self, group: str, p3) -> tuple[float, float]:
        x, y = self.plane.xy(np.asarray(p3))
        o = self.origin[group]
        return _rot(self.phi[group], (x - o[0], y - o[1]))


def _joints(c: Compiled, f: _Frames, points: dict, table: list) -> list:
    """The description's joints: one per hinge/slide, one pin per ``connect``."""
    out = []
    for j in c.joints:
        points[j.parent][j.name] = f.local(j.parent, j.anchor)
        if j.kind == "hinge":
            points[j.child][j.name] = f.local(j.child, j.anchor)
            out.append(Revolute(j.name, j.parent, j.name, j.child, j.name))
            s = "along" if f.plane.sign(j.axis) > 0 else "against (angle = -qpos)"
            table.append((f"joint {j.name!r} (hinge, axis {s} the normal)",
                          f"[[joints]] {j.name!r} revolute {j.parent} -> {j.child}"))
            continue
        # the line's origin q_ref behind the slider's point: the displacement is qpos
        points[j.parent][j.name] = f.local(j.parent, j.anchor - j.q_ref * j.axis)
        points[j.child][j.name] = f.local(j.child, j.anchor)
        u = f.plane.xy(j.axis)
        out.append(Prismatic(j.name, j.parent, j.name, math.atan2(u[1], u[0]) - f.phi[j.parent],
                             j.child, j.name, f.phi[j.child] - f.phi[j.parent]))
        table.append((f"joint {j.name!r} (slide)",
                      f"[[joints]] {j.name!r} prismatic, guide {j.parent}, slider {j.child}"))
    taken = {j.name for j in out}
    for cl in c.closures:
        name = cl.name if cl.name not in taken else f"{cl.name}_connect"
        points[cl.group1][name] = f.local(cl.group1, cl.p1)
        points[cl.group2][name] = f.local(cl.group2, cl.p2)
        out.append(Revolute(name, cl.group1, name, cl.group2, name))
        table.append((f"equality connect {cl.name!r} ({cl.how})",
                      f"[[joints]] {name!r} revolute {cl.group1} -> {cl.group2}"))
    return out


def _bodies(c: Compiled, f: _Frames, points: dict, table: list, notes: list) -> list[Body]:
    """Mass, centre and inertia about the axis through the centre (along the normal) of
    each group; a hinge's armature on a ground joint added to its body's inertia."""
    import mujoco
    n = f.plane.n
    arm = {j.child: (j, float(c.model.dof_armature[j.dof])) for j in c.joints
           if j.kind == "hinge" and j.parent == "world" and c.model.dof_armature[j.dof] > 0}
    out = [Body("world", points["world"])]
    for g in c.groups:
        if g.name == "world":
            continue
        welded = [mujoco.mj_id2name(c.model, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}"
                  for b in g.members if b != g.root]
        i_n = float(n @ g.inertia @ n) if g.mass > 0 else 0.0
        extra = ""
        if g.name in arm:
            jt, a = arm[g.name]
            i_n += a
            extra = f" + armature {a:g} kg m^2 of joint {jt.name!r}"
        com = f.local(g.name, g.com) if g.mass > 0 else (0.0, 0.0)
        if len(points[g.name]) == 1 and g.mass > 0:  # a pendulum: its centre gives it a size
            points[g.name]["com" if "com" not in points[g.name] else "centre_of_mass"] = com
        out.append(Body(g.name, points[g.name], g.mass, com, i_n))
        table.append((f"body {g.name!r}" + (f" + welded {welded}" if welded else ""),
                      f"[bodies.{g.name}] mass {g.mass:.6g} kg, inertia {i_n:.6g} kg m^2"
                      f"{extra}"))
        coupling = float(np.hypot(f.plane.e1 @ g.inertia @ n, f.plane.e2 @ g.inertia @ n))
        if g.mass > 0 and coupling > 1e-9 * i_n:
            notes.append(f"body {g.name!r}: its inertia couples the plane's rotation with the "
                         f"out-of-plane ones (product of inertia {coupling:.3g} kg m^2, "
                         f"{coupling / i_n:.3g} of the in-plane inertia); the joints carry "
                         "the out-of-plane moments, the planar motion is unchanged")
    return out


def build(c: Compiled, plane: Plane, driver: TreeJoint, duration: float = DEFAULT_DURATION
          ) -> Imported:
    """The description of the compiled model (see the module)."""
    f = _Frames(c, plane)
    points: dict[str, dict] = {g.name: {} for g in c.groups}
    points.setdefault("world", {})
    table: list[tuple[str, str]] = []
    notes: list[str] = []
    joints = _joints(c, f, points, table)
    bodies = _bodies(c, f, points, table, notes)
    gravity, gnote = _gravity(c, plane)
    notes.append(gnote)
    table.append(("option gravity", f"gravity = [{gravity[0]:.6g}, {gravity[1]:.6g}] m/s^2 "
                                    "(in-plane part)"))
    s_drv = plane.sign(driver.axis) if driver.kind == "hinge" else 1.0
    rate = driver.qd_ref * s_drv
    table.append((f"{c.config}: qpos of {driver.name!r}",
                  f"[driver] value, [motion] value (rate {rate:g} from qvel)"))
    springs, dampers, motors, skipped = _elements(c, plane, table)
    motion = FreeMotion(driver.name, driver.q_ref * s_drv, rate, duration, 201,
                        tuple(springs), tuple(dampers), tuple(motors))
    hints = Assembly(points={f"{j.body_b}.{j.point_b}": _world2(f, j.body_b, j.point_b, points)
                             for j in joints if isinstance(j, Revolute)},
                     angles={g: p for g, p in f.phi.items() if g != "world"})
    name = c.model.names[:c.model.names.index(b"\0")].decode() or "model"
    mech = Mechanism(
        name=name, ground="world", bodies=tuple(bodies), joints=tuple(joints),
        driver=Driver(driver.name, driver.q_ref * s_drv, rate if rate else DEFAULT_RATE),
        gravity=gravity, assembly=hints, source=c.path, motion=motion,
        description=f"Imported from {c.path} at {c.config} by xval import.")
    signs = {j.name: (plane.sign(j.axis) if j.kind == "hinge" else 1.0) for j in c.joints}
    return Imported(mech, tuple(table), tuple(skipped + _not_modelled(c)), tuple(notes),
                    plane, c, driver, signs)


def _world2(f: _Frames, body: str, point: str, points: dict) -> tuple[float, float]:
    x, y = _rot(-f.phi[body], points[body][point])
    o = f.origin[body]
    return (x + o[0], y + o[1])


def _gravity(c: Compiled, plane: Plane):
    import mujoco
    g = np.array(c.model.opt.gravity, dtype=float)
    if c.model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_GRAVITY:
        return (0.0, 0.0), "gravity is disabled in the model (disableflags)"
    out = float(g @ plane.n)
    return ((float(g @ plane.e1), float(g @ plane.e2)),
            f"gravity {g.tolist()} m/s^2: in-plane part {np.hypot(g @ plane.e1, g @ plane.e2):.6g}"
            f" m/s^2 kept, out-of-plane part {out:.6g} m/s^2 (along the normal) carried by "
            "the joints, not modelled")


def _elements(c: Compiled, plane: Plane, table: list):
    """Joint damping, joint stiffness (about ``springref``) and constant-effort motors;
    the actuators the description cannot hold are returned as not-modelled lines."""
    import mujoco
    m = c.model
    springs, dampers, motors, skipped = [], [], [], []
    by_id = {j.id: j for j in c.joints}
    for j in c.joints:
        s = plane.sign(j.axis) if j.kind == "hinge" else 1.0
        if m.dof_damping[j.dof] > 0:
            dampers.append(JointDamper(j.name, float(m.dof_damping[j.dof])))
            table.append((f"joint {j.name!r} damping", f"[[dampers]] joint {j.name!r}"))
        if m.jnt_stiffness[j.id] > 0:
            ref = float(m.qpos_spring[m.jnt_qposadr[j.id]]) * s
            springs.append(JointSpring(j.name, float(m.jnt_stiffness[j.id]), ref))
            table.append((f"joint {j.name!r} stiffness, springref",
                          f"[[springs]] joint {j.name!r}"))
    for a in range(m.nu):
        aname = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a) or f"actuator{a}"
        constant = (m.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT
                    and m.actuator_dyntype[a] == mujoco.mjtDyn.mjDYN_NONE
                    and m.actuator_gaintype[a] == mujoco.mjtGain.mjGAIN_FIXED
                    and m.actuator_biastype[a] == mujoco.mjtBias.mjBIAS_NONE)
        if not constant:
            skipped.append(f"actuator {aname!r} (not a constant-effort motor on a joint): its "
                           "force acts on the linkage in the engine, not in the reference")
            continue
        j = by_id[int(m.actuator_trnid[a, 0])]
        u = float(c.ctrl[a])
        if m.actuator_ctrllimited[a]:
            u = float(np.clip(u, *m.actuator_ctrlrange[a]))
        effort = float(m.actuator_gear[a, 0] * m.actuator_gainprm[a, 0]) * u
        effort *= plane.sign(j.axis) if j.kind == "hinge" else 1.0
        motors.append(Motor(j.name, effort))
        table.append((f"actuator {aname!r} (motor, ctrl {u:g})",
                      f"[[motors]] joint {j.name!r} effort {effort:g}"))
    return springs, dampers, motors, skipped
