"""A MuJoCo model that moves on its own in a viewer: the harness's model plus its drive
as an actuator and the assembled state as a keyframe.

:func:`viewer_spec` takes :func:`sim_models.builders.mjcf.build_mjcf` (unchanged: the verdict runs
use it as it is) and adds to the ``MjSpec``:

* **the drive** as one ``general`` actuator ``drive`` on the driven joint.  The harness
  drives through the joint's huge armature A with ``qfrc_applied = A a`` (the prescribed
  acceleration; :mod:`sim_models.engines.mujoco.driven`); a file cannot set ``qfrc_applied``, so
  the actuator's bias applies that force, ``A a``.  For a constant-rate driver it also
  holds the prescribed rate w: force ``A a + k (w - qvel) + k ctrl`` with
  ``k = A / SPIN_UP`` (s), so a model started at rest (``MjData``'s default, as
  ``python -m mujoco.viewer --mjcf=F.xml`` starts it) comes up to speed in a few tenths
  of a second, and the viewer's control slider adds up to +-w to the rate.  From the
  keyframe, at the prescribed rate, the servo's force is the drift correction only.
  An accelerating driver gets ``A a`` alone (its rate changes with time; a servo would
  fight it).
* **the keyframe** ``assembled``: the analytic assembled state (``qpos = 0``: the body
  frames are built at the reference pose) and the prescribed rate of every tree joint
  (``qvel`` from the analytic velocities), time 0.
* **a limit** on the driven joint of an input that cannot turn fully, 5% of its
  feasible range inside each end (:func:`limit_driver`): driven past the end the
  linkage would tear its loops apart; with the limit it stops there.

MJCF prints numbers to 6 significant digits, so the keyframe's rates of the joints
other than the driver are consistent with the loops to ~1e-6 of their size (the
constraint closes that in its time constant); the driven joint's rate is exact.

Loads (``[[loads]]``) are applied by the harness through ``xfrc_applied`` each step and
cannot be written into MJCF: a model file shows the motion, not the loads.  Neither can
``invweight_scale`` (see :mod:`sim_models.builders.model_files`): the file's loop constraints are
MuJoCo's stock, softer ones.  Neither changes the driven joint's motion.
"""

from __future__ import annotations

import math

import numpy as np

from analytic import Mechanism

from .mjcf import MujocoSettings, build_mjcf, compile_spec, require_mujoco
from .model_numbers import model_value
from .tree import SimTree

#: Time constant of the rate servo, s: a viewer started at rest reaches the prescribed
#: rate in a few of these; 500 steps of the default 2.5e-4 s step, so RK4 integrates
#: the servo's decay with an error of ~(h / tau)^4 / 120, nothing.
SPIN_UP = 0.125


def viewer_spec(mech: Mechanism, settings: MujocoSettings | None = None,
                tree: SimTree | None = None):
    """The harness's ``MjSpec`` of ``mech`` with its drive actuator, the ``assembled``
    keyframe and a whole number of steps per revolution (see the module docstring)."""
    mujoco = require_mujoco()
    settings = settings or MujocoSettings()
    st = tree or SimTree(mech)
    spec = build_mjcf(mech, settings, st)
    d = mech.driver
    dj = st.joints[st.driver_tree]
    A = float(settings.armature)
    sigma = float(st.driver_sigma)
    k = A / SPIN_UP if d.acceleration == 0.0 and d.velocity != 0.0 else 0.0
    w = sigma * d.velocity
    act = spec.add_actuator(name="drive", target=dj.name,
                            trntype=mujoco.mjtTrn.mjTRN_JOINT)
    act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
    act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
    gain = np.zeros(10)
    gain[0] = k
    bias = np.zeros(10)
    bias[0] = A * sigma * d.acceleration + k * w
    bias[2] = -k
    act.gainprm = [model_value(x, 0.0) for x in gain]  # digits a CPU cannot change
    act.biasprm = [model_value(x, 0.0) for x in bias]
    act.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE if k else mujoco.mjtLimited.mjLIMITED_FALSE
    if k:
        act.ctrlrange = [-abs(d.velocity), abs(d.velocity)]
    act.forcelimited = mujoco.mjtLimited.mjLIMITED_FALSE
    limit_driver(spec, st, spec.joint(dj.name))
    qpos, qvel = assembled_state(spec, st)
    vscale = float(np.max(np.abs(qvel), initial=0.0))
    qvel = [model_value(x, vscale) for x in qvel]
    spec.add_key(name="assembled", time=0.0, qpos=list(qpos), qvel=qvel,
                 ctrl=[0.0])
    return spec


def assembled_state(spec, st: SimTree) -> tuple[np.ndarray, np.ndarray]:
    """``qpos, qvel`` of the compiled model at the analytic assembled state with the
    prescribed rate (tree coordinates of :meth:`SimTree.coords` at the reference)."""
    m, _ = compile_spec(spec, None, st.mech)  # refused in one line, as compare refuses
    _, qd, _ = st.coords(st.kin_ref)
    qpos = np.array(m.qpos0, float)
    qvel = np.zeros(m.nv)
    for i, tj in enumerate(st.joints):
        jnt = m.joint(tj.name)
        qvel[jnt.dofadr[0]] = qd[0, i]
    return qpos, qvel


def limit_driver(spec, st: SimTree, jnt) -> tuple[float, float] | None:
    """A limited input (one that cannot turn fully): limit the driven joint just inside
    the feasible range holding the reference value, so that a model driven past it stops
    at the end of the range instead of tearing its loops apart.  Returns the range in
    tree coordinates (rad or m), None for a full-turn crank."""
    from analytic import Revolute
    mech = st.mech
    v0 = mech.driver.value
    feas = st.linkage.feasible_ranges()
    rev = isinstance(mech.driver_joint, Revolute)
    if rev and len(feas) == 1 and feas[0][1] - feas[0][0] >= 2 * math.pi * (1 - 1e-9):
        return None
    lo, hi = next(((a, b) for a, b in feas if a <= v0 <= b), (v0, v0))
    pad = LIMIT_PAD * (hi - lo)
    q = sorted((st.driver_sigma * (lo + pad - v0), st.driver_sigma * (hi - pad - v0)))
    mujoco = require_mujoco()
    scale = 180.0 / math.pi if rev and spec.compiler.degree else 1.0
    jnt.limited = mujoco.mjtLimited.mjLIMITED_TRUE
    jnt.range = [q[0] * scale, q[1] * scale]
    return q[0], q[1]


#: A limited input stops this fraction of its feasible range inside each end (the
#: loops' Jacobian is singular at the end itself; measured: with 1% hibbeler-16-30
#: arriving at 2 m/s tears its loops (NaN), 2% holds, 5% for margin).
LIMIT_PAD = 0.05


def viewer_xml(mech: Mechanism, settings: MujocoSettings | None = None) -> str:
    """MJCF text of :func:`viewer_spec` (what ``xval models`` writes)."""
    return viewer_spec(mech, settings).to_xml()




# ============================================================================ the viewer
def viewer_unavailable() -> str | None:
    """Why MuJoCo's viewer cannot open a window here (None when it can): its window
    library, GLFW, must initialise on the display.  (Without this check the viewer
    prints 'could not initialize GLFW' and ends the process.)"""
    import warnings
    try:
        import glfw
    except ImportError as e:  # pragma: no cover - installed with mujoco
        return f"the viewer's window library glfw is missing ({e})"
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        ok = glfw.init()
        if ok:
            glfw.terminate()
    if ok:
        return None
    msg = next((str(x.message) for x in w), "")
    return "GLFW cannot open a window" + (f" ({msg})" if msg else "")


def run_viewer(mech: Mechanism, settings: MujocoSettings | None = None,
               seconds: float | None = None, launch=None) -> str:
    """Open MuJoCo's viewer on the harness's own session of ``mech``
    (:class:`sim_models.engines.mujoco.driven.MujocoSession`: the drive through the armature and
    ``qfrc_applied``, loads through ``xfrc_applied``) and step it in real time from the
    assembled state; a limited input restarts from there at the end of its run.  Returns
    why it stopped.  ``launch``: the viewer's ``launch_passive`` (a test passes a stub);
    ``seconds``: stop after this much simulated time (default: when the window closes).
    Needs a display: the caller checks first."""
    import time

    from ..engines.protocol import plan_samples
    from ..runs.driven import open_session
    from ..runs.engine_run import RunRequest
    from .tree import SimTree
    if launch is None:
        import mujoco.viewer
        launch = mujoco.viewer.launch_passive
    st = SimTree(mech)
    plan = plan_samples(st, RunRequest.revolutions, RunRequest.samples)
    t_end = None if plan.full else plan.t_end  # a limited input: one run, then again
    sess = open_session(st, "mujoco", settings)
    h = float(sess.settings.timestep)
    try:
        sess.reset(0.0, h)
        t, total, why = 0.0, 0.0, "window closed"
        with launch(sess.model, sess.data) as v:
            wall0 = time.perf_counter()
            while v.is_running():
                lag = (time.perf_counter() - wall0) - t
                n = max(1, min(int(lag / h), 2000))
                if t_end is not None:  # never past the end of a limited input's run
                    n = max(1, min(n, int((t_end - t) / h)))
                with v.lock():
                    reason = sess.advance(t, h, n)
                t += n * h
                total += n * h
                if reason:
                    why = f"stopped: {reason} at t = {t:.4g} s"
                    break
                if t_end is not None and t >= t_end:
                    with v.lock():
                        sess.reset(0.0, h)
                    t, wall0 = 0.0, time.perf_counter()
                v.sync()
                if seconds is not None and total >= seconds:
                    why = f"ran {total:.4g} s"
                    break
                if lag < h:
                    time.sleep(h)
        return why
    finally:
        sess.close()


__all__ = ["LIMIT_PAD", "SPIN_UP", "assembled_state", "limit_driver", "run_viewer",
           "viewer_spec", "viewer_unavailable", "viewer_xml"]
