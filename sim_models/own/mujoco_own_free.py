"""MuJoCo on the user's own MJCF file, released: nothing added, started from the model's
own state (its ``qpos0`` or keyframe, with the keyframe's velocities and controls), under
its own gravity, damping, springs, actuators, contacts and limits; read in the imported
description's conventions (:class:`sim_models.own.mujoco_own.Mapping`) and judged
against the exact free motion of that description."""

from __future__ import annotations

import math

import numpy as np

from ..builders.tree import SimTree
from ..engines.free_protocol import FreeRead, FreeSession
from ..runs.engine_run import Recorder
from ..runs.sampling import times_plan
from .describe import Imported
from .mujoco_own import OwnMujocoSession, OwnMujocoSettings, own_settings


class OwnFreeSession(OwnMujocoSession, FreeSession):
    """The user's model released (see the module)."""

    name = "mujoco"
    settings_class = OwnMujocoSettings
    motor_effort_source = "engine"
    native = "everything: the user's own model, as written"

    def __init__(self, tree: SimTree, imp: Imported, settings: OwnMujocoSettings):
        FreeSession.__init__(self, tree, settings)
        OwnMujocoSession.__init__(self, tree, imp, settings)

    def integrator(self) -> str:
        return self.settings.options.split("integrator=")[1].split()[0]

    def start(self, s0, h: float) -> None:
        mj, m, d, c = self.mj, self.model, self.data, self.imp.compiled
        mj.mj_resetData(m, d)
        d.qpos[:] = c.data.qpos
        d.qvel[:] = c.data.qvel
        d.ctrl[:] = c.ctrl
        m.opt.timestep = h
        mj.mj_forward(m, d)

    def advance(self, t: float, h: float, n: int) -> str | None:
        return OwnMujocoSession.advance(self, t, h, n)

    def read(self, t: float) -> FreeRead | None:
        mj, m, d, st = self.mj, self.model, self.data, self.tree
        mj.mj_forward(m, d)
        self._note_active(t)
        if d.warning[self._badqacc].number:
            return None
        if not (np.isfinite(d.qpos).all() and np.isfinite(d.qvel).all()):
            return None
        rec = Recorder(st, times_plan(st, np.array([t])))
        self.convert(np.array([t]), [self._raw(0.0)], [[0]], rec)
        mp = self.map
        q = mp.tree_q(np.array(d.qpos)[None])
        qd = (d.qvel[mp.dadr] @ mp.T.T)[None]
        qdd = (d.qacc[mp.dadr] @ mp.T.T)[None]
        th, om, al, org, vo, _ = st.propagate(q, qd, qdd)
        return FreeRead(th[0], om[0], al[0], org[0], vo[0], rec.force[0].copy(), math.nan)


def run_free_own(imp: Imported, request=None, reference=None, timestep: float | None = None,
                 tuned: tuple = ()):
    """The user's model released: a :class:`sim_models.runs.free_run.FreeEngineRun` against
    the exact free motion of ``imp.mechanism`` (``reference``, computed if not given;
    ``tuned``: settings over the file's, :func:`sim_models.own.mujoco_own.apply_tuned`)."""
    from ..engines.free_protocol import drive_free
    from ..engines.protocol import compile_linkage
    from ..runs.free_run import FreeRequest
    tree = compile_linkage(imp.mechanism, chords="analytic")  # the model's own tree
    fm = imp.mechanism.motion
    request = request or FreeRequest(duration=fm.duration, samples=max(1, fm.samples - 1))
    session = OwnFreeSession(tree, imp, own_settings(imp, prescribed=False,
                                                     timestep=timestep, tuned=tuned))
    try:
        return drive_free(session, request, reference)
    finally:
        session.close()
