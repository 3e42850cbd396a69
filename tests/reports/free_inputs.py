"""The released seed four-bar the ``xval simulate`` tests edit into bad input: the seed
four-bar under gravity with a spring, a damper and a motor table (valid as it is)."""

from __future__ import annotations

from analytic.cases import case_path

MOTION = """
[motion]
joint = "O2"
value = 60.0
rate = 0.0
duration = 1.0

[[springs]]
bodies = ["coupler", "ground"]
points = ["B", "O2"]
stiffness = 30.0
free_length = 250.0

[[dampers]]
joint = "O4"
coefficient = 0.01

[[motors]]
joint = "O2"
table = [[0.0, 0.0], [1.0, 0.3]]
"""


def seed_under_gravity() -> str:
    """The built-in seed four-bar's file with gravity 9.81 m/s^2 down (no [motion])."""
    return case_path("seed-four-bar").read_text().replace("gravity = [0.0, 0.0]",
                                                           "gravity = [0.0, -9.81]")
