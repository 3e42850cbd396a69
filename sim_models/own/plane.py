"""The plane of a compiled model and the checks that make it a planar one-degree-of-
freedom linkage: the driver, every hinge axis parallel to the driver's (or to the first
hinge's, for a slide driver), every slide axis in the plane, every loop closed at the
reference configuration, and exactly one degree of freedom.

The plane's frame: ``n`` along the driver's hinge axis (so a body's rate about ``n`` has
the sign of the model's joint coordinates); ``e2`` against the in-plane part of gravity
(so the description's gravity is ``(0, -g)``), else along the world axis most in the
plane; ``e1 = e2 x n``, so ``(e1, e2, n)`` is right-handed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analytic.errors import DescriptionError

from .mjcf_read import Compiled, TreeJoint

#: Largest angle (rad) between a hinge axis and the plane's normal, or between a slide
#: axis and the plane: the issue's 1e-9 rad.  A tilt of 1e-9 rad moves a point of a 1 m
#: link 1e-9 m out of the plane, below the analytic solver's loop residual (1e-12 of the
#: size) times the size scale only by 1e3, and far below any modelling intent.
AXIS_TOLERANCE = 1e-9
#: Largest gap of a loop closure at the reference configuration, relative to the
#: mechanism's size: keyframes written by hand or printed by MuJoCo carry ~7 significant
#: figures, so a closed loop read from one is closed to ~1e-7 of its size; 1e-6 accepts
#: that and refuses a real opening (a 2 mm gap in a 0.4 m linkage is 5e-3).
GAP_TOLERANCE = 1e-6
#: Relative size below which a singular value of the closures' in-plane Jacobian is
#: zero (the Jacobian's entries are lengths of the order of the linkage's size).
RANK_TOLERANCE = 1e-9


@dataclass(frozen=True)
class Plane:
    """The plane: unit normal ``n`` and in-plane axes ``e1``, ``e2`` (world)."""

    n: np.ndarray
    e1: np.ndarray
    e2: np.ndarray

    def xy(self, p: np.ndarray) -> tuple[float, float]:
        """In-plane coordinates of world point ``p`` (m)."""
        return (float(p @ self.e1), float(p @ self.e2))

    def sign(self, axis: np.ndarray) -> float:
        """+1 when a hinge axis points along ``n``, -1 when against it."""
        return 1.0 if axis @ self.n >= 0 else -1.0


def choose_driver(c: Compiled, driver: str | None) -> TreeJoint:
    """``--driver`` by name, else the one joint an actuator acts on."""
    import mujoco
    m = c.model
    names = [j.name for j in c.joints]
    if driver is not None:
        for j in c.joints:
            if j.name == driver:
                return j
        raise DescriptionError(f"--driver {driver!r}: no such hinge or slide joint; the "
                               f"joints are {names}", c.path)
    acted = sorted({int(m.actuator_trnid[a, 0]) for a in range(m.nu)
                    if m.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT})
    if len(acted) != 1:
        said = ("no actuated joint" if not acted else
                f"{len(acted)} actuated joints {[names[j] for j in acted]}")
        raise DescriptionError(f"{said}: name the input with --driver JOINT (joints: "
                               f"{names})", c.path)
    return next(j for j in c.joints if j.id == acted[0])


def plane_of(c: Compiled, driver: TreeJoint) -> Plane:
    """The plane (see the module) and the planarity check of every joint axis."""
    hinges = [j for j in c.joints if j.kind == "hinge"]
    if not hinges:
        raise DescriptionError("no hinge joint: the plane of the linkage is undefined",
                               c.path)
    ref = driver if driver.kind == "hinge" else hinges[0]
    n = ref.axis / np.linalg.norm(ref.axis)
    for j in c.joints:
        a = j.axis / np.linalg.norm(j.axis)
        if j.kind == "hinge":
            tilt = float(np.arctan2(np.linalg.norm(np.cross(a, n)), abs(a @ n)))
            what = "hinge axis is tilted"
        else:
            tilt = float(abs(np.arcsin(np.clip(a @ n, -1, 1))))
            what = "slide axis leaves the plane"
        if tilt > AXIS_TOLERANCE:
            raise DescriptionError(f"joint {j.name!r}: {what} by {tilt:.3g} rad from joint "
                                   f"{ref.name!r}'s axis {_vec(n)} (tolerance "
                                   f"{AXIS_TOLERANCE:g} rad): not a planar mechanism",
                                   c.path)
    g = np.array(c.model.opt.gravity, dtype=float)
    g_in = g - (g @ n) * n
    if np.linalg.norm(g_in) > 1e-12 * max(np.linalg.norm(g), 1.0):
        e2 = -g_in / np.linalg.norm(g_in)
    else:
        axis = np.eye(3)[int(np.argmin(np.abs(n)))]
        e2 = axis - (axis @ n) * n
        e2 /= np.linalg.norm(e2)
    return Plane(n, np.cross(e2, n), e2)


def _vec(v) -> str:
    return "(" + ", ".join(f"{x:.6g}" for x in v) + ")"


def size_of(c: Compiled) -> float:
    """The mechanism's size: the largest distance between two of its joint points (m)."""
    pts = [j.anchor for j in c.joints] + [p for cl in c.closures for p in (cl.p1, cl.p2)]
    pts = np.array(pts)
    return float(max(np.linalg.norm(pts[:, None] - pts[None], axis=-1).max(), 1e-12))


def check_closures(c: Compiled) -> None:
    """Every ``connect`` holds its two points together at the reference configuration."""
    size = size_of(c)
    for cl in c.closures:
        gap = float(np.linalg.norm(cl.p1 - cl.p2))
        if gap > GAP_TOLERANCE * size:
            raise DescriptionError(
                f"equality connect {cl.name!r} ({cl.how}, bodies {cl.group1!r} and "
                f"{cl.group2!r}): the loop is open by {gap * 1e3:.4g} mm at the model's "
                f"configuration ({c.config}); tolerance {GAP_TOLERANCE:g} of the linkage's "
                f"size {size:.4g} m. Move the site or the body so the points meet", c.path)


def check_one_dof(c: Compiled, plane: Plane, driver: TreeJoint) -> None:
    """Exactly one degree of freedom: the joints less the rank of the closures' in-plane
    Jacobian (``mj_jac`` at the reference).  Otherwise the independent joints named."""
    import mujoco
    m, d = c.model, c.data
    rows = []
    for cl in c.closures:
        j1, j2 = np.zeros((3, m.nv)), np.zeros((3, m.nv))
        mujoco.mj_jac(m, d, j1, None, cl.p1, cl.body1)
        mujoco.mj_jac(m, d, j2, None, cl.p2, cl.body2)
        rows += [plane.e1 @ (j1 - j2), plane.e2 @ (j1 - j2)]
    jac = np.array(rows).reshape(len(rows), m.nv)
    sv = np.linalg.svd(jac, compute_uv=False) if rows else np.zeros(0)
    rank = int((sv > RANK_TOLERANCE * max(sv.max(initial=0.0), 1e-300)).sum())
    dof = m.nv - rank
    if dof == 1:
        return
    names = {j.dof: j.name for j in c.joints}
    if dof == 0:
        raise DescriptionError("0 degrees of freedom: the closures lock every joint "
                               f"({sorted(names.values())})", c.path)
    null = np.linalg.svd(jac)[2][rank:] if rows else np.eye(m.nv)
    free = _independent(c, null, driver)
    hint = (" (a URDF holds no loop: close each with --close LINK_A:x,y,z=LINK_B:x,y,z)"
            if str(c.path).lower().endswith(".urdf") else "")
    raise DescriptionError(f"{dof} degrees of freedom: joints {free} move independently "
                           "(a driven linkage has one; close another loop or fix a "
                           f"joint){hint}", c.path)


def _independent(c: Compiled, null: np.ndarray, driver: TreeJoint) -> list[str]:
    """A set of joints whose coordinates fix the mechanism (columns of the closures'
    null space ``null`` (dof, nv) of full rank), taken greedily: the driver first, then
    the joints on the ground, then the others, in the model's order."""
    order = sorted(c.joints, key=lambda j: (j is not driver, j.parent != "world", j.id))
    picked: list[TreeJoint] = []
    for j in order:
        cols = null[:, [p.dof for p in picked + [j]]]
        if np.linalg.matrix_rank(cols, tol=RANK_TOLERANCE) == len(picked) + 1:
            picked.append(j)
        if len(picked) == null.shape[0]:
            break
    return [j.name for j in picked]
