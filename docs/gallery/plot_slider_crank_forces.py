"""
A slider-crank's joint forces over a cycle
==========================================

The course's centred slider-crank (crank 10 cm, rod 20 cm, 200 rad/s) with its rod and
slider masses and a 500 N load on the slider: the joint reactions and the drive torque
over a full turn, and the power balance the solver checks at every angle.
"""

import matplotlib.pyplot as plt
import numpy as np

from analytic import Linkage, load_case

linkage = Linkage(load_case("seed-slider-crank"))
table = linkage.sweep(361).frame
angle = table["input"].to_numpy()  # deg

# %%
# Each joint's force is by the joint's first body on its second, in world axes; its
# magnitude follows.
fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True, layout="constrained")
for joint in ("A", "B", "C", "slide"):
    magnitude = np.hypot(table[f"{joint}.fx"], table[f"{joint}.fy"])
    ax1.plot(angle, magnitude / 1e3, label=joint)
ax1.set(ylabel="|F| (kN)", title="joint forces")
ax1.legend()
ax2.plot(angle, table["drive.torque"])
ax2.set(xlabel="crank angle (deg)", ylabel="drive torque (N m)")
for ax in (ax1, ax2):
    ax.grid(True)
plt.show()

# %%
# The power balance, drive power = dKE/dt - power of gravity and loads, holds at every
# angle to rounding:
peak = np.abs(table["drive.power"]).max()
print(f"largest power-balance residual: {np.abs(table['power_residual']).max() / peak:.1e}"
      " of the peak drive power")
