"""An engine's arithmetic and the error floor it sets (:class:`Arithmetic`).

An engine's settings declare the arithmetic its solver computes in
(:attr:`sim_models.engines.settings.EngineSettings.arithmetic`).  A float64 engine claims
no floor: its round-off (``u64 = 1.1e-16`` per operation) lies ten orders of magnitude
below any tolerance this harness applies, so its verdict is pass or FAIL.  A float32
engine (MuJoCo Warp) has a floor that can reach a tolerance: the verdict reads
"precision limit (float32)" where the error exceeds the tolerance but sits at or below
the floor (:meth:`Arithmetic.floor`), and FAIL above it.

The float32 floor (normalised by the quantity's peak, as the errors)::

    floor = STEP_GROWTH  * u32 * steps * condition     (a run of ``steps`` steps)
    floor = SOLVE_GROWTH * u32 * condition             (one solve: the instantaneous mode)

* ``u32 = 2**-24`` (5.96e-8), float32's unit round-off;
* ``steps``: the steps the run took (float32 ``qpos`` is rounded at every step and the
  rounding accumulates: measured linear in the step count, see below);
* ``condition``: the analytic loop-Jacobian condition number at the sample where the
  quantity's error is largest (a position error is amplified into accelerations and
  forces by it; it grows without bound towards a limit position);

Measured (MuJoCo Warp 4.0.0 on the CPU, RK4, 2 revolutions, 36 samples of the 2nd,
every judged quantity of the ten built-in cases; ``ratio = error / (u32 * steps *
condition)``): at 2304 steps a revolution, where float32 dominates (MuJoCo float64 on
the same model already has only 4e-7 to 6e-5 at four times that step, and MuJoCo Warp's
error grows from 576 to 2304 steps while the step's own error falls), the ratio of the
worst quantity of each case lies in 0.6-3.0 (inverted-slider-crank 2.7,
offset-slider-crank 3.0, seed-four-bar 2.8, seed-slider-crank 1.9, six-bar 0.8,
quick-return 0.6).  ``STEP_GROWTH = 4`` is that envelope with a third in
hand.  An error above it is not float32 rounding: hibbeler-two-inclines at 576 steps a
revolution (591 steps, 1.1e-3 of peak, ratio 5.4) is a step that is too coarse: MuJoCo
float64 at the same model and step has 1.2e-3 there, and a FAIL is the right verdict.
In the instantaneous mode (one solve at the analytic state, 36 inputs of each case) the
ratio ``error / (u32 * condition)`` of the worst quantity lies in 51-7.6e3
(hibbeler-two-inclines 7.6e3: slideB.a 2.6e-3 of peak at -2.357 m, where MuJoCo float64
on the same model has 6.9e-6; hibbeler-16-121 6.5e3, six-bar 980, seed-four-bar 435);
``SOLVE_GROWTH = 1e4`` is that envelope.  Its cause was not isolated (the 1e8 drive
armature is not it: 1e4 gives the same 2.7e-3); the run floor is calibrated on runs
separately because a run's errors stay far below it (hibbeler-two-inclines 1.6e-4 over
1101 steps at the same condition).
"""

from __future__ import annotations

from dataclasses import dataclass

#: float32's unit round-off (half the spacing of floats at 1): 2**-24.
U32 = 2.0 ** -24

#: The float32 floor's growth per step and per unit of condition, in units of ``u32``
#: (module docstring: the measured envelope 3.0 of the float32-dominated runs, plus a third).
STEP_GROWTH = 4.0

#: One float32 solve's floor per unit of condition, in units of ``u32`` (module docstring:
#: MuJoCo Warp's instantaneous mode, the measured envelope 7.6e3 of the built-in cases).
SOLVE_GROWTH = 1.0e4


@dataclass(frozen=True)
class Arithmetic:
    """The arithmetic an engine's solver computes in.

    ``name`` is what the report prints (``"float64"``, ``"float32"``); ``unit_roundoff``
    the format's ``u``; ``step_growth`` and ``solve_growth`` the floor's constants
    (module docstring); ``claims_floor`` False for an arithmetic whose floor never
    reaches a tolerance (float64: the verdict stays pass or FAIL)."""

    name: str
    unit_roundoff: float
    step_growth: float = STEP_GROWTH
    solve_growth: float = SOLVE_GROWTH
    claims_floor: bool = True

    def floor(self, steps: int, condition: float) -> float:
        """The error floor (normalised by the quantity's peak) of a run of ``steps`` steps
        (0: one solve) at a sample of loop condition number ``condition``; 0.0 when the
        arithmetic claims none or the condition is not finite (a sample at a singular
        position is no place to excuse an error)."""
        if not self.claims_floor or not condition == condition or condition == float("inf"):
            return 0.0
        growth = self.step_growth * int(steps) if steps > 0 else self.solve_growth
        return growth * self.unit_roundoff * float(condition)

    def limit_label(self) -> str:
        """The verdict word of an error within this arithmetic's floor."""
        return f"precision limit ({self.name})"


#: IEEE double precision: no floor claimed.
FLOAT64 = Arithmetic("float64", 2.0 ** -53, claims_floor=False)
#: IEEE single precision (MuJoCo Warp's kernels).
FLOAT32 = Arithmetic("float32", U32)

__all__ = ["FLOAT32", "FLOAT64", "SOLVE_GROWTH", "STEP_GROWTH", "U32",
           "Arithmetic"]
