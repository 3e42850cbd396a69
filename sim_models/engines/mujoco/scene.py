"""Scene variants of the MuJoCo model (:attr:`MujocoSettings.scene`): unneeded parts added
to the project's minimal scene, for the scene-economy study.

* ``contacts``: contact flag on, every geom collidable (contype = conaffinity = 1), each
  link's geoms in its own z layer (4 capsule radii apart, as the links of a real planar
  linkage are stacked) and ``exclude`` pairs for the bodies sharing a joint: contacts are
  detected but none occur;
* ``contacts-same-plane``: the same with every link in the plane z = 0 (the coupler's
  capsule sweeps over the ground pivot O4);
* ``contacts-no-excludes``: same plane and no excludes (capsules overlap at the pins);
* ``extra-visual``: 24 extra non-colliding geoms per moving link (boxes, cylinders,
  ellipsoids along it), contacts off;
* ``extra-collision``: those geoms collidable, in layers, contacts on, pin excludes.
"""

from __future__ import annotations

import math

import numpy as np

from analytic import Mechanism

from ...builders.mjcf import require_mujoco
from ...builders.tree import SimTree


def _jointed_pairs(mech: Mechanism) -> list[tuple[str, str]]:
    """Body pairs sharing a joint, with the ground called ``world`` (the MJCF name)."""
    pairs = set()
    for j in mech.joints:
        a, b = (j.guide, j.slider) if hasattr(j, "guide") else (j.body_a, j.body_b)
        a = "world" if a == mech.ground else a
        b = "world" if b == mech.ground else b
        pairs.add(tuple(sorted((a, b))))
    return sorted(pairs)


def _contacts(spec, st: SimTree, layered: bool = True, excludes: bool = True) -> None:
    mujoco = require_mujoco()
    mech = st.mech
    layer = {b.name: (0 if b.name == mech.ground else i + 1)
             for i, b in enumerate(x for x in mech.bodies if x.name != mech.ground)}
    layer["world"] = 0
    layer[mech.ground] = 0
    spec.option.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    dz = 4 * 0.01 * st.size
    for g in spec.geoms:
        g.contype, g.conaffinity = 1, 1
        z = dz * layer.get(g.parent.name, 0) if layered else 0.0
        if z:
            ft = list(g.fromto)
            if np.isnan(ft[0]):
                g.pos = [g.pos[0], g.pos[1], g.pos[2] + z]
            else:
                g.fromto = [ft[0], ft[1], ft[2] + z, ft[3], ft[4], ft[5] + z]
    if excludes:
        for a, b in _jointed_pairs(mech):
            spec.add_exclude(bodyname1=a, bodyname2=b)


def _extra(spec, st: SimTree, collide: bool) -> None:
    mujoco = require_mujoco()
    mech = st.mech
    radius = 0.01 * st.size
    types = [mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_CYLINDER,
             mujoco.mjtGeom.mjGEOM_ELLIPSOID]
    for body in mech.bodies:
        if body.name == mech.ground:
            continue
        bs = spec.body(body.name)
        pts = np.array(list(body.points.values()), float)
        if len(pts) < 2:
            pts = np.vstack([pts, pts + [radius, 0.0]])
        for k in range(24):
            p, q = pts[k % (len(pts) - 1)], pts[k % (len(pts) - 1) + 1]
            c = p + (k + 0.5) / 24 * (q - p)
            ang = math.atan2(q[1] - p[1], q[0] - p[0])
            bs.add_geom(type=types[k % 3], size=[0.8 * radius, 0.5 * radius, 0.4 * radius],
                        pos=[c[0], c[1], 0.0],
                        quat=[math.cos(ang / 2), 0, 0, math.sin(ang / 2)],
                        contype=int(collide), conaffinity=int(collide),
                        rgba=[0.7, 0.7, 0.2, 0.5])


def _extra_collision(spec, st):
    _extra(spec, st, True)
    _contacts(spec, st)


#: scene name -> edit of the MjSpec (after it is built, before it is compiled)
SCENE_EDITS = {
    "minimal": None,
    "contacts": _contacts,
    "contacts-same-plane": lambda spec, st: _contacts(spec, st, layered=False),
    "contacts-no-excludes": lambda spec, st: _contacts(spec, st, layered=False,
                                                       excludes=False),
    "extra-visual": lambda spec, st: _extra(spec, st, False),
    "extra-collision": _extra_collision,
}


def apply_scene(spec, st: SimTree, scene: str) -> None:
    """Edit ``spec`` into scene variant ``scene`` (``"minimal"``: unchanged)."""
    edit = SCENE_EDITS[scene]
    if edit is not None:
        edit(spec, st)
