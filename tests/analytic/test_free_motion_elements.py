"""Force elements at their extremes (issue 30): ends that coincide, stiffness in range
but beyond what an exact integration can resolve in bounds."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from analytic.free_motion import simulate
from analytic.free_motion.dynamics import CoincidentEndsError
from analytic.free_motion.stiffness import TooStiffError
from analytic.toml_io import load_mechanism

BUGS = Path(__file__).resolve().parents[1] / "data" / "bugs" / "turn4"
#: The same motion with and without an element that exerts no force: two integrations
#: of the same equation, equal to the integration's tolerance (1e-13) over 0.5 s.
SAME_MOTION = 1e-10


def _load(name):
    return load_mechanism(BUGS / name)


def _without(mech, springs=True, dampers=True):
    """``mech`` without the last spring (or damper): the one between coincident points."""
    fm = mech.motion
    return replace(mech, motion=replace(fm, springs=fm.springs[:-1] if springs else fm.springs,
                                        dampers=fm.dampers[:-1] if dampers else fm.dampers))


@pytest.mark.parametrize("name, springs, dampers", [
    ("F2_zero_length_spring_coincident.toml", True, False),
    ("F2b_point_damper_coincident.toml", False, True),
    ("damper_coincident_points.toml", False, True)])
@pytest.mark.slow
def test_element_between_coincident_points_exerts_no_force(name, springs, dampers):
    """A zero-length spring or a damper between two points of the same pin: no force
    (before: "loops cannot close at driver 'O2' = nan deg"), so the motion is the one
    without the element."""
    mech = _load(name)
    T = min(mech.motion.duration, 0.5)
    t = np.linspace(0.0, T, 11)
    a = simulate(mech, duration=T).at(t, forces=False)
    b = simulate(_without(mech, springs, dampers), duration=T).at(t, forces=False)
    assert np.all(np.isfinite(a.x))
    assert np.max(np.abs(a.x - b.x)) <= SAME_MOTION


def test_spring_with_free_length_between_coincident_points_is_one_line():
    with pytest.raises(CoincidentEndsError, match=r"spring crank\.A - coupler\.A: its ends "
                       r"coincide .* free length is 0\.05 m"):
        simulate(_load("spring_coincident_points.toml"))


@pytest.mark.parametrize("name, what", [
    ("spring_1e12_joint_hang.toml", r"spring 0 \(joint 'O4', stiffness 1e\+12 N m/rad\)"),
    ("spring_1e12_points_hang.toml", r"spring 0 \(coupler\.B - ground\.O2, stiffness 1e\+12"),
    ("damper_1e12_joint.toml", r"damper 0 \(joint 'O4', coefficient 1e\+12 N m s/rad\)")])
def test_element_too_stiff_to_resolve_is_refused_at_once(name, what):
    """Before: a hang (springs) or "loops cannot close ... = -inf deg" (damper)."""
    with pytest.raises(TooStiffError, match=what + r".* shorten the duration to"):
        simulate(_load(name))


@pytest.mark.parametrize("name, said", [
    ("F3b_prismatic_dead_centre_moving.toml",
     r"joint 'slide' = 0\.3 m is a singular position .* got 0\.05 m/s"),
    ("F4b_crank_limit_moving.toml",
     r"joint 'O2' = 81\.1074 deg is a singular position .* got 57\.2958 deg/s")])
def test_moving_release_at_a_singular_position_says_value_and_rate_in_units(name, said):
    """A joint at its own limit position or dead centre cannot move (its rate is zero
    there on every motion through it): one line with the value and rate in the file's
    kinds of unit (before: '= 1.41559 ... got 1', radians unlabelled)."""
    from analytic.errors import LinkageError
    with pytest.raises(LinkageError, match=said):
        simulate(_load(name))
