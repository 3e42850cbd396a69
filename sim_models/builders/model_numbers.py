"""How numbers are written into generated model files (URDF, closure lists).

The files must be the same bytes on every machine: the poses they hold come out of
rotations and sums that numpy may hand to a BLAS whose kernels (chosen by the CPU:
SkylakeX, Haswell, generic SSE) round differently in the last bit, so a coordinate that
is exactly zero by construction prints as ``-1.12e-17`` on one machine and
``-1.39e-17`` on another.  Two rules make the text independent of that noise:

* **Snap round-off to zero.**  A length below :data:`ROUND_OFF` of the mechanism's size
  (an angle below :data:`ROUND_OFF` rad) is written as ``0``.  The solver's own zero
  tests use the same fraction (:mod:`analytic.tolerances`), and no engine resolves a
  geometry finer than that: its loop constraints close to ~1e-10 of the size at best.
* **A fixed number of significant digits.**  :data:`MODEL_DIGITS` digits (a relative
  1e-12) are far more than any engine's accuracy needs, and a round-off difference of
  ~1e-16 relative changes the printed value only if the true value sits within 1e-16 of
  a rounding boundary at the 12th digit (about one number in 10^4 by chance; the
  committed models are tested with noise injected into their inputs).

These numbers are what the engines are built from too (PyBullet loads the same URDF
text), so a written file and a harness run see the same model.  MuJoCo's ``MjSpec``
writes its own digits (6 significant): its builder snaps round-off to zero with
:func:`snap`, and the viewer model's computed values (actuator gains, keyframe rates)
go through :func:`model_value`.
"""

from __future__ import annotations

#: Significant digits of a number in a model file (relative resolution 1e-12).
MODEL_DIGITS = 12

#: A length below this fraction of the mechanism's size, or an angle below this many
#: radians, is round-off of an exact zero and is written as 0.
ROUND_OFF = 1e-12


def model_number(x: float, scale: float = 1.0) -> str:
    """``x`` as written in a model file: 0 where ``|x| < ROUND_OFF * scale`` (``scale``:
    the mechanism's size for a length, 1 for an angle in radians, 0 for a quantity that
    is never round-off, e.g. a mass), else :data:`MODEL_DIGITS` significant digits;
    never ``-0``."""
    x = float(x)
    if abs(x) < ROUND_OFF * scale or x == 0.0:
        return "0"
    return f"{x:.{MODEL_DIGITS}g}"


def snap(x: float, scale: float = 1.0) -> float:
    """``x`` with round-off of an exact zero (``|x| < ROUND_OFF * scale``) made 0.0; other
    values unchanged (the MJCF builder: MuJoCo writes its own digits, but prints a
    near-zero as ``1e-17`` and writes an identity ``quat`` only when it is not exact)."""
    x = float(x)
    return 0.0 if abs(x) < ROUND_OFF * scale else x


def model_value(x: float, scale: float = 1.0) -> float:
    """The float that :func:`model_number` writes (for JSON files)."""
    return float(model_number(x, scale))
