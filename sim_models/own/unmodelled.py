"""What a compiled model holds that the planar description does not model, each with its
possible effect on the motion (the header of an imported description)."""

from __future__ import annotations

from .mjcf_read import Compiled


def not_modelled(c: Compiled) -> list[str]:
    """One line per element kind the reference leaves out (joint names listed)."""
    import mujoco
    m = c.model
    out = []

    def names(pred) -> list[str]:
        return [j.name for j in c.joints if pred(j)]

    if fl := names(lambda j: m.dof_frictionloss[j.dof] > 0):
        out.append(f"friction loss on joints {fl}: dry friction slows the engine's motion "
                   "and can stop it")
    if lim := names(lambda j: m.jnt_limited[j.id]):
        out.append(f"limits on joints {lim}: if reached, the engine's motion stops or "
                   "rebounds there")
    arm = names(lambda j: m.dof_armature[j.dof] > 0 and not (j.kind == "hinge"
                                                              and j.parent == "world"))
    if arm:
        out.append(f"armature on joints {arm} (a rotor inertia on a joint between two moving "
                   "bodies, or on a slide): the engine's motion is slower under the same "
                   "forces")
    if m.ntendon:
        out.append(f"{m.ntendon} tendon(s): their springs, damping and limits act in the "
                   "engine only")
    contact = [g for g in range(m.ngeom) if m.geom_bodyid[g] != 0
               and (m.geom_contype[g] or m.geom_conaffinity[g])]
    if contact and not m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT:
        out.append(f"contacts: {len(contact)} geoms of moving bodies can collide "
                   "(contype/conaffinity); a contact during the motion changes it")
    inactive = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_EQUALITY, e) or f"equality{e}"
                for e in range(m.neq) if not m.eq_active0[e]]
    if inactive:
        out.append(f"inactive equalities {inactive}: left out; activating one changes the "
                   "linkage")
    return out
