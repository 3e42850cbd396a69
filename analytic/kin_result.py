"""The solver's kinematic result: :class:`Kinematics` (every array) and
:class:`CompactKinematics` (the fused kernel's compact pass, the rest deferred).

A lower module than :mod:`analytic.kinematics` (the solver, which makes them) and
:mod:`analytic.fused` (the kernel, which makes them too), so that neither imports the
other for them.  Frames and signs: world axes, x right, y up; angles, omega, alpha
counter-clockwise positive (see :mod:`analytic.mechanism`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .linalg import condition
from .planar import as_xy, cplx


@dataclass
class FusedTag:
    """What a result of the fused kernel (:mod:`analytic.fused`) carries for the calls
    that follow it: ``Linkage.forces(kin)`` runs (or reads) the same kernel's forces
    pass, and a compact result computes its deferred arrays by it.

    Attributes
    ----------
    kernel : analytic.fused.FusedKernel
        The kernel that made the result.
    branch : str
        The branch argument of its pass (``"continued"`` or ``"held"``).
    singular : bool
        A sample lies near a singular position (the condition-number screen's bound
        reached): the numpy path treats the call.
    forces : analytic.kinetostatics.Forces or None
        The forces the same pass wrote, when it wrote them.
    forces_guess : object or None
        The mark of a pass that wrote the forces unasked
        (``analytic.kinematics.Linkage._forces_guess``), ``used`` once they are read.
    """

    kernel: object
    branch: str = "continued"
    singular: bool = False
    forces: object | None = None
    forces_guess: object | None = None


@dataclass
class Kinematics:
    """Positions, velocities and accelerations for N input values (SI, world frame).

    Attributes
    ----------
    value, velocity, acceleration : (N,)
        The driver's coordinate (rad or m) and its rates.
    q, qd, qdd : (N, nq)
        Vector-loop unknowns (moving group angles, then slider displacements).
    theta, omega, alpha : (N, B)
        Body angles (rad), angular velocities (rad/s), accelerations (rad/s^2).
    origin, v_origin, a_origin : (N, B, 2)
        Body frame origins and their velocity and acceleration.
    condition : (N,)
        Condition number of the loop Jacobian in the unknowns (inf: singular).
    determinant : (N,)
        Its determinant, normalised by the product of its column norms (in
        [-1, 1]; a sign change marks passing a dead-centre or change point).
    transmission : dict joint name -> (N,) deg
        Transmission angle at the inner joint of each dyad (0..180 deg; 90 is ideal).
    """

    linkage: object  # the analytic.kinematics.Linkage solved
    value: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    E: np.ndarray       # exp(i theta), complex (N, B)
    zO: np.ndarray      # origins, complex (N, B)
    zv: np.ndarray      # their velocities
    za: np.ndarray      # their accelerations
    jacobian: np.ndarray        # (N, n, n) loop Jacobian in the unknowns
    determinant: np.ndarray
    transmission_vectors: list = field(default_factory=list)
    joint_point: dict[int, np.ndarray] = field(default_factory=dict)
    # joint index -> world position (complex) of its point on body_b (the slider point
    # for a prismatic joint)
    #: per sample, where the loop Jacobian is singular: 0 regular, 1 the rates are
    #: their limits along the branch (passed through), 3 not determined (NaN); see
    #: :mod:`analytic.singular`.  ``None``: no singular sample was processed.
    at_singular: np.ndarray | None = None
    #: the fused kernel's tag on a result it made (:class:`FusedTag`); ``None`` on the
    #: numpy path
    fused: FusedTag | None = field(default=None, repr=False, compare=False)
    #: the branch argument the rates at singular samples were continued on
    #: (:func:`analytic.singular.rate_limits`; its forces follow the same branch)
    singular_branch: str = field(default="continued", repr=False, compare=False)
    #: what the sweep's analyses compute once from these kinematics (by name: the
    #: limit positions and least transmission angles of :mod:`analytic.refine`)
    memo: dict = field(default_factory=dict, repr=False, compare=False)

    @cached_property
    def condition(self) -> np.ndarray:
        """2-norm condition number of the loop Jacobian in the unknowns, with each
        slider's displacement measured in mechanism sizes (so that the number, and the
        singular test against it, is the same in any length unit and at any scale);
        computed on first use: it is a diagnostic, not on the solver's path."""
        A = self.jacobian
        return condition(A * self.linkage.column_scale) if A.shape[-1] else np.ones(self.n)

    @cached_property
    def transmission(self) -> dict[str, np.ndarray]:
        """Transmission angle (deg, 0..180) at each dyad's inner joint."""
        tr = {}
        for name, e1, e2 in self.transmission_vectors:
            c = (e1.conjugate() * e2).real / (np.abs(e1) * np.abs(e2))
            tr[name] = np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))
        return tr

    @property
    def origin(self) -> np.ndarray:
        return as_xy(self.zO)

    @property
    def v_origin(self) -> np.ndarray:
        return as_xy(self.zv)

    @property
    def a_origin(self) -> np.ndarray:
        return as_xy(self.za)

    @property
    def n(self) -> int:
        return len(self.value)

    def point(self, body: str, point: str | tuple[float, float]):
        """Position, velocity and acceleration ``(N, 2)`` each of a body point.

        ``point`` is a point name or body-frame coordinates in m.
        """
        return tuple(as_xy(z) for z in self.point_c(body, point))

    def point_c(self, body: str | int, point):
        """As :meth:`point`, as complex ``(N,)`` arrays (x + iy)."""
        topo = self.linkage.topo
        if isinstance(body, str):
            b = self.linkage.body_index(body)
        else:
            b, body = body, topo.body_names[body]
        if isinstance(point, str):
            self.linkage.mech.body(body).point(point)  # typed error for an unknown name
            c = cplx(topo.body_points[b][point])
        else:
            c = cplx(point)
        r = self.E[:, b] * c
        w = self.omega[:, b]
        return (self.zO[:, b] + r, self.zv[:, b] + 1j * w * r,
                self.za[:, b] + (1j * self.alpha[:, b] - w * w) * r)

    def series(self, pick) -> np.ndarray:
        """``pick(self)``: a per-sample quantity computed from these kinematics."""
        return np.asarray(pick(self))

    def slider(self, joint: str):
        """Displacement s (m), velocity s' and acceleration s'' ``(N,)`` of a prismatic joint."""
        topo = self.linkage.topo
        k = topo.joint_names.index(joint)
        if k not in topo.slider_index:
            raise KeyError(f"joint {joint!r} is not prismatic")
        i = topo.n_groups + topo.slider_index[k]
        return self.q[:, i], self.qd[:, i], self.qdd[:, i]

    def com(self, b: int):
        """Centre-of-mass position, velocity, acceleration ``(N, 2)`` of body index ``b``."""
        return tuple(as_xy(z) for z in self.com_c(b))

    def com_c(self, b: int):
        """As :meth:`com`, complex ``(N,)``."""
        return self.point_c(b, self.linkage.mech.bodies[b].com)


#: the :class:`Kinematics` arrays a :class:`CompactKinematics` computes on first use
DEFERRED = ("theta", "omega", "alpha", "E", "zO", "zv", "za", "jacobian", "determinant",
            "transmission_vectors", "joint_point")


class CompactKinematics(Kinematics):
    """:class:`Kinematics` from the fused kernel's compact pass: the inputs and ``q, q',
    q''`` (8 bytes per unknown and configuration, 72 for a four-bar).  The other arrays
    (:data:`DEFERRED`: angles, poses, origin rates, Jacobian, transmission vectors,
    joint points; ~490 bytes per four-bar configuration) come from one more pass of the
    kernel at the same inputs on first use, the same numbers bit for bit.  A caller
    that needs only ``q, q', q''``, a slider's motion or the forces never holds them."""

    def __init__(self, kernel, linkage, value, velocity, acceleration, q, qd, qdd, branch,
                 forces=None):
        """``velocity, acceleration``: ``(1,)`` for a constant rate (the ``(N,)`` view
        is made when first read: a broadcast view costs more than a small call) or
        ``(N,)``; ``forces``: those the same pass wrote (:attr:`FusedTag.forces`)."""
        # not Kinematics.__init__: the deferred fields stay unset until asked for
        self.__dict__.update(linkage=linkage, value=value, _rates=(velocity, acceleration),
                             q=q, qd=qd, qdd=qdd, at_singular=None, memo={},
                             fused=FusedTag(kernel, branch, forces=forces))

    def __getattr__(self, name):  # only for attributes not set: the deferred ones
        if name in ("velocity", "acceleration"):
            d = self.__dict__
            r = d["_rates"][name == "acceleration"]
            d[name] = np.broadcast_to(r, (len(d["value"]),)) if len(r) == 1 else r
            return d[name]
        if name in DEFERRED:
            d = self.__dict__
            d.update(d["fused"].kernel.deferred(self))
            return d[name]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
