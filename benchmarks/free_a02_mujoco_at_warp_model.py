"""A02's verdict row for MuJoCo (float64) on MuJoCo Warp's free model and step: what
float32 adds to Warp's row (README, "A02 judged").

    python benchmarks/free_a02_mujoco_at_warp_model.py OUT.json

:func:`free_a02_verdicts.run` for ``mujoco`` with the settings of
:class:`sim_models.engines.mujoco.free.MujocoFreeSettings` set to MuJoCo Warp's recommended free
ones (step, integrator, solref, solimp, iterations, tolerance, inverse-weight scale).
"""

from __future__ import annotations

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import free_a02_verdicts  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    a = ap.parse_args()
    import sim_models.runs.free as fe
    from sim_models.engines.mujoco.free import MujocoFreeSettings
    w = fe.free_settings("mujoco_warp")
    same = MujocoFreeSettings(timestep=w.timestep, integrator=w.integrator, solref=w.solref,
                              solimp=w.solimp, iterations=w.iterations,
                              tolerance=w.tolerance, invweight_scale=w.invweight_scale)
    print(same)
    fe.free_settings = lambda engine: same  # run() looks it up in sim_models.runs.free
    free_a02_verdicts.run("mujoco", a.out, 20.0, 401, 3600.0)


if __name__ == "__main__":
    main()
