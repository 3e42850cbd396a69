"""Analytic vector-loop solver for planar linkages (the product).

Front door::

    from analytic import load_case, Linkage
    lk = Linkage(load_case("seed-four-bar"))
    kin = lk.kinematics()          # at the description's input
    frc = lk.forces(kin)
    kin, frc = lk.solve(x)         # both, one pass of the compiled kernel
    table = lk.sweep(360).frame    # full cycle as a DataFrame
"""

from .cases import case_names, load_case
from .errors import (
                     AssemblyError,
                     DescriptionError,
                     LinkageError,
                     MissingMassError,
                     SingularConfigurationError,
)
from .kinematics import Kinematics, Linkage
from .kinetostatics import Forces
from .mechanism import Assembly, Body, Driver, Load, Mechanism, Prismatic, Revolute
from .toml_io import load_mechanism

__all__ = ["AssemblyError", "Assembly", "Body", "DescriptionError", "Driver", "Forces",
           "Kinematics", "Linkage", "LinkageError", "Load", "Mechanism", "MissingMassError",
           "Prismatic", "Revolute", "SingularConfigurationError", "case_names", "load_case",
           "load_mechanism"]
