"""The IFToMM multibody benchmark problems as descriptions (the shipped case files).

A02, the N four-bar mechanism, has N as a parameter: :func:`n_four_bar_toml` writes its
description for any N; ``analytic/cases/free/iftomm-a02-n-four-bar.toml`` is its text for the
published N = 40 (a test checks they agree).  Source of the definition: IFToMM
benchmark library (Gonzalez, Dopico, Lugris, Cuadrado, "A benchmarking system for MBS
simulation software", Multibody System Dynamics 16, 2006;
lim.ii.udc.es/mbsbenchmark/dist/A02/A02_specification.xml): 2N+1 links of 1 m with a
uniformly distributed mass of 1 kg, gravity 9.81 m/s^2 in -y, initially the vertical
links upright and the x-velocity of B0 (the tip of the first vertical link) 1 m/s,
20 s.
"""

from __future__ import annotations

#: The published number of four-bar windows.
A02_N = 40
#: Most windows :func:`n_four_bar_toml` writes (2N+1 bodies; 2001 bodies is far beyond
#: the published 81 and still assembles in seconds).
MAX_N = 1000


def n_four_bar_toml(n: int = A02_N) -> str:
    """The TOML description of the N four-bar mechanism (N >= 1 windows)."""
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_N:
        raise ValueError(f"N must be an integer from 1 to {MAX_N}, got {n!r}")
    rod = 'points = { O = [0.0, 0.0], B = [1.0, 0.0] }\nmass = 1.0\ncom = [0.5, 0.0]\n' \
          'inertia = 0.08333333333333333   # 1 kg x (1 m)^2 / 12, uniform rod\n'
    bar = 'points = { L = [0.0, 0.0], R = [1.0, 0.0] }\nmass = 1.0\ncom = [0.5, 0.0]\n' \
          'inertia = 0.08333333333333333\n'
    out = ['name = "iftomm-a02-n-four-bar"',
           'description = """IFToMM multibody benchmark A02, the N four-bar mechanism, '
           f'N = {n}: 2N+1 = {2 * n + 1}',
           'links of 1 m and 1 kg (uniform rods), ground pins 1 m apart, released upright '
           'with B0 (tip of crank0)',
           'moving at 1 m/s in +x, under gravity, 20 s. Every horizontal pass is a change '
           'point (N+1 degrees of',
           'freedom there); the physical branch keeps the parallelogram windows. Source: '
           'Gonzalez et al. 2006,',
           'lim.ii.udc.es/mbsbenchmark/dist/A02/A02_specification.xml. Written by',
           f'analytic.free_motion.iftomm.n_four_bar_toml({n})."""',
           'ground = "ground"', "gravity = [0.0, -9.81]", "", "[units]", 'length = "m"', "",
           "[bodies.ground]",
           "points = { " + ", ".join(f"O{i} = [{float(i)}, 0.0]" for i in range(n + 1)) + " }"]
    for i in range(n + 1):
        out += ["", f"[bodies.crank{i}]", rod.rstrip("\n")]
    for i in range(1, n + 1):
        out += ["", f"[bodies.coupler{i}]", bar.rstrip("\n")]
    for i in range(n + 1):
        out += ["", "[[joints]]", f'name = "G{i}"', 'type = "revolute"',
                f'bodies = ["ground", "crank{i}"]', f'points = ["O{i}", "O"]']
    for i in range(1, n + 1):
        out += ["", "[[joints]]", f'name = "L{i}"', 'type = "revolute"',
                f'bodies = ["crank{i - 1}", "coupler{i}"]', 'points = ["B", "L"]',
                "", "[[joints]]", f'name = "R{i}"', 'type = "revolute"',
                f'bodies = ["crank{i}", "coupler{i}"]', 'points = ["B", "R"]']
    out += ["", "[driver]   # for prescribed runs; free motion reads [motion]", 'joint = "G0"',
            "value = 90.0", "velocity = -1.0", "",
            "[motion]", 'joint = "G0"', "value = 90.0     # deg: upright",
            "rate = -1.0      # rad/s: B0 moves at +1 m/s in x", "duration = 20.0",
            "samples = 401    # the published 400 output steps", "",
            "[assembly]   # the parallelogram windows (every crank upright)",
            "angles = { " + ", ".join([f"crank{i} = 90.0" for i in range(n + 1)]
                                      + [f"coupler{i} = 0.0" for i in range(1, n + 1)]) + " }"]
    return "\n".join(out) + "\n"
