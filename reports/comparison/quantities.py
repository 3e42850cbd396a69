"""The quantities a comparison names, and which of them the verdict judges.

A verdict quantity is named ``WHAT.KIND`` (``rocker.alpha``, ``B.force``,
``drive.effort``, ``S.normal``).  An engine's own reading of a quantity (PyBullet's
``jointReactionForces``, a drive's applied effort) is compared under the same name with
:data:`ENGINE_READING` appended: reported beside the judged rows, never judged (README,
Engines).  Every module asks here whether a row is one.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TypeVar

#: The suffix of an engine's own reading (``B.force[engine]``).
ENGINE_READING = "[engine]"

_C = TypeVar("_C")


def engine_reading(quantity: str) -> str:
    """The name of the engine's own reading of ``quantity``."""
    return quantity + ENGINE_READING


def is_engine_reading(quantity: str) -> bool:
    """Whether ``quantity`` names an engine's own reading (reported, not judged)."""
    return quantity.endswith(ENGINE_READING)


def base_quantity(quantity: str) -> str:
    """``quantity`` without the engine-reading suffix (its unit and family are those of
    the judged quantity it reads)."""
    return quantity.removesuffix(ENGINE_READING)


def judged(comparisons: Iterable[_C]) -> list[_C]:
    """The comparisons the verdict judges: the quantities this project computes, the
    engines' own readings left out (anything with a ``quantity`` name)."""
    return [c for c in comparisons if not is_engine_reading(c.quantity)]


__all__ = ["ENGINE_READING", "base_quantity", "engine_reading", "is_engine_reading", "judged"]
