"""Every numerical tolerance of the solver and its checks, with why it has its size.

Relative errors elsewhere in the project are normalised by the peak magnitude of
the quantity over the cycle (see :func:`reports.comparison.compare.compare`), so zero
crossings do not blow them up.
"""

# --- solver -----------------------------------------------------------------

#: Loop-closure residual accepted from the position solution, relative to the
#: mechanism's size (its longest in-body point distance).  The closed forms are
#: exact to a few ulps (~1e-16 relative); Newton stops below this.  1e-12 leaves
#: four orders of magnitude for the rounding of sums of ~10 loop vectors.
LOOP_RESIDUAL = 1e-12

#: Dyad discriminants (relative: for an RRR dyad h^2 (L1 + L2) / (L1 L2 max(L1, L2)),
#: h the distance of the inner joint from the line of the outer joints; for RRP h^2 / L^2;
#: for RPR 1 - cos^2) inside [-TOGGLE_SNAP, TOGGLE_SNAP] are taken as exactly 0: the dyad
#: is at its toggle.  Rounding leaves a few eps at an exact toggle (so h ~ 1e-8 L would
#: be pure noise); setting h to 0 makes the Jacobian exactly singular there, so a
#: requested dead-centre position is reported as one.  The snap shortens the links'
#: reach by h^2 (1/L1 + 1/L2) / 2 = disc * max(L1, L2) / 2 <= 5e-13 of the mechanism's
#: size: half of LOOP_RESIDUAL, the other half left for rounding.  (The discriminant was
#: h^2 / L1^2, whose snap left a gap of disc * L1^2 / (2 L2): next to a parallelogram's
#: change point, with L1 = 12 L2, 1.3e-12 of the size, and an assembly that exists was
#: refused by the residual check.)  Below -TOGGLE_SNAP the loop cannot close.
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

# --- assembly, branches and continuation -------------------------------------

#: Largest distance between the solved assembly and any assembly hint, as a fraction of
#: the mechanism's size (its longest in-body point distance); an angle hint's distance
#: is its angle error in rad (the arc it sweeps at one size from the pivot).  Hints are
#: approximate by design, often only "which side of the line": the built-in six-bar's
#: hint for link.E sits 0.60 of the size from its assembly, and side hints placed a link
#: length off the line of a dyad's outer joints (tests/conftest.py) sit up to 1.18 sizes
#: from theirs.  A hint farther than 1.5 sizes from every assembly is no hint for any
#: of them (a unit slip, a mirrored drawing, a geometry edited after the hint): the
#: solver raises, naming the hint and the distance, instead of returning an assembly the
#: user did not ask for.
HINT_DISTANCE = 1.5

#: Random Newton starts used to enumerate the assemblies of a mechanism without a dyad
#: plan (a Stephenson triad has up to 6 real assemblies).  Deterministic (seeded).
ASSEMBLY_STARTS = 384

#: Largest Newton step: 0.5 rad for an angle, 0.5 mechanism sizes for a slider, so that a
#: far start moves toward the nearest assembly instead of jumping across the chain.
NEWTON_MAX_STEP = 0.5

#: Limit and singular positions found by continuation are located by bisection to this
#: width: rad for a revolute input, times the mechanism's size (m) for a prismatic one.
#: (Issue 8 asks for 1e-9; the bisection goes to 1e-10 to leave a margin.)
LIMIT_BISECTION = 1e-10

#: A dyad's relative discriminant (h^2 / L^2) whose local minimum over the input lies
#: within this of 0 touches zero there: a change point (two assembly branches meet and
#: cross), not a near miss.  Rounding leaves a few eps at an exact touch, and the
#: minimum is located to ~1e-11 rad, where a true double root's disc is ~1e-22; a
#: near-toggle linkage 1e-4 of its length off the Grashof boundary has a minimum of
#: ~1e-4.  Same size as TOGGLE_SNAP, with which the dyad is snapped to its toggle.
CHANGE_POINT_DISC = 1e-12

#: Continuity of velocity decides the branch after a change point when the best
#: candidate's jump in d(pose)/d(input) is below this fraction of the next best's; the
#: held (kinked) branch jumps by about twice the rocker's speed ratio, the continued one
#: by O(step * curvature) ~ 1e-3 of it (step 1e-4).  Otherwise continuity cannot decide and the
#: ``branch_rule`` option does.
CONTINUITY_RATIO = 0.1

#: Side steps (rad of a revolute input, mechanism sizes of a prismatic one) from which
#: the rates and forces at a singular sample are extrapolated to their limits along the
#: branch (:mod:`analytic.singular`), tried in this order.  Close to a toggle the closed
#: form's inner joint carries a rounding error ~ eps / (step^2 curvature) relative (the
#: discriminant cancels), which the accelerations amplify further: at 1e-4 rad from the
#: parallelogram's change point 4e-5 of omega^2, at 1e-3 ~1e-9; Richardson's truncation
#: at 1e-3 is O(h^4) ~ 1e-12.  1e-2 and 1e-4 are the fallbacks (a strongly curved branch,
#: a neighbouring singular position).
LIMIT_STEP = (1e-3, 1e-2, 1e-4)

#: The one-sided extrapolations of a rate or force to a singular sample must agree to
#: this fraction of its scale (an acceleration's: at least the velocities' squared) for
#: the value to have a limit there.  A smooth branch leaves them 12 h^3 (third
#: derivative) apart: accelerations curve sharply near a change point, 6e-6 of omega^2
#: at h = 1e-3 on a Grashof-boundary four-bar (0.05 / 0.6 / 0.73 / 0.18) found by the
#: fuzz, plus the rounding above; a kink (a held branch, a reference on a change point)
#: or a divergence (a dead centre's rates; an unbounded reaction ~ c / s, which leaves
#: them 3 c / h apart) is O(1).
LIMIT_CONTINUITY = 1e-4

#: The same for the forces at a singular sample: steps of 1e-2 rad (or sizes), then 1e-3.
#: The reactions near a singular position amplify the positions' rounding once more (by
#: the condition number ~1/step): 3e-4 of the reactions at 1e-3 rad from the hard-case
#: parallelogram's flat position, 1e-6 at 1e-2, where Richardson's truncation is
#: ~1e-8.  A bounded reaction's one-sided extrapolations then agree to ~1e-5; an
#: unbounded one's (~ c / s) differ by 3 c / h, so 1e-3 of the force scale flags a
#: divergence that reaches 3e-4 of the finite part at 1e-2 rad.
FORCE_LIMIT_STEP = (1e-2, 1e-3)
FORCE_LIMIT_CONTINUITY = 1e-3
