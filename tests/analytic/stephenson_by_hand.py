"""The Stephenson chain of the reproducers, solved by hand with numpy (no solver code).

The file is read with ``tomllib``; every body has a pose ``(x, y, theta)``.  The crank
turns about G2 at the input angle, T1 about G1, T2 hangs on the crank at H; b1 and b2
are free.  The unknowns are ``u = (theta_T1, theta_T2, x_b1, y_b1, theta_b1, x_b2,
y_b2, theta_b2)`` and the equations the coincidence of E1, F1, E2, F2 on their two
bodies (8 scalar equations).  Newton with a finite-difference Jacobian solves them.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np


def rot(t):
    return np.array([[math.cos(t), -math.sin(t)], [math.sin(t), math.cos(t)]])


class Stephenson:
    def __init__(self, path: Path):
        d = tomllib.loads(Path(path).read_text())
        self.d = d
        self.p = {b: {k: np.array(v, float) for k, v in d["bodies"][b]["points"].items()}
                  for b in d["bodies"]}
        self.size = max(np.linalg.norm(a - b) for pts in self.p.values()
                        for a in pts.values() for b in pts.values())

    def poses(self, x, u):
        """World poses {body: (origin, theta)} for input angle x (rad) and unknowns u."""
        p = self.p
        out = {"ground": (np.zeros(2), 0.0)}
        out["crank"] = (p["ground"]["G2"] - rot(x) @ p["crank"]["G2"], x)
        out["T1"] = (p["ground"]["G1"] - rot(u[0]) @ p["T1"]["G1"], u[0])
        H = out["crank"][0] + rot(x) @ p["crank"]["H"]
        out["T2"] = (H - rot(u[1]) @ p["T2"]["H"], u[1])
        out["b1"] = (np.array(u[2:4]), u[4])
        out["b2"] = (np.array(u[5:7]), u[7])
        return out

    def world(self, poses, body, point):
        o, t = poses[body]
        return o + rot(t) @ self.p[body][point]

    def residual(self, x, u):
        P = self.poses(x, u)
        w = self.world
        return np.concatenate([w(P, "T1", "E1") - w(P, "b1", "E1"),
                               w(P, "b1", "F1") - w(P, "T2", "F1"),
                               w(P, "T1", "E2") - w(P, "b2", "E2"),
                               w(P, "T2", "F2") - w(P, "b2", "F2")])

    def jacobian(self, x, u, h=1e-7):
        r0 = self.residual(x, u)
        J = np.empty((8, 8))
        for i in range(8):
            du = np.zeros(8)
            du[i] = h
            J[:, i] = (self.residual(x, u + du) - r0) / h
        return J

    def solve(self, x, u0, iters=60):
        u = np.array(u0, float)
        for _ in range(iters):
            r = self.residual(x, u)
            if np.max(np.abs(r)) < 1e-14 * self.size:
                return u
            u = u - np.linalg.lstsq(self.jacobian(x, u), r, rcond=None)[0]
        if np.max(np.abs(self.residual(x, u))) < 1e-11 * self.size:
            return u
        raise ArithmeticError("no convergence")

    def from_points(self, hints: dict[str, tuple[float, float]]) -> np.ndarray:
        """Unknowns from exact positions of T1.E1, T1.E2, T2.F1, T2.F2 (the hints):
        each body's angle from the direction between two of its points."""
        p = self.p

        def angle(world_a, world_b, body_a, body_b):
            dw, db = world_b - world_a, body_b - body_a
            return math.atan2(dw[1], dw[0]) - math.atan2(db[1], db[0])

        E1, E2 = np.array(hints["T1.E1"]), np.array(hints["T1.E2"])
        F1, F2 = np.array(hints["T2.F1"]), np.array(hints["T2.F2"])
        tT1 = angle(E1, E2, p["T1"]["E1"], p["T1"]["E2"])
        tT2 = angle(F1, F2, p["T2"]["F1"], p["T2"]["F2"])
        tb1 = angle(E1, F1, p["b1"]["E1"], p["b1"]["F1"])
        tb2 = angle(E2, F2, p["b2"]["E2"], p["b2"]["F2"])
        ob1 = E1 - rot(tb1) @ p["b1"]["E1"]
        ob2 = E2 - rot(tb2) @ p["b2"]["E2"]
        return np.array([tT1, tT2, *ob1, tb1, *ob2, tb2])

    # --- dynamics by energy ------------------------------------------------------
    def com_and_angle(self, x, u):
        out = {}
        for b, spec in self.d["bodies"].items():
            if b == "ground":
                continue
            P = self.poses(x, u)
            o, t = P[b]
            out[b] = (o + rot(t) @ np.array(spec["com"], float), t)
        return out

    def drive_torque(self, x, omega, u0, dt=2e-5):
        """Drive torque at input x, constant input speed omega, by the power balance:
        T omega = dKE/dt - P_gravity - P_loads, with every rate a central finite
        difference in time of hand-solved positions (O(dt^2))."""
        d = self.d
        g = np.array(d.get("gravity", [0.0, 0.0]), float)
        us, u = {}, np.array(u0, float)
        for k in (0, 1, 2):  # continue outward from x, each from its neighbour
            u = self.solve(x + k * omega * dt, u)
            us[k] = u
        u = us[0]
        for k in (-1, -2):
            u = self.solve(x + k * omega * dt, u)
            us[k] = u
        st = {k: self.com_and_angle(x + k * omega * dt, us[k]) for k in us}

        def ke(k):
            e = 0.0
            for b, spec in d["bodies"].items():
                if b == "ground":
                    continue
                v = (st[k + 1][b][0] - st[k - 1][b][0]) / (2 * dt)
                w = (st[k + 1][b][1] - st[k - 1][b][1]) / (2 * dt)
                e += 0.5 * spec["mass"] * v @ v + 0.5 * spec["inertia"] * w * w
            return e

        dke = (ke(1) - ke(-1)) / (2 * dt)
        p_grav = 0.0
        for b, spec in d["bodies"].items():
            if b == "ground":
                continue
            v = (st[1][b][0] - st[-1][b][0]) / (2 * dt)
            p_grav += spec["mass"] * g @ v
        p_load = 0.0
        for ld in d.get("loads", []):
            b = ld["body"]
            pa = self.world(self.poses(x + omega * dt, us[1]), b, ld["point"])
            pb = self.world(self.poses(x - omega * dt, us[-1]), b, ld["point"])
            w = (st[1][b][1] - st[-1][b][1]) / (2 * dt)
            p_load += np.array(ld["force"], float) @ ((pa - pb) / (2 * dt)) \
                + ld.get("torque", 0.0) * w
        return (dke - p_grav - p_load) / omega
