"""The IFToMM benchmark's accuracy rule on a free run (Gonzalez et al. 2006): the
reference point's position error over the run, m, against the benchmark's two precision
levels, for the IFToMM problems among the cases (:data:`IFTOMM_POINTS`).
:func:`reports.comparison.free_compare.compare_free` puts it in a
:class:`reports.comparison.free_compare.FreeVerdict`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from analytic.mechanism import Revolute
from reports.comparison.compare import json_safe

#: The IFToMM benchmark's two precision levels for the reference point's position
#: error over the run, m (Gonzalez et al. 2006: low and high precision).
IFTOMM_LEVELS = (1e-1, 1e-3)
#: The IFToMM problems among the cases, and their reference point (body, point): A01's
#: lumped mass, A02's B0 (the tip of the first vertical link).  A03 (Andrews) publishes
#: angles at 0.03 s, not a point's path: it has no position class.
IFTOMM_POINTS = {"iftomm-a01-pendulum": ("link", "P1"),
                 "iftomm-a02-n-four-bar": ("crank0", "B")}


@dataclass(frozen=True)
class IftommAccuracy:
    """The IFToMM accuracy rule on one run: the reference point ``body.point``'s
    position error (Euclidean, m) over the run, its time, and its class: ``"1e-3"``
    (high precision: at most 1e-3 m), ``"1e-1"`` (low: at most 1e-1 m), ``"none"``
    (beyond both, or not measured over the whole run)."""

    problem: str
    body: str
    point: str
    max_error: float
    at: float
    measured: bool
    level: str

    def as_json(self) -> dict:
        return json_safe(self.__dict__.copy())


def grounded_point(mech, body: str, point: str, theta: np.ndarray) -> np.ndarray:
    """``(N, 2)`` world position, m, of ``point`` of ``body`` when ``body`` is pinned to
    the ground by a revolute joint and turned to the absolute angles ``theta`` (rad):
    ``pin + R(theta) (p - pin_b)`` in the body frame.  Raises ValueError when the body
    has no revolute joint to the ground."""
    bodies = {b.name: b for b in mech.bodies}
    for j in mech.joints:
        if isinstance(j, Revolute) and {j.body_a, j.body_b} == {mech.ground, body}:
            g_pt, b_pt = (j.point_a, j.point_b) if j.body_a == mech.ground else \
                (j.point_b, j.point_a)
            pin = np.asarray(bodies[mech.ground].points[g_pt], float)
            rel = np.asarray(bodies[body].points[point], float) - \
                np.asarray(bodies[body].points[b_pt], float)
            c, s = np.cos(theta), np.sin(theta)
            return pin + np.stack([c * rel[0] - s * rel[1], s * rel[0] + c * rel[1]], axis=1)
    raise ValueError(f"body {body!r} has no revolute joint to the ground")


def iftomm_level(max_error: float, measured: bool = True) -> str:
    """The IFToMM precision class of a position error, m: ``"1e-3"``, ``"1e-1"`` or
    ``"none"``."""
    if not measured or not math.isfinite(max_error):
        return "none"
    for lim in sorted(IFTOMM_LEVELS):
        if max_error <= lim:
            return f"{lim:.0e}".replace("e-0", "e-")
    return "none"


def iftomm_accuracy(run, ref, mech) -> IftommAccuracy | None:
    """The IFToMM accuracy rule where ``run.case`` is one of :data:`IFTOMM_POINTS`
    (None otherwise): the reference point's position error over the run, from the body
    angles of both (the point's body turns about a ground pin, so its angle fixes it)."""
    where = IFTOMM_POINTS.get(run.case)
    if where is None:
        return None
    body, point = where
    names = [b.name for b in mech.bodies]
    p_ref = grounded_point(mech, body, point, ref.theta[:, names.index(body)])
    p_eng = grounded_point(mech, body, point, run.theta[:, list(run.body_names).index(body)])
    err = np.linalg.norm(p_ref - p_eng, axis=1)
    finite = np.isfinite(err)
    if not finite.any():
        return IftommAccuracy(run.case, body, point, math.inf, float(run.times[0]), False,
                              "none")
    k = int(np.argmax(np.where(finite, err, -1.0)))
    return IftommAccuracy(run.case, body, point, float(err[k]), float(run.times[k]),
                          bool(finite.all()), iftomm_level(float(err[k]), bool(finite.all())))



__all__ = ["IFTOMM_LEVELS", "IFTOMM_POINTS", "IftommAccuracy", "grounded_point",
           "iftomm_accuracy", "iftomm_level"]
