"""Typed errors raised at the API boundary.

Every error names what is at fault (file, body, point, joint, input value) so
that a user never has to read a traceback from deep inside numpy.  All derive
from :class:`LinkageError`, itself a :class:`ValueError`.
"""

from __future__ import annotations


class LinkageError(ValueError):
    """Base class of every error this package raises on bad input."""


class DescriptionError(LinkageError):
    """The mechanism description is malformed or inconsistent.

    Parameters
    ----------
    message
        What is wrong.
    where
        Where it is wrong, e.g. ``"cases/four.toml: joint 'B'"``.
    """

    def __init__(self, message: str, where: str | None = None):
        self.where = where
        super().__init__(f"{where}: {message}" if where else message)


class OutputError(LinkageError):
    """An output file or folder the user named cannot be written."""


class MissingMassError(DescriptionError):
    """Forces were requested but a moving body has no mass properties."""


class AssemblyError(LinkageError):
    """The loops cannot close at the requested input value.

    Attributes
    ----------
    input_value
        The driver value (rad or m, SI) at which assembly failed.
    feasible
        The feasible input intervals found near it, as a list of (lo, hi) in SI
        units, or ``None`` when they were not computed.
    """

    def __init__(self, message: str, input_value: float | None = None,
                 feasible: list[tuple[float, float]] | None = None):
        self.input_value = input_value
        self.feasible = feasible
        super().__init__(message)


class SingularConfigurationError(LinkageError):
    """The velocity/acceleration (or force) equations are singular at this input.

    Raised at a dead-centre or change point, where the loop Jacobian loses
    rank and the velocities are not determined by the input alone.
    """

    def __init__(self, message: str, input_value: float | None = None):
        self.input_value = input_value
        super().__init__(message)
