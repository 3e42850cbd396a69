"""MuJoCo on the user's own MJCF file, judged against its imported description.

The session compiles the user's file as it is (its timestep, integrator, solver,
iterations, tolerance, ``solref``/``solimp``, armature, damping, springs, contacts and
limits) and adds only the harness's drive in the prescribed mode: the driver joint's
armature raised by :attr:`OwnMujocoSettings.armature` and ``qfrc_applied = A a`` (the
way :class:`sim_models.engines.mujoco.driven.MujocoSession` drives the harness's own models).

Coordinates: the model's joints are mapped onto the description's spanning tree
(:class:`sim_models.builders.tree.SimTree`) linearly.  A body's rotation about the plane's normal
since the reference is ``sum s_j (qpos_j - qpos_ref_j)`` over the hinges on its path in
the model (``s_j`` = +1 for an axis along the normal, -1 against); a tree hinge's
coordinate is its child's rotation less its parent's, a slide's the model's ``qpos``
(the importer made them equal).  Velocities and accelerations map with the same matrix.
The user's tree must be the description's spanning tree (checked; refused otherwise).
"""

from __future__ import annotations

import dataclasses
from typing import ClassVar

import numpy as np

from ..builders.tree import SimTree, wrap
from ..engines.mujoco.driven import MujocoSession
from ..engines.protocol import EngineRefusal
from ..engines.settings import EngineSettings
from .describe import Imported
from .mjcf_read import load_spec

#: The drive's armature relative to the driver's diagonal of the model's mass matrix at
#: the reference (added before compiling).  The harness's own models take a fixed 1e8
#: kg m^2 with their own solver tolerance 1e-12; a user's model keeps its own solver
#: settings, and its constraint solve degrades as the ratio grows.  Measured on the
#: hand-written models of tests/sim_models/own at MuJoCo's default solver (worst
#: alpha / pin force error over a revolution, of peak), ratio 1e5 / 1e6 / 1e7 / 1e9:
#: four-bar with connect solref 0.002, solimp 0.9999: 3.2e-3 / 3.7e-4 / 1.4e-4 /
#: 1.9e-4 alpha, 7e-4 / 7e-5 / 7e-6 / 1.4e-6 forces; the simulator example (default
#: solref): 7.9e-4 / 4.6e-4 / 3.3e-3 / 0.73 alpha, 7e-4 / 5e-3 / 0.044 / 4.6 forces.  1e6
#: keeps the input acceleration within effort/A ~ 3e-5 of its prescribed value.
DRIVE_RATIO = 1e6


@dataclasses.dataclass(frozen=True)
class OwnMujocoSettings(EngineSettings):
    """The user's file and the options MuJoCo compiled from it (read, not chosen):
    ``timestep`` the model's own (s); ``armature`` the drive's (prescribed mode only)."""

    file: str = ""
    timestep: float = 1e-3
    armature: float = 0.0
    options: str = ""
    #: settings set over the file's for this run (``xval tune``): ``(key, value)`` pairs
    #: of :data:`TUNED_KEYS`, applied to the model before compiling (:func:`apply_tuned`)
    tuned: tuple = ()
    engine_name: ClassVar[str] = "mujoco"

    def validate(self) -> None:  # read from a compiled model: nothing to range-check
        return None

    def describe(self) -> str:
        return f"the user's model {self.file} with its own options: {self.options}"


#: What ``xval tune`` may set over a user's file, as the MJCF attributes spell them:
#: ``<option integrator iterations tolerance>`` and every equality constraint's
#: ``solref``, ``solimp``.
TUNED_KEYS = ("integrator", "iterations", "tolerance", "solref", "solimp")
#: MJCF's integrator spellings -> MuJoCo's enum names.
INTEGRATORS = {"Euler": "mjINT_EULER", "RK4": "mjINT_RK4", "implicit": "mjINT_IMPLICIT",
               "implicitfast": "mjINT_IMPLICITFAST"}


def apply_tuned(spec, tuned) -> None:
    """Set ``tuned`` (``(key, value)`` pairs of :data:`TUNED_KEYS`) on ``spec`` (an
    ``MjSpec``): the solver's options, and ``solref``/``solimp`` on every equality
    constraint (what ``xval tune --write-model`` writes into the file)."""
    import mujoco
    for key, value in tuned:
        if key == "integrator":
            spec.option.integrator = getattr(mujoco.mjtIntegrator, INTEGRATORS[value])
        elif key in ("iterations", "tolerance"):
            setattr(spec.option, key, value)
        elif key in ("solref", "solimp"):
            for eq in spec.equalities:
                setattr(eq, key, list(value))
        else:
            raise ValueError(f"{key!r} is not a setting of a user's model ({TUNED_KEYS})")


def option_items(m) -> dict[str, str]:
    """The compiled model's solver options and its equality constraints' ``solref`` and
    ``solimp`` (and any joint's armature), ``key -> value`` as written in the settings
    line and kept in a baseline's model identity."""
    import mujoco
    o = m.opt
    out = {"timestep": f"{o.timestep:g}",
           "integrator": mujoco.mjtIntegrator(o.integrator).name[6:],
           "solver": mujoco.mjtSolver(o.solver).name[6:], "iterations": str(o.iterations),
           "tolerance": f"{o.tolerance:g}", "cone": mujoco.mjtCone(o.cone).name[7:]}
    for e in range(m.neq):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_EQUALITY, e) or f"equality{e}"
        out[f"{name}.solref"] = "(" + ",".join(f"{x:g}" for x in m.eq_solref[e]) + ")"
        out[f"{name}.solimp"] = "(" + ",".join(f"{x:g}" for x in m.eq_solimp[e]) + ")"
    arm = [(j, float(m.dof_armature[j])) for j in range(m.nv) if m.dof_armature[j] > 0]
    if arm:
        out["armature"] = ",".join(f"dof{j}:{a:g}" for j, a in arm)
    return out


def model_options(m) -> str:
    """:func:`option_items` in one line."""
    return " ".join(f"{k}={v}" for k, v in option_items(m).items())


def own_settings(imp: Imported, prescribed: bool = True,
                 timestep: float | None = None, tuned: tuple = ()) -> OwnMujocoSettings:
    """The settings record of a run on the user's model: its file, its own options and
    (prescribed) the drive's armature, :data:`DRIVE_RATIO` times the driver's diagonal
    of the mass matrix at the reference; ``tuned``: settings over the file's
    (:func:`apply_tuned`; the options line then reads the model with them)."""
    import mujoco
    m, d = imp.compiled.model, imp.compiled.data
    full = np.zeros((m.nv, m.nv))
    mujoco.mj_crb(m, d)
    mujoco.mj_fullM(m, d, full)
    arm = DRIVE_RATIO * float(full[imp.driver.dof, imp.driver.dof]) if prescribed else 0.0
    step = f"; timestep {timestep:g} s given for this run" if timestep else ""
    if tuned:
        spec = load_spec(str(imp.compiled.path), imp.compiled.closes)
        apply_tuned(spec, tuned)
        m = spec.compile()
        step += "; tuned over the file: " + ", ".join(k for k, _v in tuned)
    return OwnMujocoSettings(file=str(imp.compiled.path),
                             timestep=float(timestep or m.opt.timestep),
                             armature=arm, options=model_options(m) + step + (
                                 f"; drive: armature {arm:.3g} on {imp.driver.name!r}"
                                 if prescribed else ""), tuned=tuple(tuned))


class Mapping:
    """The linear map between the model's coordinates and the tree's (module doc)."""

    def __init__(self, tree: SimTree, imp: Imported):
        c = imp.compiled
        names = tree.body_names
        self.qadr = np.array([c.model.jnt_qposadr[j.id] for j in c.joints])
        self.dadr = np.array([j.dof for j in c.joints])
        self.q_ref = np.array([j.q_ref for j in c.joints])
        sign = np.array([imp.signs[j.name] if j.kind == "hinge" else 0.0 for j in c.joints])
        # Pm: body rotation from the model's hinge coordinates (paths in the model's tree)
        by_child = {j.child: i for i, j in enumerate(c.joints)}
        parent_of = {j.child: j.parent for j in c.joints}
        pm = np.zeros((len(names), len(c.joints)))
        for b, bname in enumerate(names):
            x = bname
            while x != "world":
                pm[b, by_child[x]] = sign[by_child[x]]
                x = parent_of[x]
        phi = dict(imp.mechanism.assembly.angles)
        self.dphi = np.array([float(wrap(tree.theta_ref[b] - phi.get(n, 0.0)))
                              for b, n in enumerate(names)])
        model_idx = {j.name: i for i, j in enumerate(c.joints)}
        t = np.zeros((len(tree.joints), len(c.joints)))
        self.slide_off = np.zeros(len(tree.joints))
        for i, tj in enumerate(tree.joints):
            if tj.name not in model_idx:
                raise EngineRefusal(f"{c.path}: the model's tree differs from the "
                                    f"description's spanning tree (joint {tj.name!r} is a "
                                    "loop closure in the model)")
            if tj.kind == "hinge":
                t[i] = pm[tj.child] - pm[tj.parent]
            else:
                t[i, model_idx[tj.name]] = tj.sigma
                self.slide_off[i] = tj.sigma * tj.q_ref
        self.T, self.pm, self.sign, self.tree = t, pm, sign, tree
        self.hinge = np.array([tj.kind == "hinge" for tj in tree.joints])
        self.model_idx = model_idx
        self.model_joints = c.joints

    def tree_q(self, qpos: np.ndarray) -> np.ndarray:
        """(K, nt) tree coordinates of (K, nq) model positions."""
        dq = qpos[:, self.qadr] - self.q_ref
        rot = dq @ self.pm.T - self.dphi                       # (K, B) rotation since ref
        out = dq @ self.T.T - self.slide_off
        st = self.tree
        for i, tj in enumerate(st.joints):
            if tj.kind == "hinge":
                out[:, i] = rot[:, tj.child] - rot[:, tj.parent]
        return out

    def model_state(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Model joint positions and velocities (in the model's joint order) of tree
        coordinates ``q, qd`` (nt,)."""
        st = self.tree
        rot = st.path @ q + self.dphi
        om = st.path @ qd
        pos, vel = self.q_ref.copy(), np.zeros(len(self.q_ref))
        for i, j in enumerate(self.model_joints):
            b = st.body_names
            if j.kind == "hinge":
                c, p = b.index(j.child), b.index(j.parent)
                pos[i] += self.sign[i] * (rot[c] - rot[p])
                vel[i] = self.sign[i] * (om[c] - om[p])
            else:
                k = next(k for k, tj in enumerate(st.joints) if tj.name == j.name)
                pos[i] = st.joints[k].q_ref + st.joints[k].sigma * q[k]
                vel[i] = st.joints[k].sigma * qd[k]
        return pos, vel


class OwnMujocoSession(MujocoSession):
    """MuJoCo on the user's file (module doc); readout in the description's plane."""

    name = "mujoco"

    def __init__(self, tree: SimTree, imp: Imported, settings: OwnMujocoSettings):
        self.imp = imp
        super().__init__(tree, settings)

    def mujoco_settings(self):
        return self.settings

    def _build(self) -> None:
        import mujoco
        imp, st = self.imp, self.tree
        # the drive's armature added before compiling, as the harness's own models have
        # it: the compiled constraint weights (dof/body_invweight0) then see it
        spec = load_spec(str(imp.compiled.path), imp.compiled.closes)
        apply_tuned(spec, self.settings.tuned)
        self.A = float(self.settings.armature)
        if self.A:
            spec.joint(imp.driver.name).armature += self.A
        self.model = m = spec.compile()
        self.data = mujoco.MjData(m)
        self.map = Mapping(st, imp)
        self.drive_dof = int(imp.driver.dof)
        self.acc = float(st.mech.driver.acceleration)
        self._equality = int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)
        self._badqacc = int(mujoco.mjtWarning.mjWARN_BADQACC)
        self.loads, self.moving_loads, self.max_contacts = [], False, 0
        self.plane = imp.plane
        self.active: dict[str, float] = {}
        self.eq = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_EQUALITY, ch.name)
                   for ch in st.chords]
        names = [j.name for j in imp.compiled.joints]
        self.qadr = self.map.qadr  # the base class's record() reads qpos[qadr] raw
        self.dadr = self.map.dadr
        bid = {g.name: g.root for g in imp.compiled.groups}
        self.child_bid = np.array([bid[st.body_names[tj.child]] for tj in st.joints])
        self.child_root = np.array([m.body_rootid[b] for b in self.child_bid], dtype=int)
        # +1 when the description's tree child is the model's child of that joint
        self.same_way = np.array([
            1.0 if imp.compiled.joints[names.index(tj.name)].child == st.body_names[tj.child]
            else -1.0 for tj in st.joints])

    def extra(self) -> dict:
        return {"file": str(self.imp.compiled.path), "ngeom": int(self.model.ngeom),
                "max_contacts": self.max_contacts, "active": dict(self.active)}

    def record(self, t: float):
        """The base class's record, then what acted besides the linkage at ``t``: joint
        limits, contacts, actuators with a force, tendons (first time of each, s)."""
        out = super().record(t)
        self._note_active(t)
        return out

    def _note_active(self, t: float) -> None:
        mj, m, d = self.mj, self.model, self.data
        seen = []
        for r in range(d.nefc):
            if d.efc_type[r] == mj.mjtConstraint.mjCNSTR_LIMIT_JOINT:
                jn = mj.mj_id2name(m, mj.mjtObj.mjOBJ_JOINT, d.efc_id[r])
                seen.append(f"limit of joint {jn!r}")
            elif d.efc_type[r] == mj.mjtConstraint.mjCNSTR_LIMIT_TENDON:
                seen.append(f"limit of tendon {d.efc_id[r]}")
        for c in range(d.ncon):
            g1, g2 = d.contact[c].geom
            seen.append(f"contact of geoms {g1} and {g2}")
        for a in range(m.nu):
            if d.actuator_force[a] != 0.0:
                name = mj.mj_id2name(m, mj.mjtObj.mjOBJ_ACTUATOR, a) or f"actuator{a}"
                seen.append(f"actuator {name!r}")
        if m.ntendon and np.any(m.tendon_stiffness + m.tendon_damping > 0):
            seen.append("tendon springs/dampers")
        for s in seen:
            self.active.setdefault(s, t)

    def set_state(self, q, qd) -> None:
        pos, vel = self.map.model_state(np.asarray(q, float), np.asarray(qd, float))
        self.data.qpos[self.map.qadr] = pos
        self.data.qvel[self.map.dadr] = vel

    def set_drive(self, a_prescribed: float) -> None:
        # the importer made the driver's coordinate the model's own (sign +1)
        self.data.qfrc_applied[self.drive_dof] = self.A * a_prescribed

    def apply_loads(self, d=None) -> None:  # the user's model has no harness loads
        return None

    def state(self):
        d = self.data
        q = self.map.tree_q(np.array(d.qpos)[None])[0]
        return q, self.map.T @ d.qvel[self.map.dadr]

    def reset(self, t: float, h: float) -> None:
        mj, m, d = self.mj, self.model, self.data
        mj.mj_resetData(m, d)
        q, qd, (_, _, acc) = self.analytic_state(t)
        self.set_state(q, qd)
        self.set_drive(acc)
        mj.mj_forward(m, d)  # the model's own timestep: never changed

    def advance(self, t: float, h: float, n: int) -> str | None:
        self.model.opt.timestep = h  # the run's step (the model's, shortened to the samples)
        return super().advance(t, h, n)

    def convert(self, times, raws, rows, rec):
        """The description's conventions of K raw records (motions, drive effort, pin
        forces projected on the plane)."""
        st, mech, pl = self.tree, self.tree.mech, self.plane
        qpos, qvel, qacc, cfrc, com, efc_type, efc_id, efc_force, acc = \
            zip(*(r[:9] for r in raws), strict=True)
        dadr = self.map.dadr
        q = self.map.tree_q(np.array(qpos))
        qd = np.array(qvel)[:, dadr] @ self.map.T.T
        qdd = np.array(qacc)[:, dadr] @ self.map.T.T
        prop, gap, rate = rec.put_motions(rows, times, q, qd, qdd)
        th, org = prop[0], prop[3]
        tau = self.A * (np.array(acc) - np.array(qacc)[:, self.drive_dof])
        K, J, P = len(raws), len(mech.joints), len(st.prismatic)
        force, normal, moment = np.zeros((K, J, 2)), np.zeros((K, P)), np.zeros((K, P))
        cf = np.array(cfrc)[:, self.child_bid]
        c3 = np.array(com)[:, self.child_root]
        e = np.stack([pl.e1, pl.e2])
        for ti, tj in enumerate(st.joints):
            jt = mech.joints[tj.joint]
            f = (cf[:, ti, 3:] @ e.T) * tj.sigma * self.same_way[ti]
            force[:, tj.joint] = f
            if tj.kind == "hinge":
                continue
            sb = st.body_names.index(jt.slider)
            pw = st.point_world(th, org, sb, mech.bodies[sb].points[jt.point])
            cc = c3[:, ti] @ e.T
            mz = cf[:, ti, :3] @ pl.n - _cross(pw - cc, cf[:, ti, 3:] @ e.T)
            ang = th[:, st.body_names.index(jt.guide)] + jt.direction
            p = st.prismatic.index(tj.joint)
            normal[:, p] = -f[:, 0] * np.sin(ang) + f[:, 1] * np.cos(ang)
            moment[:, p] = tj.sigma * self.same_way[ti] * mz
        loops = self._loop_forces(efc_type, efc_id,
                                  [self._project(f, t) for f, t in zip(efc_force, efc_type,
                                                                      strict=True)])
        for ci, ch in enumerate(st.chords):
            force[:, ch.joint] = loops[:, ci]
        rec.put_forces_many(rows, force, tau, normal, moment)
        return gap, rate

    def _project(self, f, types):
        """The equality rows' forces with each connect's 3 world rows replaced by its
        force on body2 (minus MuJoCo's on body1), projected on the plane, in the first two
        rows (what :meth:`_loop_forces` reads)."""
        f = np.array(f, dtype=float)
        rows = np.flatnonzero(np.asarray(types) == self._equality)
        for k in range(0, len(rows) - 2, 3):
            w = -f[rows[k:k + 3]]
            f[rows[k]], f[rows[k + 1]] = w @ self.plane.e1, w @ self.plane.e2
        return f


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


__all__ = ["INTEGRATORS", "TUNED_KEYS", "Mapping", "OwnMujocoSession", "OwnMujocoSettings",
           "apply_tuned", "own_settings"]



def run_prescribed(imp: Imported, request=None, timestep: float | None = None,
                   tuned: tuple = ()):
    """The user's model driven along the description's prescribed motion: an
    :class:`sim_models.runs.engine_run.EngineRun` against ``compile_linkage(imp.mechanism)``
    (``tuned``: settings over the file's, :func:`apply_tuned`)."""
    from ..engines.protocol import RunRequest, compile_linkage, drive, plan_samples
    request = dataclasses.replace(request or RunRequest(), chords="analytic")
    # the model's own tree: its joints first (description order), its connects the chords
    tree = compile_linkage(imp.mechanism, chords="analytic")
    plan = plan_samples(tree, request.revolutions, request.samples)
    with OwnMujocoSession(tree, imp, own_settings(imp, timestep=timestep,
                                                  tuned=tuned)) as session:
        return tree, drive(session, plan, request)


def file_settings(m) -> dict:
    """The settings ``xval tune`` may change, as the compiled MuJoCo model ``m`` holds
    them (the file's own values): timestep (s), integrator (MJCF name), iterations,
    tolerance, and the first equality constraint's ``solref``/``solimp`` (None without
    one)."""
    import mujoco

    names = {int(getattr(mujoco.mjtIntegrator, e)): k for k, e in INTEGRATORS.items()}
    out = {"timestep": float(m.opt.timestep), "integrator": names[int(m.opt.integrator)],
           "iterations": int(m.opt.iterations), "tolerance": float(m.opt.tolerance),
           "solref": None, "solimp": None}
    if m.neq:
        out["solref"] = tuple(float(x) for x in m.eq_solref[0])
        out["solimp"] = tuple(float(x) for x in m.eq_solimp[0])
    return out
