"""Every numerical tolerance of the solver and its checks, with why it has its size.

Relative errors elsewhere in the project are normalised by the peak magnitude of
the quantity over the cycle (see :func:`reports.compare.compare`), so zero
crossings do not blow them up.
"""

# --- solver -----------------------------------------------------------------

#: Loop-closure residual accepted from the position solution, relative to the
#: mechanism's size (its longest in-body point distance).  The closed forms are
#: exact to a few ulps (~1e-16 relative); Newton stops below this.  1e-12 leaves
#: four orders of magnitude for the rounding of sums of ~10 loop vectors.
LOOP_RESIDUAL = 1e-12

#: Dyad discriminants (h^2 / L^2, the squared distance of the inner joint from the
#: line of the outer joints, relative) inside [-TOGGLE_SNAP, TOGGLE_SNAP] are taken
#: as exactly 0: the dyad is at its toggle.  Rounding leaves |h^2 / L^2| of a few
#: eps at an exact toggle (so h ~ 1e-8 L would be pure noise); setting h^2 to 0
#: moves the inner joint along its link by h^2 / (2 L) <= 5e-13 L, inside
#: LOOP_RESIDUAL, and makes the Jacobian exactly singular there, so a requested
#: dead-centre position is reported as one.  Below -TOGGLE_SNAP the loop cannot close.
TOGGLE_SNAP = 1e-12

#: Newton-Raphson iteration cap.  Quadratic convergence from a continuation
#: predictor needs 3-5 iterations; 50 covers damped starts from rough hints.
NEWTON_MAX_ITER = 50

#: Condition number of the loop Jacobian (in the unknowns) above which a
#: configuration is treated as singular (dead centre / change point) and a
#: single-point solve raises.  In double precision a condition number of 1e10
#: leaves ~6 significant digits in the velocities, the least this tool reports.
SINGULAR_CONDITION = 1e10

#: Power balance of the kinetostatic solution: drive power = dKE/dt - power of
#: gravity and loads.  Both sides are sums of products of exact quantities, so
#: they agree to rounding; 1e-9 of the peak drive power allows for the
#: cancellation of large inertia terms (up to ~1e5 x the net) in fast cases.
POWER_BALANCE = 1e-9

# --- independent checks used by the tests -----------------------------------

#: Central finite differences of positions (velocities) or of analytic
#: velocities (accelerations) in time, step h: the truncation error is
#: O(h^2 * third derivative) ~ 1e-8 relative at h = 1e-4 of a period, and the
#: rounding error O(eps / h) ~ 1e-12.  1e-6 of the peak leaves a margin of
#: 100 for sharply peaked accelerations near toggle positions.
FINITE_DIFFERENCE = 1e-6

#: Agreement with the exact values in REFERENCE.md, which are printed to 5-6
#: significant figures: half a unit in the 6th figure.
REFERENCE_RELATIVE = 5e-6

# --- engine comparisons (MuJoCo, PyBullet against the analytic solution) -----------

#: Engine accelerations, joint forces and drive torque at the recommended settings,
#: relative to each quantity's peak over the cycle.  Both engines reach this on the
#: 200 rad/s slider-crank per ENGINE_NOTES.md (MuJoCo RK4 with a critically damped
#: loop, PyBullet dt 1e-5); 1e-3 is what issue 3 asks of a validation run.
ENGINE_RELATIVE = 1e-3

#: MuJoCo's instantaneous mode (mj_forward at the exact analytic state) on the S4
#: four-bar: only the constraint regularisation separates it from the exact answer;
#: measured 1.5e-5 of peak for alpha4 with solimp 0.9999, so 1e-4 holds with margin.
MUJOCO_INSTANTANEOUS = 1e-4
