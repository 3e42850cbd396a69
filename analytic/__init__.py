"""Analytic vector-loop solver for planar linkages (the product).

Front door::

    from analytic import load_case, Linkage
    lk = Linkage(load_case("seed-four-bar"))
    kin = lk.kinematics()          # at the description's input
    frc = lk.forces(kin)
    kin, frc = lk.solve(x)         # both, one pass of the compiled kernel
    table = lk.sweep(360).frame    # full cycle as a DataFrame
"""

import importlib

#: the front door's names -> the module that defines each; loaded on first use (PEP 562),
#: so ``from analytic.errors import LinkageError`` or ``analytic.cases`` does not import
#: the solver and numpy (``xval --help`` and ``xval cases`` start without them)
_EXPORTS = {
    "case_names": "cases", "load_case": "cases",
    "AssemblyError": "errors", "DescriptionError": "errors", "LinkageError": "errors",
    "MissingMassError": "errors", "SingularConfigurationError": "errors",
    "Kinematics": "kinematics", "Linkage": "kinematics",
    "Forces": "kinetostatics",
    "Assembly": "mechanism", "Body": "mechanism", "Driver": "mechanism", "Load": "mechanism",
    "Mechanism": "mechanism", "Prismatic": "mechanism", "Revolute": "mechanism",
    "load_mechanism": "toml_io",
}

__all__ = ["AssemblyError", "Assembly", "Body", "DescriptionError", "Driver", "Forces",
           "Kinematics", "Linkage", "LinkageError", "Load", "Mechanism", "MissingMassError",
           "Prismatic", "Revolute", "SingularConfigurationError", "case_names", "load_case",
           "load_mechanism"]


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
        globals()[name] = value  # once
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))
