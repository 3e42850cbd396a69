"""Scene economy: what MuJoCo's scene costs (contacts, gravity, extra geoms), each
variant's errors and speed through the verdict runs' session."""

from __future__ import annotations

import math
from dataclasses import asdict, replace

import numpy as np
import pandas as pd

from analytic import Linkage
from reports.comparison.runs import run_verdict
from reports.figures.study_plots import pareto_plot
from reports.studies.runs import load, make_settings
from reports.studies.speed_accuracy import run_errors, time_engine, verdict_errors
from sim_models import compile_linkage
from sim_models.builders.mjcf import MujocoSettings

SCENE_VARIANTS = {
    "minimal": "the project's scene: contacts off, no gravity, one capsule per link",
    "contacts": "contacts on, link capsules collidable in stacked z layers, pin pairs "
                "excluded",
    "contacts-same-plane": "contacts on, link capsules collidable, all in z = 0, pin pairs "
                           "excluded",
    "contacts-no-excludes": "contacts on, link capsules collidable, all in z = 0, no pin "
                            "excludes",
    "gravity": "gravity (0, -9.81) m/s^2 in the engine and the analytic reference",
    "extra-visual": "24 extra visual geoms per moving link (no collision)",
    "extra-collision": "24 extra collidable geoms per link in stacked layers, contacts on, "
                       "pin pairs excluded",
    "everything": "extra collidable geoms, contacts on, gravity on",
}


#: scene variant -> (MujocoSettings.scene, gravity in the description)
SCENE_PARTS = {
    "minimal": ("minimal", False), "contacts": ("contacts", False),
    "contacts-same-plane": ("contacts-same-plane", False),
    "contacts-no-excludes": ("contacts-no-excludes", False), "gravity": ("minimal", True),
    "extra-visual": ("extra-visual", False), "extra-collision": ("extra-collision", False),
    "everything": ("extra-collision", True),
}


def scene_task(case_name: str, variant: str, settings_dict: dict, timing_steps: int,
               repeats: int) -> dict:
    """One scene variant (:data:`SCENE_VARIANTS`; the MuJoCo scene is a setting,
    :attr:`sim_models.builders.mjcf.MujocoSettings.scene`): errors and speed, through the verdict
    runs' session.  Never raises."""
    try:
        scene, gravity = SCENE_PARTS[variant]
        mech0 = load(case_name)
        mech = replace(mech0, gravity=(0.0, -9.81)) if gravity else mech0
        tree = compile_linkage(mech)
        s = make_settings("mujoco", dict(settings_dict, scene=scene))
        v = run_verdict(tree, "mujoco", s)  # the one run-and-compare, the request's defaults
        r = v.run
        e = verdict_errors(r, v.comparisons)
        notes = [SCENE_VARIANTS[variant]]
        if mech is not mech0 and r.ok:
            # deliberately judged against another description: its own Linkage
            e0 = run_errors(r, Linkage(mech0))
            notes.append(f"against the gravity-free description: accel {e0['accel_error']:.2g},"
                         f" force {e0['force_error']:.2g}")
        sps = time_engine(tree, "mujoco", s, r.timestep, timing_steps, repeats)
        return dict(variant=variant, seconds_per_rev=r.steps_per_rev / sps if sps else math.nan,
                    steps_per_second=sps, accel_error=e["accel_error"],
                    force_error=e["force_error"], error=e["error"],
                    ngeom=int(r.extra.get("ngeom", 0)),
                    max_contacts=int(r.extra.get("max_contacts", 0)), ok=r.ok,
                    reason=r.reason or "", notes="; ".join(notes))
    except Exception as ex:  # noqa: BLE001
        return dict(variant=variant, seconds_per_rev=math.nan, steps_per_second=math.nan,
                    accel_error=math.inf, force_error=math.inf, error=math.inf, ngeom=0,
                    max_contacts=0, ok=False, reason=f"{type(ex).__name__}: {ex}",
                    notes=SCENE_VARIANTS.get(variant, ""))


def scene_economy(quick: bool, case: str = "seed-four-bar") -> pd.DataFrame:
    """``case`` in MuJoCo (the project's default settings) with the minimal scene and
    with unneeded parts added (:data:`SCENE_VARIANTS`).  Columns ``variant,
    seconds_per_rev, steps_per_second, accel_error, force_error, error, ngeom,
    max_contacts, ok, reason, notes`` plus ``slowdown`` (time / the minimal scene's).
    Runs serially (timings of the variants side by side on one core)."""
    sd = asdict(MujocoSettings())
    steps, reps = (2000, 3) if quick else (6000, 5)
    rows = [scene_task(case, v, sd, steps, reps) for v in SCENE_VARIANTS]
    df = pd.DataFrame(rows)
    base = df.loc[df["variant"] == "minimal", "seconds_per_rev"]
    df["slowdown"] = df["seconds_per_rev"] / float(base.iloc[0]) if len(base) else math.nan
    cols = ["variant", "seconds_per_rev", "slowdown", "steps_per_second", "accel_error",
            "force_error", "error", "ngeom", "max_contacts", "ok", "reason", "notes"]
    return df[cols]


def scene_figure(scene: pd.DataFrame) -> bytes:
    rows = [dict(engine="mujoco", label=r.variant, seconds_per_rev=r.seconds_per_rev,
                 error=r.error) for r in scene.itertuples()
            if np.isfinite(r.seconds_per_rev)]
    return pareto_plot(rows, "seed-four-bar in MuJoCo: what the unneeded scene parts cost")


