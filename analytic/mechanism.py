"""The mechanism description: the single source of truth.

A planar linkage is a set of rigid bodies joined by revolute and prismatic
joints, one of which is driven.  The analytic solver, the MJCF and the URDF
are all generated from a :class:`Mechanism`.

Conventions (used everywhere in this package)
---------------------------------------------
* SI units inside: m, rad, s, kg, N.  Files may use other length units and
  degrees; :mod:`analytic.toml_io` converts at the edge.
* World frame: x to the right, y up, angles counter-clockwise from +x.
  Positive omega and alpha are counter-clockwise.
* Every body has a frame.  Its named points, centre of mass and the lines of
  the prismatic joints it guides are given in that frame.  A body's *angle* is
  the angle of its frame's x axis in the world frame.  The ground body's frame
  is the world frame.
* A revolute joint pins ``point_a`` of ``body_a`` to ``point_b`` of ``body_b``.
  Its reaction force is the force **exerted by body_a on body_b**, in world
  axes (body_b receives the opposite from nothing else: body_a receives
  ``-force``).
* A prismatic joint lets point ``point`` of ``slider`` move along the line
  through point ``origin`` of ``guide`` with direction angle ``direction``
  (guide frame).  The slider's frame keeps the constant angle ``angle``
  relative to the guide's frame.  Its displacement is
  ``s = u . (P_slider - Q_origin)`` with ``u`` the line's world direction.  Its
  reaction is the normal force ``N`` (along ``n = u`` rotated +90 deg) and the
  couple ``M`` exerted by the guide on the slider, the force acting at the
  slider point.
* The driver of a revolute joint sets the angle of ``body_b`` relative to
  ``body_a`` (rad); of a prismatic joint, its displacement ``s`` (m).  The
  drive effort (torque in N m or force in N) is what the driver applies to
  ``body_b`` (revolute) or ``slider`` (prismatic), the reaction acting on the
  other body.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from .errors import DescriptionError

Vec2 = tuple[float, float]


@dataclass(frozen=True)
class Body:
    """A rigid body.

    Parameters
    ----------
    name
        Unique body name.
    points
        Named points in the body frame, m.
    mass
        kg, or ``None`` when the body is massless / mass unknown.  A massless
        body must also have no inertia.
    com
        Centre of mass in the body frame, m.
    inertia
        Moment of inertia about the centre of mass, kg m^2.
    """

    name: str
    points: Mapping[str, Vec2]
    mass: float | None = None
    com: Vec2 = (0.0, 0.0)
    inertia: float | None = None

    def point(self, name: str) -> Vec2:
        try:
            return self.points[name]
        except KeyError:
            raise DescriptionError(
                f"unknown point {name!r}; body has {sorted(self.points)}",
                f"body {self.name!r}") from None


@dataclass(frozen=True)
class Revolute:
    """A pin joining ``point_a`` of ``body_a`` and ``point_b`` of ``body_b``."""

    name: str
    body_a: str
    point_a: str
    body_b: str
    point_b: str

    @property
    def bodies(self) -> tuple[str, str]:
        return (self.body_a, self.body_b)


@dataclass(frozen=True)
class Prismatic:
    """A slider joint: ``slider.point`` moves on a line fixed in ``guide``.

    Parameters
    ----------
    guide, origin, direction
        The line: through point ``origin`` of body ``guide``, direction angle
        ``direction`` (rad) in the guide frame.  The guide may itself move.
    slider, point
        The body that slides and its point that stays on the line.
    angle
        Constant angle of the slider frame relative to the guide frame, rad.
    """

    name: str
    guide: str
    origin: str
    direction: float
    slider: str
    point: str
    angle: float = 0.0

    @property
    def body_a(self) -> str:
        return self.guide

    @property
    def body_b(self) -> str:
        return self.slider

    @property
    def point_a(self) -> str:
        return self.origin

    @property
    def point_b(self) -> str:
        return self.point

    @property
    def bodies(self) -> tuple[str, str]:
        return (self.guide, self.slider)


Joint = Revolute | Prismatic


@dataclass(frozen=True)
class Driver:
    """The input: one joint's coordinate and its first two time derivatives.

    ``value`` is rad (revolute: angle of body_b relative to body_a) or m
    (prismatic displacement); ``velocity`` rad/s or m/s; ``acceleration``
    rad/s^2 or m/s^2.  The default is a constant-speed input.
    """

    joint: str
    value: float
    velocity: float
    acceleration: float = 0.0


@dataclass(frozen=True)
class Load:
    """An external force (N, world axes) at a body point and a couple (N m, ccw)."""

    body: str
    point: str | None = None
    force: Vec2 = (0.0, 0.0)
    torque: float = 0.0


@dataclass(frozen=True)
class Assembly:
    """Hints that pick the assembly mode (branch).

    Parameters
    ----------
    points
        Approximate world positions (m) of some points, keyed ``"body.point"``.
        The solver picks, at the driver's reference value, the branch whose
        points lie nearest these.
    angles
        Approximate body angles (rad), keyed by body name; used the same way
        and as the Newton start where no closed form exists.
    """

    points: Mapping[str, Vec2] = field(default_factory=dict)
    angles: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Mechanism:
    """A planar single-degree-of-freedom linkage with one driver.

    Constructing one validates it; see :func:`validate`.
    """

    name: str
    ground: str
    bodies: tuple[Body, ...]
    joints: tuple[Joint, ...]
    driver: Driver
    loads: tuple[Load, ...] = ()
    gravity: Vec2 = (0.0, 0.0)
    assembly: Assembly = field(default_factory=Assembly)
    loops: tuple[tuple[str, ...], ...] | None = None
    description: str = ""
    source: str | None = None  # file it came from, for error messages

    def __post_init__(self):
        object.__setattr__(self, "bodies", tuple(self.bodies))
        object.__setattr__(self, "joints", tuple(self.joints))
        object.__setattr__(self, "loads", tuple(self.loads))
        validate(self)

    # -- look-ups ---------------------------------------------------------
    def body(self, name: str) -> Body:
        for b in self.bodies:
            if b.name == name:
                return b
        raise DescriptionError(f"unknown body {name!r}; bodies are "
                               f"{[b.name for b in self.bodies]}", self.source)

    def joint(self, name: str) -> Joint:
        for j in self.joints:
            if j.name == name:
                return j
        raise DescriptionError(f"unknown joint {name!r}; joints are "
                               f"{[j.name for j in self.joints]}", self.source)

    @property
    def moving_bodies(self) -> tuple[Body, ...]:
        return tuple(b for b in self.bodies if b.name != self.ground)

    @property
    def driver_joint(self) -> Joint:
        return self.joint(self.driver.joint)

    @property
    def has_mass(self) -> bool:
        """True when every moving body has a mass (possibly zero)."""
        return all(b.mass is not None for b in self.moving_bodies)

    def with_driver(self, value: float | None = None, velocity: float | None = None,
                    acceleration: float | None = None) -> Mechanism:
        """A copy with some of the driver's value/velocity/acceleration replaced (SI)."""
        from dataclasses import replace
        d = self.driver
        return replace(self, driver=Driver(
            d.joint,
            d.value if value is None else float(value),
            d.velocity if velocity is None else float(velocity),
            d.acceleration if acceleration is None else float(acceleration)))


def _where(mech: Mechanism, what: str) -> str:
    return f"{mech.source}: {what}" if mech.source else what


def _finite(x, what: str, where: str) -> None:
    vals = x if isinstance(x, tuple | list) else (x,)
    for v in vals:
        if not isinstance(v, int | float) or isinstance(v, bool) or not math.isfinite(v):
            raise DescriptionError(f"{what} must be a finite number, got {x!r}", where)


def validate(mech: Mechanism) -> None:
    """Check a description for consistency; raise :class:`DescriptionError`.

    Checks names (unique, known bodies and points), joints joining a body to
    itself, zero-length links (two joints of a body at one point), mass
    properties (positive inertia, non-negative mass), the driver, the loads,
    connectivity to ground and the mobility (Gruebler: exactly one degree of
    freedom).
    """
    where = mech.source
    names = [b.name for b in mech.bodies]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise DescriptionError(f"duplicate body names {dup}", where)
    if mech.ground not in names:
        raise DescriptionError(f"ground body {mech.ground!r} is not among the bodies {names}",
                               where)
    bodies = {b.name: b for b in mech.bodies}
    for b in mech.bodies:
        bw = _where(mech, f"body {b.name!r}")
        for pname, p in b.points.items():
            if len(p) != 2:
                raise DescriptionError(f"point {pname!r} must have 2 coordinates, got {p!r}",
                                       bw)
            _finite(tuple(p), f"point {pname!r}", bw)
        if b.name == mech.ground:
            continue
        if b.mass is not None:
            _finite(b.mass, "mass", bw)
            if b.mass < 0:
                raise DescriptionError(f"mass must be >= 0 kg, got {b.mass}", bw)
            if b.inertia is None:
                raise DescriptionError("a body with a mass needs an inertia about its "
                                       "centre of mass (kg m^2)", bw)
            _finite(b.inertia, "inertia", bw)
            if b.inertia < 0 or (b.mass > 0 and b.inertia == 0):
                raise DescriptionError(f"inertia about the centre of mass must be > 0 "
                                       f"kg m^2 for a body with mass, got {b.inertia}", bw)
            if b.mass == 0 and b.inertia != 0:
                raise DescriptionError("a massless body cannot have an inertia", bw)
            _finite(tuple(b.com), "com", bw)
        elif b.inertia is not None:
            raise DescriptionError("inertia given without a mass", bw)

    jnames = [j.name for j in mech.joints]
    if len(set(jnames)) != len(jnames):
        dup = sorted({n for n in jnames if jnames.count(n) > 1})
        raise DescriptionError(f"duplicate joint names {dup}", where)
    for j in mech.joints:
        jw = _where(mech, f"joint {j.name!r}")
        for bn in j.bodies:
            if bn not in bodies:
                raise DescriptionError(f"unknown body {bn!r}; bodies are {names}", jw)
        if j.body_a == j.body_b:
            raise DescriptionError(f"joins body {j.body_a!r} to itself", jw)
        for bn, pn in ((j.body_a, j.point_a), (j.body_b, j.point_b)):
            if pn not in bodies[bn].points:
                raise DescriptionError(f"body {bn!r} has no point {pn!r}; it has "
                                       f"{sorted(bodies[bn].points)}", jw)
        if isinstance(j, Prismatic):
            _finite(j.direction, "direction", jw)
            _finite(j.angle, "angle", jw)

    # Zero-length links: two joints of one body at the same point.
    for b in mech.bodies:
        if b.name == mech.ground:
            continue
        attach = [(j.name, j.point_a if j.body_a == b.name else j.point_b)
                  for j in mech.joints if b.name in j.bodies and isinstance(j, Revolute)]
        for i in range(len(attach)):
            for k in range(i + 1, len(attach)):
                p = b.points[attach[i][1]]
                q = b.points[attach[k][1]]
                if math.hypot(p[0] - q[0], p[1] - q[1]) < 1e-12:
                    raise DescriptionError(
                        f"joints {attach[i][0]!r} and {attach[k][0]!r} are at the same point "
                        f"(zero link length)", _where(mech, f"body {b.name!r}"))

    d = mech.driver
    dw = _where(mech, "driver")
    if d.joint not in jnames:
        raise DescriptionError(f"driver joint {d.joint!r} is not a joint; joints are {jnames}",
                               dw)
    for k in ("value", "velocity", "acceleration"):
        _finite(getattr(d, k), k, dw)

    for i, ld in enumerate(mech.loads):
        lw = _where(mech, f"load {i} on body {ld.body!r}")
        if ld.body not in bodies:
            raise DescriptionError(f"unknown body {ld.body!r}", lw)
        if ld.point is not None and ld.point not in bodies[ld.body].points:
            raise DescriptionError(f"body {ld.body!r} has no point {ld.point!r}", lw)
        _finite(tuple(ld.force), "force", lw)
        _finite(ld.torque, "torque", lw)
    _finite(tuple(mech.gravity), "gravity", _where(mech, "gravity"))

    for key in mech.assembly.points:
        bn, _, pn = key.partition(".")
        if bn not in bodies or pn not in bodies[bn].points:
            raise DescriptionError(f"assembly hint names unknown point {key!r} "
                                   "(expected 'body.point')", _where(mech, "assembly"))
    for bn in mech.assembly.angles:
        if bn not in bodies:
            raise DescriptionError(f"assembly hint names unknown body {bn!r}",
                                   _where(mech, "assembly"))

    # Connectivity: every body reachable from ground.
    adj: dict[str, set[str]] = {n: set() for n in names}
    for j in mech.joints:
        adj[j.body_a].add(j.body_b)
        adj[j.body_b].add(j.body_a)
    seen, stack = {mech.ground}, [mech.ground]
    while stack:
        for nb in adj[stack.pop()]:
            if nb not in seen:
                seen.add(nb)
                stack.append(nb)
    if len(seen) != len(names):
        raise DescriptionError(f"bodies {sorted(set(names) - seen)} are not connected to "
                               f"ground {mech.ground!r}", where)

    # Mobility (Gruebler-Kutzbach, planar, 1-dof joints).
    dof = 3 * (len(names) - 1) - 2 * len(mech.joints)
    if dof != 1:
        raise DescriptionError(
            f"the linkage has {dof} degrees of freedom by Gruebler's count "
            f"(3*(bodies-1) - 2*joints = 3*{len(names) - 1} - 2*{len(mech.joints)}); "
            "exactly 1 is needed for one driver", where)
