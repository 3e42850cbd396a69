"""The change-point study: a parallelogram four-bar through its singular positions.

The two assembly modes come from the analytic solver: one :class:`~analytic.Linkage`
per assembly (the description's hint, and the other intersection of the dyad's circles
as the hint of a second description), each holding its dyad signs; at every input they
are labelled ``parallelogram`` (the rocker parallel to the crank) or
``anti-parallelogram`` from their joint positions.  The engines run through the verdict
runs' session code (:func:`reports.studies.runs.trace`).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from analytic import Linkage, Mechanism
from analytic.mechanism import Assembly
from reports.studies.runs import load, make_settings, trace, trace_diagnostics
from sim_models import compile_linkage
from sim_models.builders.tree import wrap as _wrap  # (-pi, pi], the engine trees' own

#: Loop gap (relative to the mechanism's size) that ends a change-point run: looser than
#: the engine runs' 1e-3 so that soft (stock) constraints still show a branch.
CHANGE_POINT_MAX_VIOLATION = 1e-2


def _held(mech: Mechanism) -> Linkage:
    """A Linkage that holds its reference dyad signs (one assembly mode)."""
    try:
        return Linkage(mech, branch_rule="hold")
    except TypeError:  # a solver without branch rules holds its signs
        return Linkage(mech)


def four_bar_joints(mech: Mechanism) -> dict[str, str]:
    """Body and joint names of a four-bar driven at the ground: ``crank, coupler, rocker``
    and the joints ``drive`` (ground-crank), ``crank_coupler``, ``coupler_rocker``,
    ``rocker_ground``."""
    dj = mech.driver_joint
    g = mech.ground
    crank = dj.body_b if dj.body_a == g else dj.body_a
    rg = next(j for j in mech.joints if g in j.bodies and j.name != dj.name)
    rocker = rg.body_b if rg.body_a == g else rg.body_a
    cj = next(j for j in mech.joints if crank in j.bodies and j.name != dj.name)
    coupler = cj.body_b if cj.body_a == crank else cj.body_a
    rj = next(j for j in mech.joints if rocker in j.bodies and coupler in j.bodies)
    return dict(crank=crank, coupler=coupler, rocker=rocker, drive=dj.name,
                crank_coupler=cj.name, coupler_rocker=rj.name, rocker_ground=rg.name)


def _joint_point(mech: Mechanism, joint: str, body: str) -> str:
    j = next(x for x in mech.joints if x.name == joint)
    return j.point_a if j.body_a == body else j.point_b


def other_assembly(mech: Mechanism) -> Mechanism:
    """The description with its assembly hint moved to the other assembly mode: the
    coupler-rocker pin reflected across the line from the crank pin to the rocker's
    ground pivot (the two intersections of the dyad's circles)."""
    n = four_bar_joints(mech)
    kin = Linkage(mech).kinematics()
    A = kin.point(n["crank"], _joint_point(mech, n["crank_coupler"], n["crank"]))[0][0]
    bp = _joint_point(mech, n["coupler_rocker"], n["coupler"])
    B = kin.point(n["coupler"], bp)[0][0]
    O4 = kin.point(n["rocker"], _joint_point(mech, n["rocker_ground"], n["rocker"]))[0][0]
    u = (O4 - A) / np.linalg.norm(O4 - A)
    r = B - A
    B2 = A + 2 * (r @ u) * u - r
    hint = Assembly(points={f"{n['coupler']}.{bp}": (float(B2[0]), float(B2[1]))})
    return replace(mech, assembly=hint)


def assembly_modes(mech: Mechanism, theta2) -> dict[str, np.ndarray]:
    """The rocker's angle (rad) in each assembly mode at each driver value (rad), from the
    analytic solver: ``"parallelogram"`` is, at each input, the mode whose rocker
    direction (ground pivot to pin) is nearer the crank's direction (ground pivot to
    pin), ``"anti-parallelogram"`` the other."""
    n = four_bar_joints(mech)
    x = np.atleast_1d(np.asarray(theta2, float))
    rb = [b.name for b in mech.bodies].index(n["rocker"])
    out = []
    for m in (mech, other_assembly(mech)):
        kin = _held(m).kinematics(x, on_singular="flag")
        O2 = kin.point(n["crank"], _joint_point(mech, n["drive"], n["crank"]))[0]
        A = kin.point(n["crank"], _joint_point(mech, n["crank_coupler"], n["crank"]))[0]
        O4 = kin.point(n["rocker"], _joint_point(mech, n["rocker_ground"], n["rocker"]))[0]
        B = kin.point(n["rocker"], _joint_point(mech, n["coupler_rocker"], n["rocker"]))[0]
        crank_dir = np.arctan2(A[:, 1] - O2[:, 1], A[:, 0] - O2[:, 0])
        rocker_dir = np.arctan2(B[:, 1] - O4[:, 1], B[:, 0] - O4[:, 0])
        out.append((kin.theta[:, rb], np.abs(_wrap(rocker_dir - crank_dir))))
    (y0, d0), (y1, d1) = out
    para = np.where(d0 <= d1, y0, y1)
    anti = np.where(d0 <= d1, y1, y0)
    return {"parallelogram": para, "anti-parallelogram": anti}


def classify_branch(theta2, rocker, modes: dict[str, np.ndarray], singular_deg,
                    exclude_deg: float = 15.0, tol_deg: float = 5.0) -> list[dict]:
    """Label each stretch between singular positions: ``parallelogram``,
    ``anti-parallelogram`` or ``diverged``.

    ``theta2`` is the unwrapped input (rad), ``rocker`` the rocker angle (rad, NaN where
    the run had failed), ``modes`` from :func:`assembly_modes`, ``singular_deg`` the
    singular input angles (deg, mod 360).  Samples within ``exclude_deg`` of a singular
    position are left out (the modes meet there); a stretch is a branch when every
    remaining sample is within ``min(tol_deg, half the modes' separation)`` of it.
    """
    x = np.degrees(np.asarray(theta2, float))
    lo, hi = float(np.nanmin(x)), float(np.nanmax(x))
    sing = sorted({s + 360 * k for s in singular_deg for k in range(-2, 100)
                   if lo < s + 360 * k < hi})
    edges = [lo - 1e-9] + sing + [hi + 1e-9]
    out = []
    names = list(modes)
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        sel = (x >= a) & (x <= b)
        near = np.zeros_like(sel)
        for s in sing:
            near |= np.abs(x - s) < exclude_deg
        use = sel & ~near
        label, worst = "diverged", math.nan
        if use.any():
            y = np.asarray(rocker)[use]
            dists = {n: np.degrees(np.abs(_wrap(y - modes[n][use]))) for n in names}
            sep = np.degrees(np.abs(_wrap(modes[names[0]][use] - modes[names[1]][use])))
            lim = np.minimum(tol_deg, 0.5 * sep)
            for n in names:
                if np.all(np.isfinite(dists[n])) and np.all(dists[n] <= lim):
                    label, worst = n, float(np.max(dists[n]))
                    break
            else:
                worst = float(np.nanmax(np.fmin(*dists.values()))) if np.isfinite(
                    np.fmin(*dists.values())).any() else math.inf
        out.append(dict(start_deg=a if a > lo else lo, end_deg=b if b < hi else hi,
                        branch=label, max_deviation_deg=worst, samples=int(use.sum())))
    return out


def rocker_name(mech: Mechanism) -> str:
    return four_bar_joints(mech)["rocker"]


def singular_inputs(lk: Linkage, points: int = 3600) -> list[float]:
    """Input angles (deg, mod 360) of the singular positions of a sweep."""
    ev = lk.sweep(points, forces=False).events
    s = ev[ev["kind"] == "singular"]["input"].to_numpy(float)
    out: list[float] = []
    for v in np.mod(s, 360.0):
        if all(abs(_wrap(math.radians(v - o))) > 1e-3 for o in out):
            out.append(float(v))
    return sorted(out)


def _summary(segs: list[dict]) -> dict:
    return dict(final_branch=segs[-1]["branch"] if segs else "diverged",
                branches=" > ".join(s["branch"] for s in segs),
                flips=sum(1 for a, b in zip(segs[:-1], segs[1:], strict=False)
                          if a["branch"] != b["branch"]),
                max_deviation_deg=max((s["max_deviation_deg"] for s in segs
                                       if np.isfinite(s["max_deviation_deg"])),
                                      default=math.nan))


def change_point_task(case_name: str, engine: str, settings_dict: dict, revolutions: int,
                      per_rev: int = 72) -> dict:
    """Run a change-point four-bar through its singular positions and label the branch
    the engine follows after each (see :func:`classify_branch`).  Never raises."""
    label = "diverged"
    try:
        tree = compile_linkage(load(case_name))
        mech = tree.mech
        tr = trace(tree, engine, make_settings(engine, settings_dict), revolutions, per_rev,
                   CHANGE_POINT_MAX_VIOLATION)
        diag = trace_diagnostics(tree, tr, analytic=False)
        sing = singular_inputs(tree.linkage)
        x = np.radians(diag["input_deg"].to_numpy())
        y = np.radians(diag[f"theta.{rocker_name(mech)}"].to_numpy())
        modes = assembly_modes(mech, x)
        segs = classify_branch(x, y, modes, sing) if len(x) > 1 else []
        after = [s["branch"] for s in segs[1:]]
        if not tr.ok:
            # a stretch the run did not finish is a divergence
            full_x = np.degrees(mech.driver.value) + 360.0 * revolutions
            if segs and segs[-1]["end_deg"] < full_x - 1:
                segs[-1]["branch"] = "diverged"
                after = [s["branch"] for s in segs[1:]]
            if not after:
                after = ["diverged"]
        label = after[0] if after else "diverged"
        return dict(case=case_name, engine=engine, settings=tr.settings, ok=tr.ok,
                    reason=tr.reason, timestep=tr.dt, branch_after_singular=label,
                    **_summary(segs),
                    max_loop_violation=float(diag["loop_violation"].max())
                    if len(diag) else math.nan,
                    revolutions=revolutions,
                    series={"input_deg": diag["input_deg"].tolist(),
                            "rocker_deg": np.degrees(y).tolist()},
                    segments=segs)
    except Exception as e:  # noqa: BLE001
        return dict(case=case_name, engine=engine, settings=str(settings_dict), ok=False,
                    reason=f"{type(e).__name__}: {e}", branch_after_singular=label,
                    branches="", flips=0, max_deviation_deg=math.nan,
                    max_loop_violation=math.nan, revolutions=revolutions, series=None,
                    segments=[])


def analytic_branch(case_name: str, revolutions: int = 1, per_rev: int = 72) -> dict:
    """The branch the analytic solver's own solution (``Linkage(mech).kinematics``, the
    reference solution of every verdict run) follows through the singular positions."""
    mech = load(case_name)
    lk = Linkage(mech)
    x = mech.driver.value + 2 * np.pi * np.arange(revolutions * per_rev + 1) / per_rev
    kin = lk.kinematics(x, on_singular="flag")
    rb = [b.name for b in mech.bodies].index(rocker_name(mech))
    y = kin.theta[:, rb]
    modes = assembly_modes(mech, x)
    segs = classify_branch(x, y, modes, singular_inputs(lk))
    return dict(case=case_name, engine="analytic", settings="Linkage.kinematics",
                ok=True, reason="", timestep=math.nan,
                branch_after_singular=segs[1]["branch"] if len(segs) > 1 else segs[0]["branch"],
                **_summary(segs), max_loop_violation=0.0, revolutions=revolutions,
                series={"input_deg": np.degrees(x).tolist(),
                        "rocker_deg": np.degrees(y).tolist()},
                segments=segs)


__all__ = ["CHANGE_POINT_MAX_VIOLATION", "analytic_branch", "assembly_modes",
           "change_point_task", "classify_branch", "other_assembly", "rocker_name",
           "singular_inputs"]
