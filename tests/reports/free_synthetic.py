"""Synthetic engine free runs for the judging tests: the exact trajectory, sampled, with
perturbations whose errors are known in closed form (no engine runs)."""

from __future__ import annotations

import numpy as np

from sim_models.engines.settings import EngineSettings
from sim_models.runs.free_run import FreeEngineRun, FreeRequest


def synthetic_run(traj, duration: float, samples: int, *, engine: str = "fake",
                  timestep: float = 1e-3, **perturb) -> FreeEngineRun:
    """A :class:`FreeEngineRun` equal to the reference at ``samples + 1`` times, then
    changed by ``perturb``: ``x_drift=(joint index, c, t0)`` adds ``c * max(0, t - t0)``
    to a joint coordinate; ``theta_offset=(body index, d)`` adds ``d`` to a body angle;
    ``kinetic_factor=f`` multiplies the kinetic energy; ``gap=g`` makes the loop gap
    ``g * t / duration``; ``stop_at=k`` makes rows from ``k`` on NaN (a failed run)."""
    req = FreeRequest(duration=duration, samples=samples)
    t = req.times()
    s = traj.at(t)
    mech = traj.mech
    x, theta = s.x.copy(), s.theta.copy()
    if "x_drift" in perturb:
        j, c, t0 = perturb["x_drift"]
        x[:, j] += c * np.maximum(0.0, t - t0)
    if "theta_offset" in perturb:
        b, d = perturb["theta_offset"]
        theta[:, b] += d
    kinetic = s.kinetic * perturb.get("kinetic_factor", 1.0)
    gap = perturb.get("gap", 0.0) * t / duration
    jf = np.stack([s.reactions[j.name] for j in mech.joints], axis=1)
    run = dict(x=x, xd=s.xd.copy(), theta=theta, omega=s.omega.copy(), alpha=s.alpha.copy(),
               joint_force=jf, loop_gap=gap, kinetic=kinetic, potential=s.potential.copy())
    ok, reason, t_fail = True, None, None
    if "stop_at" in perturb:
        k = perturb["stop_at"]
        for v in run.values():
            v[k:] = np.nan
        ok, reason, t_fail = False, "non-finite state (simulation diverged)", float(t[k])
    return FreeEngineRun(
        case=mech.name, engine=engine, mechanism=mech, settings=EngineSettings(timestep),
        request=req, ok=ok, reason=reason, t_fail=t_fail, times=t,
        joint_names=tuple(j.name for j in mech.joints),
        body_names=tuple(b.name for b in mech.bodies), motor_effort_engine=None,
        wall=0.01 * duration, steps=int(round(duration / timestep)), timestep=timestep,
        integrator="synthetic", **run)
