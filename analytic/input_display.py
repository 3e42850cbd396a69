"""One convention for showing a run's input: the verdict table, figure axes and titles,
JUnit, Markdown, the engines' failure reasons and every message place an input the
same way (here, below the engines and the reports, so that both can use it).

A revolute input that turns fully is shown in degrees wrapped to [0, 360) (a sample of
the second turn at 495 deg reads 135 deg everywhere); a revolute input with a limited
range in degrees as its feasible interval has it (not wrapped: -40 deg stays -40, the
axis of the sweep); a prismatic input in metres, never converted.  SI in
(rad or m), display units out (deg or m).
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np

#: Digits of an input in text: enough to tell apart inputs 1e-4 deg apart on a turn
#: (the sweep's 3600-point grid is 0.1 deg) without printing round-off.
INPUT_DIGITS = 6
#: Degrees are rounded to this many decimals before wrapping, so that 360 deg - 1 ulp
#: (a sample one turn on, 2*pi*k in floating point) reads 0 deg, not 359.999999999.
WRAP_DECIMALS = 9
#: linkage -> its :class:`InputConvention` (the feasible ranges cost a scan and
#: bisection: once per linkage)
_CONVENTIONS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


@dataclass(frozen=True)
class InputConvention:
    """How an input is shown: ``revolute`` (deg) or not (m); ``full_turn``: a revolute
    input that turns fully (wrapped to [0, 360) deg)."""

    revolute: bool
    full_turn: bool = False

    @property
    def unit(self) -> str:
        return "deg" if self.revolute else "m"


def convention_of(linkage) -> InputConvention:
    """The :class:`InputConvention` of an analytic :class:`analytic.Linkage` (a full
    turn exactly when :func:`analytic.sweep.input_values` sweeps a full turn)."""
    try:
        cached = _CONVENTIONS.get(linkage)
    except TypeError:  # a linkage that cannot be a weak key: recomputed each time
        cached = None
    if cached is not None:
        return cached
    if not linkage.driver_is_revolute:
        conv = InputConvention(False, False)
    else:
        feas = linkage.feasible_ranges()
        full = len(feas) == 1 and feas[0][1] - feas[0][0] >= 2 * math.pi * (1 - 1e-9)
        conv = InputConvention(True, bool(full))
    try:
        _CONVENTIONS[linkage] = conv
    except TypeError:  # a linkage that cannot be a weak key: recomputed next time
        pass
    return conv


def display_input(values, conv: InputConvention):
    """Input values (rad or m, SI) in the display convention (deg or m): a scalar in,
    a float out; an array in, an array out.  NaN stays NaN."""
    v = np.asarray(values, float)
    if conv.revolute:
        v = np.degrees(v)
        if conv.full_turn:
            v = np.mod(np.round(v, WRAP_DECIMALS), 360.0)
    return float(v) if v.ndim == 0 else v


def input_number(value: float) -> str:
    """An input already in the display convention as a number without its unit, to
    :data:`INPUT_DIGITS` significant digits (the digits :func:`format_input` shows)."""
    return f"{value:.{INPUT_DIGITS}g}"


def format_input(value: float, unit: str) -> str:
    """An input already in the display convention (:func:`display_input`) as text with
    its unit, e.g. ``"135 deg"`` or ``"0.1 m"``; ``""`` when it is not finite."""
    if value is None or not math.isfinite(value):
        return ""
    return f"{input_number(value)} {unit}"


def input_text(value_si: float | None, conv: InputConvention) -> str:
    """An SI input (rad or m) as display text in one step (:func:`display_input`, then
    :func:`format_input`); ``""`` when it is None or not finite."""
    if value_si is None or not math.isfinite(value_si):
        return ""
    return format_input(display_input(value_si, conv), conv.unit)


__all__ = ["INPUT_DIGITS", "InputConvention", "convention_of", "display_input",
           "format_input", "input_number", "input_text"]
