"""Diagnosis of a run on the user's own model: modelling defects, each with its size, and
the engine's error with the model's settings (lines for ``xval compare`` / ``simulate``)."""

from __future__ import annotations

import numpy as np

from .describe import Imported
from .plane import size_of


def model_defects(imp: Imported) -> list[str]:
    """Defects of the model itself, measured at its reference configuration: the largest
    loop gap, the largest tilt of a joint axis out of the plane's normal (or of a slide
    out of the plane), the inertia couplings, and what the reference does not model."""
    c, n = imp.compiled, imp.plane.n
    out = []
    if c.closures:
        gaps = [(float(np.linalg.norm(cl.p1 - cl.p2)), cl.name) for cl in c.closures]
        g, name = max(gaps)
        out.append(f"loop closure at the model's pose ({c.config}): connect {name!r} "
                   f"{g * 1e3:.3g} mm open ({g / size_of(c):.2g} of the size)")
    tilts = []
    for j in c.joints:
        a = j.axis / np.linalg.norm(j.axis)
        tilts.append((float(np.arctan2(np.linalg.norm(np.cross(a, n)), abs(a @ n)))
                      if j.kind == "hinge" else float(abs(np.arcsin(np.clip(a @ n, -1, 1)))),
                      j.name))
    t, name = max(tilts)
    out.append(f"axes: largest tilt out of the plane {t:.2g} rad (joint {name!r})")
    out += [x for x in imp.notes if "couples" in x]
    out += [f"not modelled: {x}" for x in imp.not_modelled]
    return out


def run_findings(run, soft: str = "the model's solref/solimp") -> list[str]:
    """What acted during the run besides the linkage, and the loop's opening (``soft``:
    what makes the loop constraints soft in that engine)."""
    out = []
    for what, t in sorted(run.extra.get("active", {}).items(), key=lambda kv: kv[1]):
        out.append(f"modelling: {what} acted during the motion (first at t = {t:.4g} s)")
    if not run.ok:
        out.append(f"engine: the run stopped: {run.reason} (with {soft} "
                   f"at its step {run.timestep:.3g} s; the loops opened beyond the harness's "
                   "divergence limit)")
    viol = np.asarray(run.loop_violation, float)
    if viol.size and np.isfinite(viol).any():
        out.append(f"engine: the loops opened by up to {np.nanmax(np.abs(viol)) * 1e3:.3g} mm "
                   f"during the run (constraint softness of {soft} at its "
                   f"step {run.timestep:.3g} s)")
    return out
