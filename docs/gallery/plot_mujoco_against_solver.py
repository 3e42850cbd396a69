"""
MuJoCo against the analytic solver
==================================

Run the four-bar of the course in MuJoCo at its recommended settings, two crank
revolutions at 15 rad/s, and compare the rocker's angular acceleration and the drive
torque with the exact values at the engine's samples: the same comparison as
``xval compare seed-four-bar --engine mujoco``.
"""

import matplotlib.pyplot as plt
import numpy as np

from analytic import load_case
from reports.comparison.runs import run_verdict

verdict = run_verdict(load_case("seed-four-bar"), "mujoco")
print(verdict.run.settings.describe())
worst = max(verdict.judged(), key=lambda c: c.normalised)
print(f"verdict: {'pass' if verdict.ok else 'fail'}; worst {worst.quantity}: "
      f"{worst.normalised:.1e} of its peak (tolerance {worst.tolerance:g})")

# %%
# The engine's samples against the exact curve of the same linkage.
run = verdict.run
kin = run.linkage.kinematics(run.values)
frc = run.linkage.forces(kin)
rocker = run.body_names.index("rocker")
angle = np.degrees(run.values) % 360
order = np.argsort(angle)
fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True, layout="constrained")
ax1.plot(angle[order], kin.alpha[order, rocker], label="analytic")
ax1.plot(angle, run.alpha[:, rocker], "o", ms=4, label="MuJoCo")
ax1.set(ylabel="rocker alpha (rad/s^2)")
ax1.legend()
ax2.plot(angle[order], frc.effort[order], label="analytic")
ax2.plot(angle, run.drive_effort, "o", ms=4, label="MuJoCo")
ax2.set(xlabel="crank angle (deg)", ylabel="drive torque (N m)")
for ax in (ax1, ax2):
    ax.grid(True)
plt.show()
