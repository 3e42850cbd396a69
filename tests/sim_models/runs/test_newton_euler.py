"""The Newton-Euler reconstruction PyBullet's pin forces rely on, fed exact motion.

Given the analytic motion and the analytic forces at the engine tree's loop-closing
joints, it must return the analytic reactions at every other joint and the analytic
drive effort: the engine tree closes its loops elsewhere than the analytic one, so
this checks the reconstruction independently of the solver's own reduction.
"""

from __future__ import annotations

import numpy as np
import pytest

from analytic import Linkage, Prismatic, case_names, load_case
from analytic.positions import size_of
from analytic.sweep import input_values
from sim_models.builders.tree import SimTree
from sim_models.runs.newton_euler import reconstruct


@pytest.mark.parametrize("case", [c for c in case_names() if load_case(c).has_mass])
def test_reconstruction_of_exact_motion(case):
    mech = load_case(case)
    lk = Linkage(mech)
    kin = lk.kinematics(input_values(lk, 24)[0])
    frc = lk.forces(kin)
    st = SimTree(mech)
    chord_force = np.stack([frc.joint_force[ch.name] for ch in st.chords], axis=1)
    F, normal, moment, effort = reconstruct(st, kin.theta, kin.omega, kin.alpha, kin.origin,
                                            kin.a_origin, chord_force)
    # rounding of sums of inertia forces: 1e-9 of the peak joint force (N), and of
    # peak force x mechanism size for couples (N m)
    peak = max(np.max(np.linalg.norm(v, axis=1)) for v in frc.joint_force.values())
    couple = peak * size_of(lk.topo)
    for name, val in F.items():
        if isinstance(mech.joint(name), Prismatic):
            # compared by parts: the reconstructed force of a driven slider also holds
            # the drive's axial force, which the analytic joint force leaves out
            np.testing.assert_allclose(normal[name], frc.normal[name], atol=1e-9 * peak,
                                       err_msg=name)
            np.testing.assert_allclose(moment[name], frc.moment[name], atol=1e-9 * couple,
                                       err_msg=name)
        else:
            np.testing.assert_allclose(val, frc.joint_force[name], atol=1e-9 * peak,
                                       err_msg=name)
    np.testing.assert_allclose(effort, frc.effort, rtol=1e-9,
                               atol=1e-9 * np.max(np.abs(frc.effort)))
