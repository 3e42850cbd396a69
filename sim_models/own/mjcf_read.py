"""A user's MJCF file read through MuJoCo's own compiler: the compiled model at its
reference configuration (``qpos0`` or a keyframe), its rigid groups, joints and loop
closures in world coordinates.

Every quantity is taken from the compiled :class:`mujoco.MjModel` (so defaults, classes,
``childclass``, includes, ``inertiafromgeom``, ``fromto`` geoms, quaternions, Euler angles
and ``angle="degree"`` are what MuJoCo made of them) and from ``mj_kinematics`` at the
reference configuration (positions in m, world frame).  Nothing here is planar yet:
:mod:`sim_models.own.plane` checks planarity and projects.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from analytic.errors import DescriptionError


@dataclass(frozen=True)
class Group:
    """A rigid body of the linkage: a MuJoCo body with its one joint (or the world), with
    the bodies welded to it (no joint of their own).  Mass kg, ``com`` m (world, at the
    reference), ``inertia`` the 3x3 tensor about the centre of mass in world axes, kg m^2;
    ``origin`` the root body's frame origin (world, m)."""

    name: str
    root: int                 # MuJoCo body id of the group's root (0: the world)
    members: tuple[int, ...]  # MuJoCo body ids
    mass: float
    com: np.ndarray
    inertia: np.ndarray
    origin: np.ndarray


@dataclass(frozen=True)
class TreeJoint:
    """A hinge or slide joint: its MuJoCo id, name, kind, the groups it joins (parent,
    child), its anchor and axis in world at the reference and its coordinate there."""

    id: int
    name: str
    kind: str                 # "hinge" | "slide"
    parent: str
    child: str
    anchor: np.ndarray
    axis: np.ndarray
    q_ref: float
    qd_ref: float
    dof: int


@dataclass(frozen=True)
class Closure:
    """A ``connect`` equality: the point on ``body1``'s group and the point on ``body2``'s
    group (world, at the reference) that MuJoCo holds together; ``how`` says whether
    by ``anchor`` or by sites."""

    name: str
    group1: str
    group2: str
    body1: int
    body2: int
    p1: np.ndarray
    p2: np.ndarray
    how: str


@dataclass(frozen=True)
class Compiled:
    """The compiled model at its reference configuration."""

    path: str
    model: object             # mujoco.MjModel
    data: object              # mujoco.MjData at the reference (mj_kinematics done)
    config: str               # "qpos0" or "keyframe 'NAME'"
    groups: tuple[Group, ...]
    joints: tuple[TreeJoint, ...]
    closures: tuple[Closure, ...]
    ctrl: np.ndarray
    closes: tuple[Close, ...] = ()


@dataclass(frozen=True)
class Close:
    """A loop closure given on the command line (a URDF cannot hold one): point ``pa`` of
    link ``a`` pinned to point ``pb`` of link ``b`` (m, link frames); added to the model
    as two sites and a ``connect`` equality between them."""

    a: str
    pa: tuple[float, float, float]
    b: str
    pb: tuple[float, float, float]

    @property
    def name(self) -> str:
        return f"close_{self.a}_{self.b}"


def _check_utf8(path: str) -> None:
    """MuJoCo's reader keeps a name's bytes as written and its names are UTF-8: a file in
    another encoding (e.g. ISO-8859-1 with an accented name) is one line here, not an
    undecodable name later."""
    with open(path, "rb") as fh:
        data = fh.read()
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise DescriptionError(f"not UTF-8 text (byte 0x{data[e.start]:02x} at offset "
                               f"{e.start}): MuJoCo reads names as UTF-8; save the file as "
                               "UTF-8", path) from None


def load_spec(path: str, closes: tuple[Close, ...] = ()):
    """The model's ``mujoco.MjSpec`` (MJCF, or URDF through MuJoCo's URDF reader) with
    the ``closes`` added; a file MuJoCo cannot read is one line naming it."""
    import mujoco
    if not os.path.isfile(path):
        raise DescriptionError("no such file", path)
    _check_utf8(path)
    try:
        spec = mujoco.MjSpec.from_file(path)
    except ValueError as e:  # MuJoCo's parser error, several lines: keep them on one
        raise DescriptionError("MuJoCo cannot read the file: " + " ".join(str(e).split()),
                               path) from None
    for k, cl in enumerate(closes):
        sites = []
        for end, (link, p) in enumerate(((cl.a, cl.pa), (cl.b, cl.pb))):
            body = spec.worldbody if link == "world" else spec.body(link)
            if body is None:
                raise DescriptionError(f"--close {k + 1}: no link {link!r} in the model",
                                       path)
            sites.append(body.add_site(name=f"{cl.name}:{end}", pos=list(p)).name)
        eq = spec.add_equality(name=cl.name, type=mujoco.mjtEq.mjEQ_CONNECT,
                               objtype=mujoco.mjtObj.mjOBJ_SITE)
        eq.name1, eq.name2 = sites
    return spec


def compile_file(path: str, closes: tuple[Close, ...] = ()):
    """The compiled model (:func:`load_spec`), or one line naming the file and
    MuJoCo's reason."""
    import warnings
    spec = load_spec(path, closes)
    try:
        # MuJoCo's compile-time warnings (a singular inertia at qpos0) come back as
        # Python warnings: the checks that follow say what is wrong in one line
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            return spec.compile()
    except ValueError as e:
        raise DescriptionError("MuJoCo cannot compile the file: "
                               + " ".join(str(e).split()), path) from None


def _name(m, objtype, i: int, fallback: str) -> str:
    import mujoco
    return mujoco.mj_id2name(m, objtype, i) or fallback


def reference_state(m, path: str, keyframe: str | None):
    """``(data, config, ctrl)``: MjData at ``qpos0`` or the named keyframe with
    ``mj_kinematics`` done."""
    import mujoco
    d = mujoco.MjData(m)
    ctrl = np.zeros(m.nu)
    config = "qpos0"
    if keyframe is not None:
        k = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, keyframe)
        if k < 0:
            names = [_name(m, mujoco.mjtObj.mjOBJ_KEY, i, "") for i in range(m.nkey)]
            raise DescriptionError(f"no keyframe {keyframe!r}; the model has "
                                   f"{[n for n in names if n] or 'none named'}", path)
        d.qpos[:] = m.key_qpos[k]
        d.qvel[:] = m.key_qvel[k]
        ctrl = np.array(m.key_ctrl[k], dtype=float)
        config = f"keyframe {keyframe!r}"
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    return d, config, ctrl


def _groups(m, d, path: str) -> tuple[list[Group], dict[int, str]]:
    """The rigid groups: each body with a joint roots one, a body without joints joins
    its parent's.  A body with several joints, or a ball/free joint, is refused."""
    import mujoco
    owner: dict[int, int] = {0: 0}
    for b in range(1, m.nbody):
        bname = _name(m, mujoco.mjtObj.mjOBJ_BODY, b, f"body{b}")
        n = int(m.body_jntnum[b])
        if n > 1:
            js = [_name(m, mujoco.mjtObj.mjOBJ_JOINT, int(m.body_jntadr[b]) + i, "?")
                  for i in range(n)]
            raise DescriptionError(f"body {bname!r} has {n} joints {js}: a planar linkage "
                                   "body has one joint to its parent (add a body per joint)",
                                   path)
        owner[b] = b if n == 1 else owner[int(m.body_parentid[b])]
    names = {r: ("world" if r == 0 else
                 _name(m, mujoco.mjtObj.mjOBJ_BODY, r, f"body{r}")) for r in set(owner.values())}
    groups = []
    for r in sorted(set(owner.values())):
        members = tuple(b for b in range(m.nbody) if owner[b] == r)
        groups.append(_mass_properties(d, m, names[r], r, members))
    return groups, {b: names[r] for b, r in owner.items()}


def _mass_properties(d, m, name: str, root: int, members: tuple[int, ...]) -> Group:
    """Mass, centre and world inertia tensor about the centre of the group's bodies
    (the compiled ``body_mass``, ``xipos``, ``body_inertia`` in the ``ximat`` frame)."""
    masses = np.array([m.body_mass[b] for b in members])
    total = float(masses.sum())
    pos = np.array([d.xipos[b] for b in members])
    com = (masses @ pos) / total if total > 0 else np.array(d.xpos[root], dtype=float)
    inertia = np.zeros((3, 3))
    for b, mb, p in zip(members, masses, pos, strict=True):
        rot = d.ximat[b].reshape(3, 3)
        r = p - com
        inertia += rot @ np.diag(m.body_inertia[b]) @ rot.T
        inertia += mb * (r @ r * np.eye(3) - np.outer(r, r))
    return Group(name, root, members, total, com, inertia, np.array(d.xpos[root], dtype=float))


def _tree_joints(m, d, owner: dict[int, str], path: str) -> list[TreeJoint]:
    import mujoco
    out = []
    kinds = {int(mujoco.mjtJoint.mjJNT_HINGE): "hinge", int(mujoco.mjtJoint.mjJNT_SLIDE): "slide"}
    for j in range(m.njnt):
        name = _name(m, mujoco.mjtObj.mjOBJ_JOINT, j, f"joint{j}")
        kind = kinds.get(int(m.jnt_type[j]))
        if kind is None:
            what = "free" if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE else "ball"
            raise DescriptionError(f"joint {name!r} is a {what} joint: a planar linkage has "
                                   "hinge and slide joints only", path)
        b = int(m.jnt_bodyid[j])
        out.append(TreeJoint(j, name, kind, owner[int(m.body_parentid[b])], owner[b],
                             np.array(d.xanchor[j], dtype=float),
                             np.array(d.xaxis[j], dtype=float),
                             float(d.qpos[m.jnt_qposadr[j]]), float(d.qvel[m.jnt_dofadr[j]]),
                             int(m.jnt_dofadr[j])))
    return out


def _closures(m, d, owner: dict[int, str], path: str) -> list[Closure]:
    """The active ``connect`` equalities; any other equality refused by name."""
    import mujoco
    out = []
    site = int(mujoco.mjtObj.mjOBJ_SITE)
    for e in range(m.neq):
        name = _name(m, mujoco.mjtObj.mjOBJ_EQUALITY, e, f"equality{e}")
        if not m.eq_active0[e]:
            continue  # inactive at the start: not part of the linkage (listed as such)
        if m.eq_type[e] != mujoco.mjtEq.mjEQ_CONNECT:
            kind = mujoco.mjtEq(int(m.eq_type[e])).name.removeprefix("mjEQ_").lower()
            raise DescriptionError(f"equality {name!r} is a {kind} constraint: the planar "
                                   "description holds pin closures (connect) only; "
                                   "replace it by a connect, or deactivate it", path)
        o1, o2 = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
        if int(m.eq_objtype[e]) == site:
            b1, b2 = int(m.site_bodyid[o1]), int(m.site_bodyid[o2])
            p1, p2 = np.array(d.site_xpos[o1]), np.array(d.site_xpos[o2])
            how = (f"sites {_name(m, mujoco.mjtObj.mjOBJ_SITE, o1, str(o1))!r}, "
                   f"{_name(m, mujoco.mjtObj.mjOBJ_SITE, o2, str(o2))!r}")
        else:
            b1, b2 = o1, o2
            p1 = d.xpos[b1] + d.xmat[b1].reshape(3, 3) @ m.eq_data[e, 0:3]
            p2 = d.xpos[b2] + d.xmat[b2].reshape(3, 3) @ m.eq_data[e, 3:6]
            how = "anchor"
        out.append(Closure(name, owner[b1], owner[b2], b1, b2, np.array(p1, dtype=float),
                           np.array(p2, dtype=float), how))
    return out


def read_mjcf(path: str, keyframe: str | None = None, closes: tuple[Close, ...] = ()
              ) -> Compiled:
    """The compiled model of ``path`` (with ``closes`` added) at its reference
    configuration (see the module)."""
    m = compile_file(path, closes)
    d, config, ctrl = reference_state(m, path, keyframe)
    groups, owner = _groups(m, d, path)
    joints = _tree_joints(m, d, owner, path)
    closures = _closures(m, d, owner, path)
    return Compiled(path, m, d, config, tuple(groups), tuple(joints), tuple(closures), ctrl,
                    tuple(closes))
