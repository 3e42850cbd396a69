"""The studies' engine runs: the same sessions and run loop as the verdict runs.

Every study measurement goes through :mod:`sim_models`: errors from
:func:`sim_models.runs.driven.run` (the run loop :func:`sim_models.engines.protocol.drive`), speed
from :func:`sim_models.runs.driven.time_engine` (the sessions' own ``advance``, the stepping
loop of those runs, without readout), long and change-point runs from the same ``run``
with a plan of equal times (:func:`sim_models.engines.protocol.periodic_plan`).  Nothing here
steps an engine or imports an engine library.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from analytic import Mechanism, load_case
from analytic.cases import HARD_CASES_DIR, hard_case_names
from analytic.sweep import input_values
from reports.comparison.runs import request_of
from sim_models.engines.protocol import loop_gap, periodic_plan, travel_time
from sim_models.engines.registry import make_settings as registry_settings
from sim_models.runs.driven import run


def load(case: str) -> Mechanism:
    """A built-in or hard case by name, or a TOML file (:func:`analytic.load_case`)."""
    return load_case(case)


# ============================================================================ settings
def make_settings(engine: str, settings: dict):
    """The engine's settings object from a plain dict of its fields (the registry's
    settings classes; lists become tuples)."""
    return registry_settings(engine, settings)


def revolution_time(mech) -> float:
    """Duration of the driver's first revolution (s)."""
    return travel_time(mech.driver, 2 * math.pi)


@dataclass
class Trace:
    """Raw samples of a long engine run (tree coordinates, SI), from an
    :class:`~sim_models.engines.protocol.EngineRun` sampled at equal times."""

    engine: str
    settings: str
    t: np.ndarray          # (N,) s
    q: np.ndarray          # (N, nt)
    qd: np.ndarray         # (N, nt)
    qdd: np.ndarray        # (N, nt)
    effort: np.ndarray     # (N,) drive effort on body_b, N m
    ok: bool
    reason: str
    wall: float            # s of the whole loop (stepping and sampling)
    steps: int
    dt: float
    per_rev: int


def trace(tree, engine: str, settings, revolutions: int, per_rev: int,
          max_violation: float | None = None, max_speed_error: float | None = None) -> Trace:
    """Run ``engine`` for ``revolutions`` turns from the reference state, sampled
    ``per_rev`` times per turn (the verdict runs' session and run loop); samples up to a
    divergence.  A divergence limit left None is the run request's default."""
    plan = periodic_plan(tree, revolutions, per_rev)
    req = request_of({"max_violation": max_violation, "max_speed_error": max_speed_error})
    r = run(tree, engine, settings, plan=plan, max_violation=req.max_violation,
            max_speed_error=req.max_speed_error)
    good = np.all(np.isfinite(r.q), axis=1) & np.isfinite(r.times)
    K = int(np.argmin(good)) if not good.all() else len(good)
    return Trace(r.engine, r.settings_text, r.times[:K], r.q[:K], r.qd[:K], r.qdd[:K],
                 r.drive_effort[:K], r.ok, r.reason or "", r.wall, r.steps, r.timestep,
                 per_rev)


def trace_diagnostics(tree, tr: Trace, analytic: bool = True) -> pd.DataFrame:
    """Per-sample diagnostics of a :class:`Trace` (one row per sample) on the compiled
    linkage ``tree``:

    ``t``, ``input_deg`` (the engine's own driver angle), ``phase_drift`` (engine driver
    angle minus the prescribed one, rad), ``loop_violation`` (largest loop gap / the
    mechanism's size), ``speed_deviation`` ((rate - omega) / omega), ``ke`` (J, the
    engine's body velocities and the engine's mass properties), ``drive_power`` (W),
    ``power_residual`` (drive + gravity power - dKE/dt, relative to the analytic peak
    drive power), ``energy_balance`` (drive + gravity work, trapezoid rule over the
    samples, minus the change of KE, relative to the analytic drive throughput
    ``integral |P| dt`` of one revolution), ``theta.<body>`` (deg, unwrapped) and, with
    ``analytic``, ``alpha_error`` and ``effort_error`` against the analytic solution at
    the engine's driver angle (normalised by the analytic peaks over a revolution).
    """
    st = tree
    mech, lk = st.mech, st.linkage
    th, om, al, org, v, a = st.propagate(tr.q, tr.qd, tr.qdd)
    x = st.driver_value(tr.q[:, st.driver_tree])
    presc, w, _ = (np.asarray(z, float) for z in st.driver_path(tr.t))
    w0 = mech.driver.velocity
    rate = st.driver_sigma * tr.qd[:, st.driver_tree]
    gap = np.array([loop_gap(st, th[i:i + 1], org[i:i + 1]) for i in range(len(tr.t))])
    g = np.asarray(mech.gravity, float)
    ke = np.zeros(len(tr.t))
    dke = np.zeros(len(tr.t))
    pg = np.zeros(len(tr.t))
    for b in range(len(st.body_names)):
        if b == st.ground:
            continue
        c = st.com[b]
        cs, sn = np.cos(th[:, b]), np.sin(th[:, b])
        r = np.stack([cs * c[0] - sn * c[1], sn * c[0] + cs * c[1]], axis=1)
        rp = np.stack([-r[:, 1], r[:, 0]], axis=1)
        vc = v[:, b] + om[:, b, None] * rp
        ac = a[:, b] + al[:, b, None] * rp - (om[:, b] ** 2)[:, None] * r
        m_, I_ = st.mass[b], st.inertia[b]
        ke += 0.5 * m_ * np.sum(vc * vc, axis=1) + 0.5 * I_ * om[:, b] ** 2
        dke += m_ * np.sum(vc * ac, axis=1) + I_ * om[:, b] * al[:, b]
        pg += m_ * vc @ g
    power = tr.effort * rate
    kin1 = frc1 = None
    p_peak = throughput = math.nan
    if analytic:
        vals, _, _ = input_values(lk, max(tr.per_rev, 36))
        kin1 = lk.kinematics(vals, on_singular="flag")
        frc1 = lk.forces(kin1) if mech.has_mass else None
        if frc1 is not None:
            p_peak = float(np.nanmax(np.abs(frc1.power)))
            throughput = float(np.nanmean(np.abs(frc1.power)) * revolution_time(mech))
    P = power + pg
    work = np.concatenate([[0.0], np.cumsum(0.5 * (P[1:] + P[:-1]) * np.diff(tr.t))])
    cols = {"t": tr.t, "input_deg": np.degrees(x), "phase_drift": x - presc,
            "loop_violation": gap / st.size, "speed_deviation": (rate - w) / abs(w0),
            "ke": ke, "drive_power": power, "power_residual": (P - dke) / p_peak,
            "energy_balance": (work - (ke - ke[0])) / throughput}
    for b, name in enumerate(st.body_names):
        if b != st.ground:
            cols[f"theta.{name}"] = np.degrees(th[:, b])
    if analytic:
        kin = lk.kinematics(x, w, np.full(len(x), mech.driver.acceleration),
                            on_singular="flag")
        moving = [b for b in range(len(st.body_names)) if b != st.ground]
        pk = float(np.nanmax(np.abs(kin1.alpha[:, moving])))
        cols["alpha_error"] = np.max(np.abs(al[:, moving] - kin.alpha[:, moving]), axis=1) / pk
        if frc1 is not None:
            frc = lk.forces(kin)
            cols["effort_error"] = np.abs(tr.effort - frc.effort) / \
                float(np.nanmax(np.abs(frc1.effort)))
    return pd.DataFrame(cols)


__all__ = ["HARD_CASES_DIR", "Trace", "hard_case_names", "load", "make_settings",
           "revolution_time", "trace", "trace_diagnostics"]
