"""
A four-bar's coupler curve and drive torque
===========================================

Solve a crank-rocker four-bar over a full turn of its crank, and draw the path of a
point on its coupler and the torque the crank needs. The four-bar is the course's
worked example (`seed-four-bar`) with a coupler point ``P`` added, given as a
description in the TOML format.
"""

import tomllib

import matplotlib.pyplot as plt

from analytic import Linkage
from analytic.cases import case_path
from analytic.toml_io import mechanism_from_dict

# %%
# The built-in four-bar, with a point P on the coupler, 150 mm along it and 80 mm to
# its left (coordinates in the coupler's own frame, mm as the file's units say).
doc = tomllib.loads(case_path("seed-four-bar").read_text())
doc["bodies"]["coupler"]["points"]["P"] = [150, 80]
linkage = Linkage(mechanism_from_dict(doc, "seed-four-bar with P"))

# %%
# One call solves the whole cycle (kinematics and forces) at 361 crank angles, from
# the description's 60 deg; the table has a column per quantity, in SI (the input in
# degrees).
sweep = linkage.sweep(361)
table = sweep.frame
print(sweep.grashof)
print(table[["input", "coupler.P.x", "coupler.P.y", "drive.torque"]].head())

# %%
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
ax1.plot(table["coupler.P.x"] * 1e3, table["coupler.P.y"] * 1e3, label="P")
ax1.plot(table["rocker.B.x"] * 1e3, table["rocker.B.y"] * 1e3, label="B (on the rocker)")
ax1.plot([0, 400], [0, 0], "ks")
ax1.set(xlabel="x (mm)", ylabel="y (mm)", aspect="equal", title="coupler curve")
ax1.legend()
ax2.plot(table["input"], table["drive.torque"])  # the input column is in degrees
ax2.set(xlabel="crank angle (deg)", ylabel="drive torque (N m)",
        title="torque at 15 rad/s, no gravity")
ax2.grid(True)
plt.show()
