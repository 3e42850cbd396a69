"""MuJoCo model of a :class:`~analytic.mechanism.Mechanism`, built with typed ``MjSpec`` calls.

No XML is written or parsed: every element comes from ``add_body`` /
``add_joint`` / ``add_site`` / ``add_geom`` / ``add_equality`` on a
:class:`mujoco.MjSpec` (``spec.to_xml()`` gives MJCF for the viewer if wanted).

Model
-----
* Kinematic tree = :class:`sim_models.builders.tree.SimTree` (the analytic spanning tree with
  prismatic joints preferred); each body frame at its reference pose, so
  ``qpos = 0`` is the assembled reference state; hinges about z at the joint
  point, slides along the line direction.  Names: bodies and joints keep the
  description's names; the world body is the ground.
* Loops closed at each chord (a revolute joint) by an equality ``connect``
  between site ``"<joint>@<body_b>"`` (body1) and ``"<joint>@<body_a>"``
  (body2); its ``efc_force`` (3 rows, world axes) is the force **by body_a on
  body_b**, the analytic convention.
* Explicit inertials (``ipos`` = centre of mass, ``inertia = [0.6 I, 0.6 I, I]``:
  only ``Izz`` acts in a planar motion; the in-plane values are 20% above the
  lamina's ``I/2`` so that MuJoCo's triangle inequality ``A + B >= C`` still holds
  after ``to_xml`` prints them to 6 digits); massless bodies get
  :data:`sim_models.builders.tree.MASS_FLOOR` of the largest mass (see that module).
* Contacts disabled (flag and ``contype = conaffinity = 0``), gravity
  ``mech.gravity`` (0 unless the description asks), no limits, no actuators.
  Visual capsules join each body's consecutive points (massless: the compiler
  does not infer inertia from geoms).
* Drive: a huge ``armature`` on the driven joint.  Then
  ``(M + A) qacc = ... + qfrc_applied`` makes the driver follow
  ``qacc = qfrc_applied / A`` to O(1/A), and the effort the driver exerts on
  the mechanism is ``A (a_prescribed - qacc)`` (``qfrc_applied = A a_prescribed``
  is set by :mod:`sim_models.runs.driven`).  Auto-reset on bad accelerations is
  disabled so a divergence shows as non-finite state and can be reported.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from analytic import Mechanism

from ..engines import ranges
from ..engines.protocol import EngineRefusal, EngineSettings
from .model_numbers import snap
from .tree import SimModelError, SimTree

#: Oldest MuJoCo accepted: before 3.7.0 connect/weld constraints lacked the
#: Jdot*v term and loop accelerations came out near zero (ENGINE_NOTES.md).
MIN_MUJOCO = (3, 7, 0)


class EngineVersionError(SimModelError):
    """The installed engine is too old (or missing) for these models."""


def _version_tuple(v: str) -> tuple[int, ...]:
    out = []
    for part in v.split(".")[:3]:
        num = "".join(ch for ch in part if ch.isdigit())
        out.append(int(num) if num else 0)
    return tuple(out)


def require_mujoco():
    """Import MuJoCo, refusing versions older than :data:`MIN_MUJOCO`."""
    try:
        import mujoco
    except ImportError as e:  # pragma: no cover - environment problem
        raise EngineVersionError(f"MuJoCo is not installed ({e}); pip install 'mujoco>=3.7'") \
            from None
    if _version_tuple(mujoco.__version__) < MIN_MUJOCO:
        raise EngineVersionError(
            f"MuJoCo {mujoco.__version__} is too old: need >= 3.7.0 (earlier versions omit the "
            "Jdot*v term of connect constraints, so loop accelerations come out near zero)")
    return mujoco


def direct_solref(tau: float) -> tuple[float, float]:
    """Critically damped direct-form solref ``(-1/tau^2, -2/tau)`` (stiffness, damping)."""
    return (-1.0 / tau ** 2, -2.0 / tau)


#: Near-hard impedance: 0.9999 is MuJoCo's cap (ENGINE_NOTES.md).
HARD_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)


#: MuJoCo clamps the impedance d to [mjMINIMP, mjMAXIMP] = [0.0001, 0.9999]: a value
#: outside it would be changed silently.  dmin and dmax may come in either order (the
#: impedance is dmin + y (dmax - dmin), y from 0 to 1 over the width).
_IMPEDANCE = dict(lo=1e-4, hi=0.9999, why="MuJoCo clamps the impedance to [0.0001, 0.9999]")

#: Scene variants of :attr:`MujocoSettings.scene` (built by :mod:`sim_models.engines.mujoco.scene`).
SCENES = ("minimal", "contacts", "contacts-same-plane", "contacts-no-excludes",
          "extra-visual", "extra-collision")


@dataclass(frozen=True)
class MujocoSettings(EngineSettings):
    """Solver settings of the MuJoCo models (recommended defaults; evidence below).

    Parameters
    ----------
    timestep
        Largest step, s.  :func:`sim_models.runs.driven.run` shortens it so that a
        revolution is a whole number of steps and every sample falls on a step.
    integrator
        ``"RK4"``, ``"implicitfast"``, ``"implicit"`` or ``"Euler"``.
    solref
        Loop constraint reference.  Negative pair = direct form
        ``(-stiffness, -damping)``; default critically damped with time
        constant 10 ms (:func:`direct_solref`).  With the near-hard
        constraints that ``invweight_scale`` gives, the loop is a Baumgarte
        stabilised hard constraint and a slow correction is the accurate one:
        RK4 on the seed four-bar, worst error / peak of alpha, torque, pin
        forces over the 2nd revolution: dt 1e-4 with tau 0.3 ms 1.5e-3,
        0.5 ms 1.8e-4, 1 ms 1.1e-5, 3 ms 1.3e-7; dt 3e-4 with tau 10 ms
        8e-8; dt 1e-3 with tau 30 ms 1.2e-7 (slider-crank at 200 rad/s:
        2e-5).  Do not scale it with the timestep under RK4.
    solimp
        Loop constraint impedance; default the near-hard cap.
    iterations, tolerance
        Constraint solver iterations and tolerance.
    armature
        Added inertia on the driven joint (kg m^2 or kg): the drive.  The driver's
        acceleration then misses its prescribed value by ``effort / armature``
        (measured exactly so).  1e8: near the limit position of
        hibbeler-two-inclines the drive force reaches 4.5 kN and 1e6 left the input
        acceleration 1.5e-3 of its value off (the only case above 1e-3); 1e8 brings
        every built-in case to <= 1.5e-5 of peak, 1e10 to <= 3.3e-6 but leaves the
        mass matrix's diagonal spanning 1e13.
    diagexact
        Enable ``mjENBL_DIAGEXACT`` (exact diagonal in the constraint
        regularisation).  Off by default: with ``invweight_scale`` the
        approximate diagonal is the better knob.
    invweight_scale
        Factor applied by :func:`compile_spec` to the compiled model's
        ``body_invweight0`` and ``dof_invweight0``.  With ``diagexact`` off they
        form MuJoCo's approximate constraint diagonal, and the regularisation
        ``R = (1 - d) / d * diagApprox`` (d = solimp, capped at 0.9999) is what
        makes the constraints soft: the constraint-force error is proportional
        to R.  Measured with ``mj_forward`` at the analytic state (36 angles,
        max error / peak): stock (1.0) 7.4e-5 seed-four-bar, 7.6e-4
        seed-slider-crank, 2.7e-4 six-bar; 1e-2 gives 100x less; 1e-4 about
        1e-7; 1e-6 is worse again (conditioning).  1.0 restores stock MuJoCo.
    scene
        ``"minimal"`` (the project's scene: contacts off, one capsule per link) or a
        variant of the scene-economy study with unneeded parts added (:data:`SCENES`,
        :mod:`sim_models.engines.mujoco.scene`).
    """

    timestep: float = 2.5e-4
    integrator: str = "RK4"
    solref: tuple[float, float] = direct_solref(1e-2)
    solimp: tuple[float, float, float, float, float] = HARD_SOLIMP
    iterations: int = 100
    tolerance: float = 1e-12
    armature: float = 1e8
    diagexact: bool = False
    invweight_scale: float = 1e-3
    scene: str = "minimal"

    engine_name: ClassVar[str] = "mujoco"
    RANGES: ClassVar[Mapping[str, object]] = {
        "timestep": ranges.TIMESTEP,
        "integrator": ranges.Choice(("RK4", "implicitfast", "implicit", "Euler"), fold=True),
        # signs checked together in extra_problem (standard or direct form)
        "solref": (ranges.Range(name="timeconst or -stiffness"),
                   ranges.Range(name="dampratio or -damping")),
        "solimp": (ranges.Range(**_IMPEDANCE, name="dmin"),
                   ranges.Range(**_IMPEDANCE, name="dmax"),
                   ranges.Range(0, lo_open=True, unit="m", name="width",
                                why="the violation over which the impedance goes from "
                                    "dmin to dmax"),
                   ranges.Range(0, 1, lo_open=True, hi_open=True, name="midpoint",
                                why="MuJoCo divides by midpoint and 1 - midpoint"),
                   ranges.Range(1, name="power", why="MuJoCo's impedance sigmoid needs "
                                "power >= 1")),
        "iterations": ranges.Range(1, 1000, whole=True,
                                   why="the solver stops at its tolerance first; 1000 "
                                       "caps the cost of a step that does not converge"),
        "tolerance": ranges.Range(0, 1, why="the solver's relative improvement to stop "
                                  "at; 0: never stop early"),
        "armature": ranges.Range(0, 1e12, lo_open=True, unit="kg m^2 or kg",
                                 why="the drive: 0 or below drives nothing; above 1e12 "
                                     "the mechanism's own inertia falls below the "
                                     "driven joint's round-off"),
        "diagexact": ranges.FLAG,
        "invweight_scale": ranges.Range(0, lo_open=True,
                                        why="a factor on MuJoCo's inverse weights; 0 or "
                                            "below leaves the constraint regulariser "
                                            "R <= 0"),
        "scene": ranges.Choice(SCENES),
    }

    def extra_problem(self) -> tuple[str, str] | None:
        """solref: MuJoCo's standard form ``(timeconst, dampratio)``, both above 0, or
        the direct form ``(-stiffness, -damping)``, stiffness above 0 and damping >= 0
        (a mixed pair is a negative damping or stiffness: the loop gap grows).  MuJoCo
        raises a standard time constant below 2 x timestep to that value (the studies
        use it so, on purpose)."""
        a, b = self.solref
        if (a > 0 and b > 0) or (a < 0 and b <= 0):
            return None
        return "solref", ("use (timeconst, dampratio), both above 0, or the direct form "
                          "(-stiffness, -damping), stiffness above 0 and damping at least 0")

    def describe(self) -> str:
        scene = "" if self.scene == "minimal" else f", scene={self.scene}"
        return (f"MuJoCo {self.integrator} dt<={self.timestep:g} s, solref={self.solref}, "
                f"solimp={self.solimp}, iterations={self.iterations}, "
                f"tolerance={self.tolerance:g}, armature={self.armature:g}, "
                f"diagexact={self.diagexact}, invweight_scale={self.invweight_scale:g}{scene}")


_INTEGRATORS = {"rk4": "mjINT_RK4", "implicitfast": "mjINT_IMPLICITFAST",
                "implicit": "mjINT_IMPLICIT", "euler": "mjINT_EULER"}


def _quat_z(a: float) -> list[float]:
    return [math.cos(a / 2), 0.0, 0.0, math.sin(a / 2)]


def site_name(joint: str, body: str) -> str:
    return f"{joint}@{body}"


def build_mjcf(mech: Mechanism, settings: MujocoSettings | None = None,
               tree: SimTree | None = None):
    """The MuJoCo model of ``mech`` as a :class:`mujoco.MjSpec` (not compiled).

    Raises :class:`EngineVersionError` for MuJoCo < 3.7 and
    :class:`~sim_models.builders.tree.UnsupportedClosureError` when a loop cannot be
    closed at a revolute joint.
    """
    mujoco = require_mujoco()
    settings = settings or MujocoSettings()
    st = tree or SimTree(mech)
    key = settings.integrator.lower()
    if key not in _INTEGRATORS:
        raise SimModelError(f"unknown MuJoCo integrator {settings.integrator!r}; "
                            f"use one of {sorted(_INTEGRATORS)}")

    s = mujoco.MjSpec()
    s.modelname = mech.name
    _set_options(s, mujoco, mech, settings, key)
    radius = 0.01 * st.size
    specs = {st.ground: s.worldbody}
    _add_visuals(mujoco, mech, st, s.worldbody, st.ground, radius)
    for tj in st.joints:
        specs[tj.child] = _add_tree_body(mujoco, mech, st, settings, specs, tj, radius)
        _add_visuals(mujoco, mech, st, specs[tj.child], tj.child, radius)
    _add_chords(mujoco, st, settings, s, specs)
    return s


def _set_options(s, mujoco, mech: Mechanism, settings: MujocoSettings, key: str) -> None:
    """The compiler flags and the solver options: step, integrator, iterations,
    tolerance, gravity; contacts and auto-reset off."""
    s.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    s.compiler.autolimits = False
    opt = s.option
    opt.timestep = settings.timestep
    opt.integrator = getattr(mujoco.mjtIntegrator, _INTEGRATORS[key])
    opt.iterations = int(settings.iterations)
    opt.tolerance = float(settings.tolerance)
    gx, gy = mech.gravity
    opt.gravity = [float(gx), float(gy), 0.0]
    opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
    if settings.diagexact:
        opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_DIAGEXACT)


def _add_visuals(mujoco, mech: Mechanism, st: SimTree, body_spec, b: int,
                 radius: float) -> None:
    """Body ``b``'s drawing: a sphere per point (one-point bodies and the ground) or a
    capsule between consecutive points; never in contact."""
    pts = list(mech.bodies[b].points.values())
    rgba = [0.2, 0.2, 0.2, 1.0] if b == st.ground else [0.2, 0.4, 0.8, 1.0]
    if len(pts) == 1 or b == st.ground:
        for p in pts:
            body_spec.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE,
                               size=[1.5 * radius, 0, 0], pos=[p[0], p[1], 0.0],
                               contype=0, conaffinity=0, rgba=rgba)
    else:
        for p, q in zip(pts[:-1], pts[1:], strict=True):
            if math.hypot(q[0] - p[0], q[1] - p[1]) < 1e-12:
                continue
            body_spec.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[radius, 0, 0],
                               fromto=[p[0], p[1], 0.0, q[0], q[1], 0.0],
                               contype=0, conaffinity=0, rgba=rgba)


def _add_tree_body(mujoco, mech: Mechanism, st: SimTree, settings: MujocoSettings, specs,
                   tj, radius: float):
    """The child body of tree joint ``tj`` under its parent's spec: pose, inertia, the
    hinge or slide joint (a slide's guide line drawn on the guide), the driver's
    armature.  Returns the body's spec."""
    c = tj.child
    parent = specs[tj.parent]
    # round-off of an exact zero made 0, so the written MJCF is the same on any CPU
    body = parent.add_body(name=st.body_names[c], pos=[snap(tj.rel_pos[0], st.size),
                                                       snap(tj.rel_pos[1], st.size), 0.0],
                           quat=_quat_z(snap(tj.rel_angle)))
    body.explicitinertial = True
    body.mass = float(st.mass[c])
    body.ipos = [snap(st.com[c][0], st.size), snap(st.com[c][1], st.size), 0.0]
    inertia = float(st.inertia[c])
    body.inertia = [0.6 * inertia, 0.6 * inertia, inertia]
    if tj.kind == "hinge":
        jnt = body.add_joint(name=tj.name, type=mujoco.mjtJoint.mjJNT_HINGE,
                             axis=[0.0, 0.0, 1.0],
                             pos=[tj.anchor_child[0], tj.anchor_child[1], 0.0])
    else:
        jnt = body.add_joint(name=tj.name, type=mujoco.mjtJoint.mjJNT_SLIDE,
                             axis=[tj.axis_child[0], tj.axis_child[1], 0.0],
                             pos=[tj.anchor_child[0], tj.anchor_child[1], 0.0])
        # show the guide line on the guide
        guide = tj.parent if tj.sigma > 0 else tj.child
        gspec = specs[tj.parent] if tj.sigma > 0 else body
        jt = mech.joints[tj.joint]
        o = np.asarray(mech.bodies[guide].points[jt.origin], float)
        u = np.array([math.cos(jt.direction), math.sin(jt.direction)])
        a, b_ = o - 0.5 * st.size * u, o + 0.5 * st.size * u
        gspec.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[0.3 * radius, 0, 0],
                       fromto=[a[0], a[1], 0.0, b_[0], b_[1], 0.0], contype=0,
                       conaffinity=0, rgba=[0.6, 0.6, 0.6, 1.0])
    jnt.limited = mujoco.mjtLimited.mjLIMITED_FALSE
    if tj.joint == st.tree_joint_indices[st.driver_tree]:
        jnt.armature = float(settings.armature)
    return body


def _add_chords(mujoco, st: SimTree, settings: MujocoSettings, s, specs) -> None:
    """Each loop-closing joint as a site on both bodies and a CONNECT equality."""
    names = st.body_names
    for ch in st.chords:
        na, nb = names[ch.body_a], names[ch.body_b]
        specs[ch.body_b].add_site(name=site_name(ch.name, nb),
                                  pos=[ch.point_b[0], ch.point_b[1], 0.0])
        specs[ch.body_a].add_site(name=site_name(ch.name, na),
                                  pos=[ch.point_a[0], ch.point_a[1], 0.0])
        s.add_equality(name=ch.name, type=mujoco.mjtEq.mjEQ_CONNECT,
                       objtype=mujoco.mjtObj.mjOBJ_SITE,
                       name1=site_name(ch.name, nb), name2=site_name(ch.name, na),
                       solref=list(settings.solref), solimp=list(settings.solimp))


def compile_mjcf(mech: Mechanism, settings: MujocoSettings | None = None,
                 tree: SimTree | None = None):
    """Build and compile: ``(model, warnings)`` with ``settings.invweight_scale`` applied."""
    settings = settings or MujocoSettings()
    return compile_spec(build_mjcf(mech, settings, tree), settings)


def compile_refusal(e: ValueError, mech: Mechanism) -> EngineRefusal:
    """MuJoCo's compiler refused the model of ``mech``: one line, with its size."""
    reason = str(e).replace("Error:", "").split("\n")[0].strip()
    size = max((math.dist(p, q) for b in mech.bodies for p in b.points.values()
                for q in b.points.values()), default=0.0)
    # measured: the seed four-bar compiles scaled to a 1e-6 m crank, not to 1e-7 m; the
    # reason says which limit (micro-four-bar.toml: masses of 2e-7 kg, I 1.7e-16 kg m^2)
    why = ("; its compiler rejects a moving body's mass or inertia below mjMINVAL (1e-15)"
           if "mjMINVAL" in reason else
           "; its compiler rejects the geometry of links shorter than about 1e-6 m")
    return EngineRefusal(f"mechanism {mech.name!r} (size {size:.3g} m): MuJoCo cannot "
                         f"compile its model ({reason}){why}")


def compile_spec(spec, settings: MujocoSettings | None = None, mech: Mechanism | None = None):
    """Compile an ``MjSpec``; return ``(model, warnings)`` with MuJoCo's warning texts.

    With ``settings``, its ``invweight_scale`` is applied to the compiled model.  With
    ``mech``, a model MuJoCo's compiler rejects is an :class:`EngineRefusal` naming the
    mechanism and its size (:func:`compile_refusal`), the one line ``compare`` and
    ``models`` both print.
    """
    mujoco = require_mujoco()
    msgs: list[str] = []
    old = mujoco.get_mju_user_warning() if hasattr(mujoco, "get_mju_user_warning") else None
    mujoco.set_mju_user_warning(msgs.append)
    try:
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            try:
                model = spec.compile()
            except ValueError as e:
                if mech is None:
                    raise
                raise compile_refusal(e, mech) from None
        msgs.extend(str(x.message) for x in w)
    finally:
        mujoco.set_mju_user_warning(old)
    if settings is not None and settings.invweight_scale != 1.0:
        model.body_invweight0[:] *= settings.invweight_scale
        model.dof_invweight0[:] *= settings.invweight_scale
    return model, msgs
