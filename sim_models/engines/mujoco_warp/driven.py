"""MuJoCo Warp behind the engine protocol (:class:`MujocoWarpSession`, :class:`MujocoWarpSettings`).

The project's MuJoCo model (:func:`sim_models.builders.mjcf.build_mjcf`, compiled by
:func:`sim_models.builders.mjcf.compile_spec`: the very ``MjModel`` the ``mujoco`` engine steps,
inverse weights scaled by ``invweight_scale``) is put on a Warp device with
``mujoco_warp.put_model`` / ``put_data`` (one world) and stepped by ``mujoco_warp.step``
in Warp's kernels: **float32** (MuJoCo Warp has no float64 mode: its kernels are
written in Warp's ``float``, which is 32-bit; there is nothing to switch).

Device: ``settings.device`` ``"auto"`` takes the first CUDA device when Warp sees one,
else the CPU (Warp compiles its kernels for the CPU with its bundled clang/LLVM).  The
device and the precision are recorded in the run's ``extra`` (``device``,
``precision``) and notes.

What of the MuJoCo engine carries over (measured: see :class:`MujocoWarpSettings`)
-------------------------------------------------------------------------------
* **Drive by armature**: supported (``dof_armature`` is in Warp's mass matrix) with the
  same ``qfrc_applied = A a_prescribed``.  The effort is **not** read as
  ``A (a_prescribed - qacc)``: in float32 that difference loses ``A eps32 |a|``
  (``1e8 * 6e-8 * 20 = 120 N m`` on hibbeler-16-31).  It is read as MuJoCo itself
  defines the generalised force across the driven joint, ``cdof . cfrc_int`` of the
  driven body (no cancellation; :meth:`MujocoWarpSession.drive_effort`).
* **Loop equalities** (``connect``): supported, same solref/solimp, Newton or CG.
  ``mjENBL_DIAGEXACT`` is not supported by MuJoCo Warp (its ``EnableBit`` lacks it), nor
  is ``mjDSBL_AUTORESET`` (it never auto-resets): that flag is cleared on the copy
  given to Warp.  ``put_model`` raises the solver tolerance to at least 1e-6 (float32);
  the session writes the setting's own value back.
* **Samples**: as MuJoCo, a ``forward`` (and ``rne_postconstraint`` for ``cfrc_int``)
  at the state of the sample time; the readout is :meth:`MujocoSession.convert`, the
  same code on Warp's arrays.
* **Speed**: on the CPU every kernel launch costs 0.1-0.2 ms of Python argument
  packing (84 launches a ``forward``, 326 an RK4 step: 58 ms a step).  The step and the
  sample are therefore captured once each as Warp graphs (``wp.ScopedCapture``; on the
  CPU Warp replays them in C++): 0.3 ms an RK4 step on the seed four-bar.

Kernel cache: ``$XVAL_WARP_CACHE``, else ``$XDG_CACHE_HOME/linkage-xval/warp``
(``~/.cache/linkage-xval/warp``), set before Warp initialises (when Warp was already
initialised by the caller, its own cache directory is kept and named in the notes).
"""

from __future__ import annotations

import contextlib
import functools
import math
import os
from pathlib import Path

import numpy as np

from ...builders.mjcf import EngineVersionError, MujocoSettings
from ...builders.tree import SimTree
from ..mujoco.driven import MujocoSession
from ..protocol import HUGE, Recorder, check_raw_state
from ..settings import EngineRefusal
from .settings import MujocoWarpSettings

#: How to get MuJoCo Warp (the optional extra).
INSTALL = "pip install 'linkage-xval[warp]'"


def warp_cache_dir() -> Path:
    """Warp's kernel cache for this project: ``$XVAL_WARP_CACHE``, else
    ``$XDG_CACHE_HOME/linkage-xval/warp`` (``~/.cache/linkage-xval/warp``)."""
    d = os.environ.get("XVAL_WARP_CACHE")
    if not d:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(Path.home(), ".cache")
        d = os.path.join(base, "linkage-xval", "warp")
    return Path(d)


@functools.cache
def require_warp():
    """``(warp, mujoco_warp)``, Warp initialised quietly with :func:`warp_cache_dir`
    (unless the caller initialised it before).  A missing library is an
    :class:`EngineVersionError` saying how to install it."""
    try:
        import mujoco_warp
        import warp
    except ImportError as e:
        raise EngineVersionError(f"MuJoCo Warp is not installed ({e}); {INSTALL}") from None
    if getattr(warp._src.context, "runtime", None) is None:  # not initialised yet
        cache = warp_cache_dir()
        cache.mkdir(parents=True, exist_ok=True)
        warp.config.kernel_cache_dir = str(cache)
    warp.config.quiet = True
    warp.config.log_level = warp.LOG_WARNING  # no "Module ... load" line per kernel
    INIT_MESSAGES.extend(_quiet_init(warp))
    return warp, mujoco_warp


#: What Warp's native initialisation wrote to stderr (e.g. "Could not find or load the
#: NVIDIA CUDA driver" on a machine without a GPU): kept for each session's notes.
INIT_MESSAGES: list[str] = []


def _quiet_init(warp) -> list[str]:
    """``warp.init()`` with file descriptor 2 captured (its native code prints there)."""
    import tempfile
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        saved = os.dup(2)
        try:
            os.dup2(tmp.fileno(), 2)
            warp.init()
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        tmp.seek(0)
        text = tmp.read().decode(errors="replace")
    return [ln.strip() for ln in text.splitlines() if ln.strip()]


_SOLVERS = {"newton": "mjSOL_NEWTON", "cg": "mjSOL_CG"}

#: Constraint rows of one MuJoCo equality, by ``mjtEq`` name (flex equalities: none
#: in the project's models, refused by :func:`constraint_rows`).
_EQ_ROWS = {"mjEQ_CONNECT": 3, "mjEQ_WELD": 6, "mjEQ_JOINT": 1, "mjEQ_TENDON": 1,
            "mjEQ_DISTANCE": 1}


def constraint_rows(mujoco, m) -> int:
    """The most constraint rows ``m`` can have at any state: every equality (always
    active), one row per limited joint or tendon, one per dof or tendon with friction
    loss.  MuJoCo Warp preallocates ``njmax`` rows a world and, past it, **drops rows
    silently** (``d.overflow`` flagged, a printf only when ``warn_overflow`` asks);
    its default ``njmax`` is sized for contacts (64 for these models whatever their
    loops), so without this A02 at N >= 22 (66 loop rows) lost loop rows.  Contacts
    are off in the project's models (:func:`sim_models.builders.mjcf.compile_spec`); a model
    with contacts on is refused rather than guessed at."""
    if not m.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_CONTACT):
        raise EngineRefusal("MuJoCo Warp: contacts are on in this model; the harness sizes "
                            "Warp's constraint rows (njmax) for models without contacts")
    rows = {int(getattr(mujoco.mjtEq, k)): n for k, n in _EQ_ROWS.items()}
    total = 0
    for t in np.asarray(m.eq_type, int):
        if int(t) not in rows:
            raise EngineRefusal(f"MuJoCo Warp: equality type {mujoco.mjtEq(int(t)).name} "
                                "is not sized by the harness (njmax)")
        total += rows[int(t)]
    total += int(np.count_nonzero(m.jnt_limited)) + int(np.count_nonzero(m.tendon_limited))
    total += int(np.count_nonzero(m.dof_frictionloss)) + \
        int(np.count_nonzero(m.tendon_frictionloss))
    return max(total, 1)


class _WorldView:
    """World 0 of Warp's data as the MjData attributes :meth:`MujocoSession.apply_loads`
    reads and writes (NumPy views on the CPU, copies written back on a GPU)."""

    def __init__(self, d):
        self._d = d
        self.xipos = d.xipos.numpy()[0]
        self.xpos = d.xpos.numpy()[0]
        self.xmat = d.xmat.numpy()[0]
        # (nbody, 6): Warp's array is (nworld, nbody) of spatial vectors, 1-D a world
        self.xfrc_applied = np.zeros_like(d.xfrc_applied.numpy()[0])

    def commit(self) -> None:
        self._d.xfrc_applied.assign(self.xfrc_applied[None])


class WarpStepping:
    """The host ``MjModel``/``MjData`` of a MuJoCo session (``self.model``,
    ``self.data``, ``self.mj``) put on a Warp device and stepped there: the device, the
    captured step and sample graphs, the stale-``Jdot v`` and stale-force workarounds.
    Shared by the prescribed (:class:`MujocoWarpSession`) and the released
    (:class:`sim_models.engines.mujoco_warp.free.MujocoWarpFreeSession`) sessions; the settings
    carry ``solver``, ``tolerance``, ``fresh_jdotv`` and ``device``."""

    def _put_warp(self) -> None:
        """The host model (built) on the Warp device; graphs captured."""
        wp, mjw, mujoco, s = self.wp, self.mjw, self.mj, self.settings
        m = self.model
        m.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
        m.opt.solver = getattr(mujoco.mjtSolver, _SOLVERS[s.solver.lower()])
        if s.device == "auto":
            self.device = wp.get_device("cuda" if wp.is_cuda_available() else "cpu")
        elif s.device == "cuda" and not wp.is_cuda_available():
            raise EngineRefusal("MuJoCo Warp: device 'cuda' asked for, but Warp sees no "
                                "CUDA device (use device=cpu or auto)")
        else:
            self.device = wp.get_device(s.device)
        with wp.ScopedDevice(self.device):
            try:
                self.wm = mjw.put_model(m)
            except NotImplementedError as e:
                raise EngineRefusal(f"MuJoCo Warp cannot run this model: {e}") from None
            self.wm.opt.tolerance.fill_(float(s.tolerance))
            # the solver's kernels printf when the iteration cap is hit: no stdout noise
            self.wm.opt.warn_overflow = 0  # overflows are read from d.overflow instead
            self.njmax = constraint_rows(mujoco, m)
            self.wd = mjw.put_data(m, self.data, njmax=self.njmax)
        self.cpu = self.device.is_cpu
        self.notes.extend(f"Warp: {m}" for m in INIT_MESSAGES)
        self.notes.append(f"MuJoCo Warp {_version(mjw)} on Warp device "
                          f"{self.device.alias} ({self.device.name}), float32; kernel cache "
                          f"{wp.config.kernel_cache_dir}; njmax {self.njmax} (every "
                          f"constraint row the model can have)")
        self._step_graph = self._fwd_graph = None
        self._graphs()  # kernels loaded (compiled on first use) and graphs captured here

    # -- graphs -------------------------------------------------------------------
    def _graphs(self):
        """Capture the step and the sample (``forward`` + ``rne_postconstraint``) as Warp
        graphs once (after one plain call of each, which loads the kernels)."""
        if self._step_graph is None:
            wp, mjw, m, d = self.wp, self.mjw, self.wm, self.wd
            with wp.ScopedDevice(self.device):
                self._sample_plain()
                mjw.step(m, d)
                with wp.ScopedCapture() as cap, self._fresh_stages():
                    self._fresh_velocities()
                    mjw.step(m, d)
                self._step_graph = cap.graph
                with wp.ScopedCapture() as cap:
                    self._sample_plain()
                self._fwd_graph = cap.graph
        return self._step_graph, self._fwd_graph

    def _fresh_velocities(self) -> None:
        """``cvel`` and ``cdof_dot`` at the present state (kinematics, com_pos, com_vel).
        MuJoCo Warp 4.0.0 builds the loop rows' ``Jdot v`` in ``make_constraint``
        (``fwd_position``) from them *before* ``fwd_velocity`` updates them: from the
        previous call's state (measured: the first ``forward`` at a new state gave the
        slider-crank coupler 3.9 for 8262 rad/s^2; a second call at the same state was
        right).  With this before each step and sample the Euler step's constraint is
        built at its own state; RK4's inner stages still see the stage before."""
        if self.settings.fresh_jdotv:
            mjw, m, d = self.mjw, self.wm, self.wd
            mjw.kinematics(m, d)
            mjw.com_pos(m, d)
            mjw.com_vel(m, d)

    @contextlib.contextmanager
    def _fresh_stages(self):
        """While the step graph is captured: RK4's inner stages (``forward._forward``,
        which ``rungekutta4`` calls) preceded by :meth:`_fresh_velocities` too.  The
        library is patched only for the capture; the graph keeps the launches."""
        from mujoco_warp._src import forward as fwd_module
        inner = fwd_module._forward
        if not self.settings.fresh_jdotv:
            yield
            return

        def fresh(m, d, *args, **kwargs):
            self._fresh_velocities()
            return inner(m, d, *args, **kwargs)

        fwd_module._forward = fresh
        try:
            yield
        finally:
            fwd_module._forward = inner

    def _sample(self) -> None:
        """The sample graph with the solver's tolerance 0 (it runs until its line search
        stalls or ``iterations``): a solve that is done at its starting point leaves
        ``efc.force`` from the previous call (MuJoCo Warp 4.0.0 skips the force update
        of a converged world; measured: the drive torque at 60 deg read -0.034 for
        0.673 N m).  The armature's share of ``meaninertia`` makes the scaled
        tolerance test pass at once."""
        tol = self.wm.opt.tolerance
        tol.fill_(0.0)
        self.wp.capture_launch(self._graphs()[1])
        tol.fill_(float(self.settings.tolerance))

    def _sample_plain(self) -> None:
        self._fresh_velocities()
        self.mjw.forward(self.wm, self.wd)
        self.mjw.rne_postconstraint(self.wm, self.wd)

    def _overflow(self) -> str | None:
        """Why the last steps are void when MuJoCo Warp flagged dropped constraint rows
        (``d.overflow``: ``NEFC``, rows past ``njmax``; ``NJMAX_NNZ``, Jacobian entries
        past ``njmax_nnz``; the flag is sticky), else None.  Its solver silently solves
        without the dropped rows (measured on A02, N = 30: 90 loop rows, 64 kept under
        the library's default ``njmax``; the chain fell with its loops open)."""
        from mujoco_warp import OverflowType
        flags = int(self.wd.overflow.numpy()[0])
        lost = flags & int(OverflowType.NEFC | OverflowType.NJMAX_NNZ)
        if not lost:
            return None
        n = int(self.wd.nefc.numpy()[0])
        return (f"MuJoCo Warp dropped constraint rows (overflow flags {lost:#x}: nefc {n}, "
                f"njmax {self.wd.njmax}, njmax_nnz {self.wd.njmax_nnz})")

    # -- state and drive ----------------------------------------------------------
    def _put_state(self) -> None:
        """Warp's world 0 from the host data (state, applied forces, time 0)."""
        wp, d, h = self.wp, self.wd, self.data
        # not mujoco_warp.reset_data: the first forward after it left the loops unsolved
        # (measured: seed-slider-crank's coupler qacc 3.9 for 8262 rad/s^2, right on the
        # second call); the state, the applied forces, time and warm start are the state
        with wp.ScopedDevice(self.device):
            for name in ("qpos", "qvel", "qfrc_applied", "xfrc_applied", "qacc_warmstart"):
                getattr(d, name).assign(np.asarray(getattr(h, name), np.float32)[None])
            d.time.fill_(float(h.time))

    def _loads(self) -> None:
        """The harness's loads (``xfrc_applied``) at Warp's present poses."""
        view = _WorldView(self.wd)
        self.apply_loads(view)
        view.commit()

    def _diverged(self) -> str | None:
        lost = self._overflow()
        if lost is not None:
            return lost
        qvel, qacc = self.wd.qvel.numpy(), self.wd.qacc.numpy()
        if not (abs(float(qvel.sum())) < HUGE and abs(float(qacc.sum())) < HUGE):
            return "non-finite or huge velocities (simulation diverged)"
        return None


class MujocoWarpSession(WarpStepping, MujocoSession):
    """The MuJoCo model of one linkage stepped by MuJoCo Warp (float32, one world)."""

    name = "mujoco_warp"
    settings_class = MujocoWarpSettings
    engine_readings = False

    def __init__(self, tree: SimTree, settings: MujocoWarpSettings | None = None):
        self.wp, self.mjw = require_warp()
        super().__init__(tree, settings)

    def mujoco_settings(self) -> MujocoSettings:
        return self.settings.mujoco_settings()

    def _build(self) -> None:
        super()._build()  # the host MjModel, its addresses, the loads
        k = self.tree.driver_tree
        self._drive_body, self._drive_dof = int(self.child_bid[k]), int(self.dadr[k])
        self._put_warp()

    def extra(self) -> dict:
        return {"device": self.device.alias, "precision": self.settings.arithmetic.name,
                "ngeom": int(self.model.ngeom)}

    def reset(self, t: float, h: float) -> None:
        super().reset(t, h)  # host: analytic state, drive, loads (its forward unused)
        step, fwd = self._graphs()
        self.wm.opt.timestep.fill_(float(h))
        self._put_state()
        self.wp.capture_launch(fwd)

    def advance(self, t: float, h: float, n: int) -> str | None:
        wp = self.wp
        self.wm.opt.timestep.fill_(float(h))
        step, _ = self._graphs()
        if self.moving_loads:
            for _ in range(n):
                self._loads()
                wp.capture_launch(step)
        else:
            for _ in range(n):
                wp.capture_launch(step)
        return self._diverged()

    def record(self, t: float):
        """A ``forward`` + ``rne_postconstraint`` (graph) at the state at ``t``, then
        copies of Warp's arrays (:meth:`_raw`); a non-finite or huge state is a reason."""
        if self.moving_loads:
            self._loads()
        self._sample()
        raw = self._raw(self.acc)
        q, qd = raw[0][self.qadr], raw[1][self.dadr]
        if not (math.isfinite(q.sum()) and qd @ qd <= HUGE * HUGE):
            why = check_raw_state(q, qd)
            if why is not None:
                return None, 0.0, why
        return raw, 0.0, None

    def forward_at(self, q, qd, acceleration: float, rows, rec: Recorder) -> None:
        mj, m, h = self.mj, self.model, self.data
        self.set_state(q, qd)
        self.set_drive(acceleration)
        mj.mj_kinematics(m, h)
        self.apply_loads()
        self._graphs()
        self._put_state()
        self._sample()
        self.convert(np.zeros(1), [self._raw(acceleration)], [list(np.atleast_1d(rows))], rec)

    # -- readout ------------------------------------------------------------------
    def _raw(self, a_prescribed: float) -> tuple:
        """The raw record (:meth:`_raw_warp` or :meth:`_raw_host`, ``settings.readout``)."""
        if self.settings.readout == "host":
            return self._raw_host(a_prescribed)
        return self._raw_warp(a_prescribed)

    def _raw_host(self, a_prescribed: float) -> tuple:
        """Warp's solution (``qpos, qvel, qacc`` and the constraint forces ``efc.force``)
        read out in float64 by the host MuJoCo: its constraint rows rebuilt at Warp's
        state (``mj_fwdPosition``, ``mj_fwdVelocity``, the same rows in the same order),
        Warp's forces and accelerations put in, ``mj_rnePostConstraint``."""
        mj, m, h, d = self.mj, self.model, self.data, self.wd
        h.qpos[:] = d.qpos.numpy()[0]
        h.qvel[:] = d.qvel.numpy()[0]
        mj.mj_fwdPosition(m, h)
        mj.mj_fwdVelocity(m, h)
        n = int(d.nefc.numpy()[0])
        if n != h.nefc:
            return self._raw_warp(a_prescribed)  # rows differ: Warp's own readout
        h.efc_force[:] = d.efc.force.numpy()[0, :n]
        h.qacc[:] = d.qacc.numpy()[0]
        mj.mj_rnePostConstraint(m, h)
        effort = float(h.cdof[self._drive_dof] @ h.cfrc_int[self._drive_body])
        return (h.qpos.copy(), h.qvel.copy(), h.qacc.copy(), h.cfrc_int.copy(),
                h.subtree_com.copy(), h.efc_type[:n].copy(), h.efc_id[:n].copy(),
                h.efc_force[:n].copy(), a_prescribed, effort)

    def _raw_warp(self, a_prescribed: float) -> tuple:
        """:meth:`MujocoSession._raw`'s arrays, from Warp's world 0 (float32 made
        float64), plus the drive's effort along its dof, ``cdof . cfrc_int`` of the
        driven body (N m or N)."""
        d = self.wd
        n = int(d.nefc.numpy()[0])
        cfrc = d.cfrc_int.numpy()[0].astype(float)
        cdof = d.cdof.numpy()[0][self._drive_dof].astype(float)
        effort = float(cdof @ cfrc[self._drive_body])
        return (d.qpos.numpy()[0].astype(float), d.qvel.numpy()[0].astype(float),
                d.qacc.numpy()[0].astype(float), cfrc,
                d.subtree_com.numpy()[0].astype(float), d.efc.type.numpy()[0, :n].copy(),
                d.efc.id.numpy()[0, :n].copy(), d.efc.force.numpy()[0, :n].astype(float),
                a_prescribed, effort)

    def drive_effort(self, qdd, acc, raws) -> np.ndarray:
        """(K,) the drive's effort along the driven tree dof: ``cdof . cfrc_int`` of the
        driven body as Warp computed them (float32 without cancellation; the armature
        form ``A (a - qacc)`` would lose ``A eps32 |a|``)."""
        return np.array([r[9] for r in raws], float)


def _version(mjw) -> str:
    try:
        from importlib.metadata import version
        return version("mujoco-warp")
    except Exception:  # noqa: BLE001 - a version string only
        return getattr(mjw, "__version__", "?")


__all__ = ["INSTALL", "MujocoWarpSession", "MujocoWarpSettings", "WarpStepping", "constraint_rows",
           "require_warp", "warp_cache_dir"]
