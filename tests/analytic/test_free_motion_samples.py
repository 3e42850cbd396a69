"""The free trajectory's samples with forces, all samples of a segment at once (issue 34),
against the solver's kinetostatics one sample at a time with every force element
applied as a load (the implementation before), and against the drive residual (zero
effort at the integrated joint once every element is applied: Lagrange's equation and
the kinetostatics agree).

The reactions are linear in the loads at a given motion; the batched path adds each
element's share by superposition, which changes them by rounding only.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import replace

import numpy as np
import pytest

from analytic import Linkage, load_case
from analytic.free_motion import simulate
from analytic.free_motion.iftomm import n_four_bar_toml
from analytic.toml_io import mechanism_from_dict

#: Batched (superposed) against one sample at a time with the loads in the solver:
#: rounding of the superposition, ~1e-16 of the larger of the reaction and the element's
#: share (fraction of each reaction component's range over the run).
SAME_REL = 1e-12
#: The drive residual (N m or N) against the largest drive effort the elements exert
#: (the kinetostatics and Lagrange's equation agree to rounding).
RESIDUAL_REL = 1e-9


def _slider_with_joint_elements():
    from analytic.motion_spec import FreeMotion, JointDamper, JointSpring, Motor
    m = load_case("seed-slider-crank")
    s0 = float(Linkage(m).kinematics(np.radians([30.0])).slider("slide")[0][0])
    fm = FreeMotion("slide", s0, 0.0, 0.05,
                    springs=(JointSpring("slide", 2000.0, s0 - 0.01),),
                    dampers=(JointDamper("slide", 1.0),),
                    motors=(Motor("slide", 0.0, (0.0, 0.05), (5.0, 2.0)),))
    return replace(m, gravity=(0.0, -9.81), motion=fm)


def _cases():
    from .test_free_motion import _rocker_mech, _seed_released
    return {
        "seed-spring-damper-motor": (lambda: _seed_released(True), 2.0),
        "slider-joint-elements": (_slider_with_joint_elements, 0.05),
        "rocker-switching": (_rocker_mech, 1.0),
        "a02-n8": (lambda: mechanism_from_dict(tomllib.loads(n_four_bar_toml(8)), "A02"),
                   1.0),
    }


def _one_at_a_time(traj, times):
    """Reactions and drive effort from the solver at each sample alone, loads applied."""
    s = traj.at(times, forces=False)
    y, si = traj.state(times)
    N = len(times)
    reactions = {j: np.full((N, 2), np.nan) for j in traj.joints}
    drive = np.full(N, np.nan)
    for n in range(N):
        lk = traj.segments[si[n]].lk
        traj._forces_at(lk, s.x, n, n, float(y[n, 0]), float(y[n, 1]), float(times[n]),
                        reactions, drive)
    return reactions, drive


@pytest.mark.parametrize("name", list(_cases()))
def test_batched_forces_as_one_sample_at_a_time(name):
    make, T = _cases()[name]
    traj = simulate(make(), duration=T)
    times = np.linspace(0.0, T, 41)
    got = traj.at(times)
    reactions, drive = _one_at_a_time(traj, times)
    for j, want in reactions.items():
        rng = np.maximum(np.ptp(want, axis=0), 1e-300)
        assert np.all(np.abs(got.reactions[j] - want) <= SAME_REL * rng), j
    scale = max(float(np.max(np.abs(r))) for r in reactions.values())
    assert np.max(np.abs(got.drive_residual - drive)) <= SAME_REL * scale


def test_batched_forces_drive_residual_with_joint_elements():
    """A prismatic joint's spring, damper and motor as loads on the slider and the guide:
    the kinetostatics then asks no effort at the integrated joint."""
    mech = _slider_with_joint_elements()
    traj = simulate(mech, duration=0.05)
    s = traj.at(np.linspace(0.0, 0.05, 51))
    fm = mech.motion
    elements = (fm.springs[0].stiffness * 0.02 + fm.dampers[0].coefficient
                * float(np.max(np.abs(s.xd))) + max(abs(e) for e in fm.motors[0].efforts))
    assert np.max(np.abs(s.drive_residual)) <= RESIDUAL_REL * elements
    assert math.isfinite(float(np.max(np.abs(s.reactions["slide"]))))
