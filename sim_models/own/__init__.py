"""The user's own engine model: read it as the engine reads it, check that it is a planar
one-degree-of-freedom linkage, and write its exact reference as a description.

Front door::

    from sim_models.own import import_model, imported_toml
    imp = import_model("gripper.xml", driver="crank")   # MJCF through MuJoCo's compiler
    text = imported_toml(imp)       # the TOML description, its header and the table

Bad input (a file MuJoCo cannot compile, a non-planar axis, an open loop, a linkage that
is not one degree of freedom, an unknown driver or keyframe, an element the description
cannot hold) raises one :class:`analytic.errors.DescriptionError` naming the file and the
joint, body or constraint.
"""

from __future__ import annotations

import math

import numpy as np

from analytic.errors import DescriptionError
from analytic.toml_io import mechanism_to_toml

from .describe import DEFAULT_DURATION, Imported, build
from .mjcf_read import Close, read_mjcf
from .plane import check_closures, check_one_dof, choose_driver, plane_of

#: Largest difference (rad) between a body's angle in the analytic solution at the
#: driver's reference value and its angle in the model's configuration: above it the
#: solver closed the loops on another assembly branch than the model's.  The loops
#: close to GAP_TOLERANCE (1e-6) of the size, so the angles agree to about that.
BRANCH_TOLERANCE = 1e-5


def import_model(path: str, driver: str | None = None, keyframe: str | None = None,
                 duration: float = DEFAULT_DURATION, closes: tuple[Close, ...] = ()
                 ) -> Imported:
    """Read ``path`` (MJCF, or URDF with its loop closures ``closes``, both through
    MuJoCo's reader) and return its description (see the module)."""
    if not str(path).lower().endswith((".xml", ".urdf")):
        raise DescriptionError("not an MJCF (.xml) or URDF (.urdf) file; SDF models are "
                               "not read", str(path))
    c = read_mjcf(str(path), keyframe, tuple(closes))
    drv = choose_driver(c, driver)
    plane = plane_of(c, drv)
    check_closures(c)
    check_one_dof(c, plane, drv)
    imp = build(c, plane, drv, duration)
    _check_branch(imp)
    return imp


def _check_branch(imp: Imported) -> None:
    """The analytic solution at the driver's reference value is the model's pose."""
    from analytic.kinematics import Linkage
    mech = imp.mechanism
    lk = Linkage(mech)
    kin = lk.kinematics()
    want = dict(mech.assembly.angles)
    for b in mech.moving_bodies:
        got = float(kin.theta[0, lk.body_index(b.name)])
        err = abs(math.remainder(got - want[b.name], 2 * math.pi))
        if err > BRANCH_TOLERANCE:
            raise DescriptionError(f"body {b.name!r}: the loops close at the driver's value "
                                   f"on another assembly branch ({err:.3g} rad from the "
                                   "model's pose)", str(imp.compiled.path))


def imported_toml(imp: Imported) -> str:
    """The description's TOML with a header: where it came from, the plane, what is not
    modelled and the model-to-description table."""
    p = imp.plane

    def v(x) -> str:
        return "(" + ", ".join(f"{float(a) + 0.0:.9g}" for a in np.asarray(x)) + ")"

    head = [f"# Imported by `xval import` from {imp.compiled.path} ({imp.compiled.config}).",
            f"# Plane: normal n = {v(p.n)} (joint {imp.driver.name!r}'s axis; rates are about "
            "n),", f"#   x = {v(p.e1)}, y = {v(p.e2)} (world axes).",
            "# Every length in m, angles in deg, taken from MuJoCo's compiled model.", "#",
            "# Notes:"]
    head += [f"#  - {n}" for n in imp.notes]
    head += ["#", "# Not modelled by this description (possible effect):"]
    head += [f"#  - {n}" for n in imp.not_modelled] or ["#  - nothing"]
    head += ["#", "# Model element -> description element:"]
    head += [f"#  {a:<44} -> {b}" for a, b in imp.table]
    return "\n".join(head) + "\n\n" + mechanism_to_toml(imp.mechanism)


def table_text(imp: Imported) -> str:
    """The model-to-description table as printed by ``xval import``."""
    w = max(len(a) for a, _ in imp.table)
    return "\n".join(f"{a:<{w}}  ->  {b}" for a, b in imp.table)


__all__ = ["Close", "DEFAULT_DURATION", "Imported", "import_model", "imported_toml", "table_text"]
