"""The drive effort at a change point where the joint forces are unbounded (fuzz find).

A nanometre Grashof-boundary four-bar (crank - ground = rocker - coupler) with the crank
at 0 rad, where coupler and rocker fold onto one line: gravity across that line makes
the joint forces unbounded (``c / s``, analytic.singular), but the drive effort has a
finite limit (the self-stress along the folded links does no work on the input).  The
effort curves sharply here (the folded links differ by 0.18 of the ground, so the
branch bends on a scale of ~0.03 rad): at the first force step (1e-2 rad) its one-sided
extrapolations differed by 2e-3 of its scale and it was written NaN, as if unbounded,
with a blank ``drive.torque`` cell in the sweep's CSV.
"""

import tomllib

import numpy as np
import pytest

from analytic import Linkage
from analytic.singular import UNBOUNDED_FORCES
from analytic.toml_io import mechanism_from_dict

FOLDED_FOUR_BAR = """
name = "four-bar"
ground = "ground"
gravity = [3.0, -1000.0]

[units]
length = "m"

[bodies."ground"]
points = { "O2" = [0.0, 0.0], "O4" = [5.071886811118973e-10, 0.0] }

[bodies."crank"]
points = { "P0" = [0.0, 0.0], "P1" = [5.254770748996205e-10, 0.0] }
mass = 6.298139566543806
com = [2.6273853744981026e-10, 0.0]
inertia = 1.4492342250038982e-19

[bodies."coupler"]
points = { "P0" = [0.0, 0.0], "P1" = [7.588716905887666e-10, 0.0] }
mass = 9.122017138155487
com = [3.794358452943833e-10, 0.0]
inertia = 4.377703480200205e-19

[bodies."rocker"]
points = { "P0" = [0.0, 0.0], "P1" = [7.771600843764898e-10, 0.0] }
mass = 1.1892710066800807
com = [3.885800421882449e-10, 0.0]
inertia = 5.98577735292498e-20

[[joints]]
name = "O2"
type = "revolute"
bodies = ["ground", "crank"]
points = ["O2", "P0"]

[[joints]]
name = "A"
type = "revolute"
bodies = ["crank", "coupler"]
points = ["P1", "P0"]

[[joints]]
name = "B"
type = "revolute"
bodies = ["rocker", "coupler"]
points = ["P1", "P1"]

[[joints]]
name = "O4"
type = "revolute"
bodies = ["ground", "rocker"]
points = ["O4", "P0"]

[driver]
joint = "O2"
value = 180.0
velocity = 0.0
acceleration = -0.28

[assembly]
points = { "coupler.P1" = [-2.2745671430752586e-11, -5.684605340243725e-10] }
"""

#: Alpha of the description (rad/s^2); omega is 0.
ALPHA = -0.28
#: Steps (rad) of the independent two-sided limit: regular samples (condition ~3e5, far
#: below the singular threshold), where the even part of the effort leaves the mean of
#: the two sides within c h^2 ~ 2e-7 of its limit (c measured from the 1e-3 side values)
#: and the positions' rounding, amplified by the condition number, ~1e-10.
REF_STEP = 1e-5
#: The two sides differ by the effort's slope times 2 h (3e-6 of it at REF_STEP); a
#: divergent effort (~ c / s) would have opposite signs either side.
SIDES_RTOL = 1e-4
#: The solver extrapolates from +-1e-3 rad (Richardson, O(h^4)): on this sharply bent
#: branch that is ~1e-5 of the effort; the 1e-2 rad step's extrapolation is 8% off and
#: the defect's value NaN, both far outside.
EFFORT_LIMIT_RTOL = 1e-4


@pytest.fixture(scope="module")
def linkage():
    return Linkage(mechanism_from_dict(tomllib.loads(FOLDED_FOUR_BAR)))


def _effort(lk, x):
    kin = lk.kinematics(np.asarray(x, float), 0.0, ALPHA, on_singular="flag")
    return lk.forces(kin)


#: The change point as reached moving the input down from the reference (pi) to 0, and
#: up to 2 pi: the same folded position on the other branch (another effort limit).
CHANGE_POINTS = (0.0, 2.0 * np.pi)


def _two_sided(lk, at: float) -> float:
    """The effort's limit at ``at``: the mean of regular solves at ``at +- REF_STEP``."""
    left, right = _effort(lk, [at - REF_STEP, at + REF_STEP]).effort
    assert abs(left - right) <= SIDES_RTOL * abs(left)  # finite: no c / s divergence
    return 0.5 * (left + right)


@pytest.mark.parametrize("at", CHANGE_POINTS)
def test_effort_at_the_change_point_is_its_limit(linkage, at):
    ref = _two_sided(linkage, at)
    frc = _effort(linkage, [at])
    assert frc.at_singular[0] == UNBOUNDED_FORCES  # the joint forces: unbounded, said
    assert not np.isfinite(frc.joint_force["B"][0]).all()
    assert np.isfinite(frc.effort[0])
    assert frc.effort[0] == pytest.approx(ref, rel=EFFORT_LIMIT_RTOL)
    assert frc.power[0] == 0.0  # omega = 0


def test_sweep_row_writes_the_torque(linkage):
    """The CLI's table (``xval sweep``, 0 to 360 deg): the row at 0 has the torque."""
    frame = linkage.sweep(6, start=0.0).frame
    row = frame.iloc[int(np.argmin(np.abs(frame["input"].to_numpy())))]
    assert row["input"] == 0.0
    assert row["singular"] == UNBOUNDED_FORCES
    assert row["drive.torque"] == pytest.approx(_two_sided(linkage, 0.0),
                                                rel=EFFORT_LIMIT_RTOL)
