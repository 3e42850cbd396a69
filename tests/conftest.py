"""Shared helpers: mechanisms built through the Python API, independent of the TOML cases."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from analytic import Assembly, Body, Driver, Load, Mechanism, Prismatic, Revolute

# no background kernel compiles from the tests' small calls (analytic.kernels.background):
# ten structures compiling at once would load the machine; the tests that want a kernel
# compile it in the foreground (test_dispatch turns this back on where it tests them)
os.environ.setdefault("XVAL_BACKGROUND_COMPILE", "0")


def rod(name, length, mass=None, extra=None):
    """A uniform slender rod from P0 = (0, 0) to P1 = (length, 0)."""
    pts = {"P0": (0.0, 0.0), "P1": (length, 0.0)}
    pts.update(extra or {})
    if mass is None:
        return Body(name, pts)
    return Body(name, pts, mass, (length / 2, 0.0), mass * length ** 2 / 12)


def four_bar(ground, crank, coupler, rocker, theta=math.pi / 3, omega=15.0, alpha=0.0,
             masses=(0.2, 0.6, 0.5), open_branch=True, gravity=(0.0, 0.0)) -> Mechanism:
    """Crank pivot O2 at the origin, rocker pivot O4 at (ground, 0); B above (open) or
    below (crossed) the line from A to O4."""
    m = masses or (None, None, None)
    bodies = (Body("ground", {"O2": (0.0, 0.0), "O4": (ground, 0.0)}),
              rod("crank", crank, m[0]), rod("coupler", coupler, m[1]),
              rod("rocker", rocker, m[2]))
    joints = (Revolute("O2", "ground", "O2", "crank", "P0"),
              Revolute("A", "crank", "P1", "coupler", "P0"),
              Revolute("B", "rocker", "P1", "coupler", "P1"),
              Revolute("O4", "ground", "O4", "rocker", "P0"))
    # hint: B on the chosen side of the line A-O4 at the reference angle
    A = np.array([crank * math.cos(theta), crank * math.sin(theta)])
    d = np.array([ground, 0.0]) - A
    nrm = np.array([-d[1], d[0]]) / np.linalg.norm(d)
    hint = A + d / 2 + (1 if open_branch else -1) * nrm * max(coupler, rocker)
    return Mechanism("four-bar", "ground", bodies, joints, Driver("O2", theta, omega, alpha),
                     gravity=gravity, assembly=Assembly({"coupler.P1": tuple(hint)}))


def slider_crank(crank, rod_len, offset=0.0, theta=math.pi / 6, omega=200.0, alpha=0.0,
                 masses=(0.0, 3.0, 0.6), load=(0.0, 0.0), gravity=(0.0, 0.0)) -> Mechanism:
    """Crank about the origin, slider on the line y = offset along +x, slider to the right."""
    m = masses
    crank_b = (Body("crank", {"P0": (0, 0), "P1": (crank, 0)}, 0.0, (0, 0), 0.0)
               if m and m[0] == 0 else rod("crank", crank, m[0] if m else None))
    bodies = (Body("ground", {"O": (0.0, 0.0), "L": (0.0, offset)}), crank_b,
              rod("rod", rod_len, m[1] if m else None),
              Body("piston", {"C": (0.0, 0.0)},
                   *((m[2], (0.0, 0.0), 1e-4 if m[2] else 0.0) if m else ())))
    joints = (Revolute("A", "ground", "O", "crank", "P0"),
              Revolute("B", "crank", "P1", "rod", "P0"),
              Revolute("C", "rod", "P1", "piston", "C"),
              Prismatic("slide", "ground", "L", 0.0, "piston", "C"))
    loads = (Load("piston", "C", load),) if any(load) else ()
    return Mechanism("slider-crank", "ground", bodies, joints,
                     Driver("A", theta, omega, alpha), loads=loads, gravity=gravity,
                     assembly=Assembly({"piston.C": (crank + rod_len, offset)}))


@pytest.fixture
def make_four_bar():
    return four_bar


@pytest.fixture
def make_slider_crank():
    return slider_crank
