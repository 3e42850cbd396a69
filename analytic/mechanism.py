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
import unicodedata
from collections.abc import Mapping
from dataclasses import dataclass, field

from .errors import DescriptionError
from .motion_spec import FreeMotion, check_motion

Vec2 = tuple[float, float]

# --- accepted ranges (SI) ------------------------------------------------------
# Every number of a description, and every input value given on the command line,
# must lie in these ranges.  They are far beyond any physical linkage, and narrow
# enough that no product the solver forms (m L^2 omega^3, amplified by a Jacobian
# condition up to 1e10) comes near the overflow of a double (1e308).

#: Largest |coordinate| (points, centres of mass, hints, a slider's value), m.
#: The largest planar linkages (draglines, bridge spans) are ~1e2 m.
MAX_LENGTH = 1e4
#: Smallest mechanism size (the longest distance between two points of one
#: body), m: a picometre, below atomic scale.  Squared lengths (1e-24 m^2) stay
#: far from the underflow of a double.
MIN_SIZE = 1e-12
#: A link shorter than this fraction of the mechanism's size is a zero-length
#: link: 1000 times the loop residual accepted from the solver
#: (:data:`analytic.tolerances.LOOP_RESIDUAL`, 1e-12 of the size), so the
#: solved length of any accepted link is good to 1e-3 of itself.
ZERO_LENGTH = 1e-9
#: Largest mass, kg (a million tonnes).
MAX_MASS = 1e9
#: Largest moment of inertia, kg m^2 (10 x MAX_MASS x MAX_LENGTH^2 / 12 and more).
MAX_INERTIA = 1e18
#: Largest |angle| (driver value, slider line direction and angle, angle hints),
#: rad: 1000 turns.  Beyond it the spacing of doubles exceeds 1e-12 rad.
MAX_ANGLE = 2000 * math.pi
#: Largest |input velocity|, rad/s or m/s: ten million rpm, 30 times the fastest
#: rotors built.
MAX_RATE = 1e6
#: Largest |input acceleration|, rad/s^2 or m/s^2.
MAX_ACCEL = 1e12
#: Largest |load force| (N) and |load torque| (N m).
MAX_LOAD = 1e12
#: Largest |gravity| component, m/s^2 (1000 g).
MAX_GRAVITY = 1e4


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
    #: how the linkage moves when released (``xval simulate``); None: prescribed only
    motion: FreeMotion | None = None

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


#: Relative slack of a range's upper bound: a value typed in a display unit (deg) that
#: equals the printed bound converts to SI within a few ulps of it (4 x 2.2e-16).
RANGE_ROUND_OFF = 8.9e-16


def check_range(x, limit: float, what: str, where: str | None, unit: str = "",
                scale: float = 1.0, lo: float | None = None) -> None:
    """Raise :class:`DescriptionError` unless every value of ``x`` is finite and in range.

    ``limit`` (and ``lo``) are SI; ``scale`` is the size of one displayed ``unit`` in
    SI, so the message states the value and the accepted range in the user's units.
    Without ``lo`` the range is ``|x| <= limit``; with it, ``lo <= x <= limit``.
    """
    _finite(x, what, where)
    u = f" {unit}" if unit else ""
    # the bound as printed is accepted: 360000 deg converts to 1 ulp above 2000 pi rad
    top = limit * (1 + RANGE_ROUND_OFF)
    for v in (x if isinstance(x, tuple | list) else (x,)):
        if (abs(v) <= top) if lo is None else (lo <= v <= top):
            continue
        rng = (f"|{what}| <= {limit / scale:g}{u}" if lo is None
               else f"{lo / scale:g} to {limit / scale:g}{u}")
        raise DescriptionError(f"{what} = {v / scale:g}{u} is out of range: the accepted "
                               f"range is {rng}", where)


def mechanism_size(bodies) -> float:
    """The longest distance between two points of one body, m (0 when none)."""
    s = 0.0
    for b in bodies:
        pts = list(b.points.values())
        for i, p in enumerate(pts):
            for q in pts[i + 1:]:
                s = max(s, math.hypot(p[0] - q[0], p[1] - q[1]))
    return s


def validate(mech: Mechanism) -> None:
    """Check a description for consistency; raise :class:`DescriptionError`.

    Checks names (unique, known bodies and points), joints joining a body to
    itself, every number (finite and in the accepted ranges above), zero-length
    links (two joints of a body closer than ZERO_LENGTH of the mechanism's size),
    mass properties (positive inertia, non-negative mass), the driver, the loads,
    the hints, connectivity to ground, the mobility (Gruebler: exactly one degree
    of freedom) and a user's loops (closed cycles of distinct bodies).
    """
    _check_names(mech)
    bodies = _check_bodies(mech)
    _check_joints(mech, bodies)
    _check_size(mech)
    _check_driver(mech)
    _check_loads_and_hints(mech, bodies)
    _check_graph(mech)
    if mech.loops is not None:
        _check_loops(mech)
    if mech.motion is not None:
        check_motion(mech)


def _bad_char(text: str, allow: str = "") -> str | None:
    """The first character of ``text`` that no file may carry: a control character
    (Unicode category Cc: U+0000-U+001F, U+007F-U+009F) other than those in ``allow``,
    a lone surrogate, or U+FFFE/U+FFFF, none of which XML 1.0 (the MJCF, URDF and JUnit
    files) can hold and which make terminal output and file names lie."""
    for ch in text:
        if ch in allow:
            continue
        if unicodedata.category(ch) in ("Cc", "Cs") or ch in "\ufffe\uffff":
            return ch
    return None


def _check_names(mech: Mechanism) -> None:
    """Every name (the mechanism's, bodies', points', joints') and the description
    without control characters: refused here, where every door (a file, the Python
    API) passes, so that no writer has to guess what a user meant by one."""
    names = [("name", mech.name, mech.source), ("ground", mech.ground, mech.source)]
    for b in mech.bodies:
        bw = _where(mech, f"body {b.name!r}")
        names += [("body name", b.name, bw)] + [("point name", pn, bw) for pn in b.points]
    names += [("joint name", j.name, _where(mech, f"joint {j.name!r}")) for j in mech.joints]
    for key, text, where in names:
        if (ch := _bad_char(text)) is not None:
            raise DescriptionError(f"{key} {text!r} contains the control character "
                                   f"U+{ord(ch):04X}; names must be printable text", where)
    if (ch := _bad_char(mech.description, "\n\t\r")) is not None:
        raise DescriptionError(f"description contains the control character U+{ord(ch):04X}"
                               "; only line breaks and tabs are allowed", mech.source)


def _check_bodies(mech: Mechanism) -> dict[str, Body]:
    """Unique names, ground among them, points and mass properties in range."""
    where = mech.source
    names = [b.name for b in mech.bodies]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise DescriptionError(f"duplicate body names {dup}", where)
    if mech.ground not in names:
        raise DescriptionError(f"ground body {mech.ground!r} is not among the bodies {names}",
                               where)
    for b in mech.bodies:
        bw = _where(mech, f"body {b.name!r}")
        for pname, p in b.points.items():
            if len(p) != 2:
                raise DescriptionError(f"point {pname!r} must have 2 coordinates, got {p!r}",
                                       bw)
            check_range(tuple(p), MAX_LENGTH, f"point {pname!r}", bw, "m")
        if b.name != mech.ground:
            _check_mass(b, bw)
    return {b.name: b for b in mech.bodies}


def _check_mass(b: Body, bw: str) -> None:
    if b.mass is None:
        if b.inertia is not None:
            raise DescriptionError("inertia given without a mass", bw)
        return
    _finite(b.mass, "mass", bw)
    if b.mass < 0:
        raise DescriptionError(f"mass must be >= 0 kg, got {b.mass}", bw)
    check_range(b.mass, MAX_MASS, "mass", bw, "kg", lo=0.0)
    if b.inertia is None:
        raise DescriptionError("a body with a mass needs an inertia about its "
                               "centre of mass (kg m^2)", bw)
    _finite(b.inertia, "inertia", bw)
    if b.inertia < 0 or (b.mass > 0 and b.inertia == 0):
        raise DescriptionError(f"inertia about the centre of mass must be > 0 "
                               f"kg m^2 for a body with mass, got {b.inertia}", bw)
    check_range(b.inertia, MAX_INERTIA, "inertia", bw, "kg m^2", lo=0.0)
    if b.mass == 0 and b.inertia != 0:
        raise DescriptionError("a massless body cannot have an inertia", bw)
    check_range(tuple(b.com), MAX_LENGTH, "com", bw, "m")


def _check_joints(mech: Mechanism, bodies: dict[str, Body]) -> None:
    """Unique names, known bodies and points, no joint of a body to itself."""
    names = list(bodies)
    jnames = [j.name for j in mech.joints]
    if len(set(jnames)) != len(jnames):
        dup = sorted({n for n in jnames if jnames.count(n) > 1})
        raise DescriptionError(f"duplicate joint names {dup}", mech.source)
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
            check_range(j.direction, MAX_ANGLE, "direction", jw, "deg", math.pi / 180)
            check_range(j.angle, MAX_ANGLE, "angle", jw, "deg", math.pi / 180)


def _check_size(mech: Mechanism) -> None:
    """Size, and zero-length links (two joints of one body at one point) relative to
    it, so that a linkage is valid or not whatever its scale."""
    size = mechanism_size(mech.bodies)
    if size < MIN_SIZE:
        raise DescriptionError(f"the mechanism's size (the longest distance between two "
                               f"points of one body) is {size:g} m; it must be at least "
                               f"{MIN_SIZE:g} m", mech.source)
    for b in mech.bodies:
        if b.name == mech.ground:
            continue
        attach = [(j.name, j.point_a if j.body_a == b.name else j.point_b)
                  for j in mech.joints if b.name in j.bodies and isinstance(j, Revolute)]
        for i in range(len(attach)):
            for k in range(i + 1, len(attach)):
                if attach[i][1] == attach[k][1]:
                    continue  # a compound pin: several joints declared at one named point
                p = b.points[attach[i][1]]
                q = b.points[attach[k][1]]
                if math.hypot(p[0] - q[0], p[1] - q[1]) < ZERO_LENGTH * size:
                    raise DescriptionError(
                        f"joints {attach[i][0]!r} and {attach[k][0]!r} are at the same point "
                        f"(zero link length): closer than {ZERO_LENGTH:g} of the mechanism's "
                        f"size {size:g} m", _where(mech, f"body {b.name!r}"))


def _check_driver(mech: Mechanism) -> None:
    d = mech.driver
    dw = _where(mech, "driver")
    jnames = [j.name for j in mech.joints]
    if d.joint not in jnames:
        raise DescriptionError(f"driver joint {d.joint!r} is not a joint; joints are {jnames}",
                               dw)
    rev = isinstance(mech.joint(d.joint), Revolute)
    if rev:
        check_range(d.value, MAX_ANGLE, "value", dw, "deg", math.pi / 180)
    else:
        check_range(d.value, MAX_LENGTH, "value", dw, "m")
    check_range(d.velocity, MAX_RATE, "velocity", dw, "rad/s" if rev else "m/s")
    check_range(d.acceleration, MAX_ACCEL, "acceleration", dw,
                "rad/s^2" if rev else "m/s^2")


def _check_loads_and_hints(mech: Mechanism, bodies: dict[str, Body]) -> None:
    for i, ld in enumerate(mech.loads):
        lw = _where(mech, f"load {i} on body {ld.body!r}")
        if ld.body not in bodies:
            raise DescriptionError(f"unknown body {ld.body!r}", lw)
        if ld.point is not None and ld.point not in bodies[ld.body].points:
            raise DescriptionError(f"body {ld.body!r} has no point {ld.point!r}", lw)
        check_range(tuple(ld.force), MAX_LOAD, "force", lw, "N")
        check_range(ld.torque, MAX_LOAD, "torque", lw, "N m")
    check_range(tuple(mech.gravity), MAX_GRAVITY, "gravity", _where(mech, "gravity"), "m/s^2")

    aw = _where(mech, "assembly")
    for key, xy in mech.assembly.points.items():
        bn, _, pn = str(key).partition(".")
        if bn not in bodies or pn not in bodies[bn].points:
            raise DescriptionError(f"assembly hint names unknown point {key!r} "
                                   "(expected 'body.point')", aw)
        if not isinstance(xy, tuple | list) or len(xy) != 2:
            raise DescriptionError(f"hint {key!r} must be a pair [x, y], got {xy!r}", aw)
        check_range(tuple(xy), MAX_LENGTH, f"hint {key!r}", aw, "m")
    for bn, ang in mech.assembly.angles.items():
        if bn not in bodies:
            raise DescriptionError(f"assembly hint names unknown body {bn!r}", aw)
        check_range(ang, MAX_ANGLE, f"hint {bn!r}", aw, "deg", math.pi / 180)


def _check_graph(mech: Mechanism) -> None:
    """Every body reachable from ground; one degree of freedom by Gruebler's count."""
    where = mech.source
    names = [b.name for b in mech.bodies]
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


def _check_loops(mech: Mechanism) -> None:
    """A user's loops: as many as the joint graph's independent cycles, each a closed
    walk through distinct bodies (consecutive joints share a body, the last joint
    joins the first, no body twice), and independent of each other."""
    where = _where(mech, "loops")
    joints = {j.name: j for j in mech.joints}
    n_indep = len(mech.joints) - len(mech.bodies) + 1
    if len(mech.loops) != n_indep:
        raise DescriptionError(f"{len(mech.loops)} loops given but the joint graph has "
                               f"{n_indep} independent loops (joints - bodies + 1)", where)
    rows = []
    for i, lp in enumerate(mech.loops, 1):
        lw = _where(mech, f"loops entry {i} {list(lp)}")
        for n in lp:
            if n not in joints:
                raise DescriptionError(f"unknown joint {n!r}; joints are {list(joints)}", lw)
        if len(set(lp)) != len(lp):
            dup = sorted({n for n in lp if list(lp).count(n) > 1})
            raise DescriptionError(f"{NOT_A_CYCLE}: joints {dup} appear more than once", lw)
        if len(lp) < 3:
            raise DescriptionError(f"{NOT_A_CYCLE}: {len(lp)} joints cannot close a loop "
                                   "through distinct bodies (3 at least)", lw)
        rows.append(_walk_loop([joints[n] for n in lp], joints, lw))
    import numpy as np  # only here: the description module needs no numpy otherwise
    if np.linalg.matrix_rank(np.array(rows, float)) < len(rows):
        raise DescriptionError("the loops are not independent: one is a combination of the "
                               "others, so they do not determine the positions", where)


NOT_A_CYCLE = "not a closed cycle of distinct bodies"


def _walk_loop(js: list, joints: dict, where: str) -> list[int]:
    """Walk a loop from the body its last and first joints share; return the signed
    joint incidence (+1 crossing a joint from body_a to body_b, -1 back)."""
    first, last = js[0], js[-1]
    starts = [b for b in first.bodies if b in last.bodies]
    if not starts:
        raise DescriptionError(f"{NOT_A_CYCLE}: the last joint {last.name!r} "
                               f"{list(last.bodies)} and the first joint {first.name!r} "
                               f"{list(first.bodies)} share no body", where)
    err = None
    for start in starts:  # two only for parallel joints between the same two bodies
        body, seen, row = start, [start], dict.fromkeys(joints, 0)
        for k, j in enumerate(js):
            if body not in j.bodies:
                came = f" through joint {js[k - 1].name!r}" if k else ""
                err = (f"{NOT_A_CYCLE}: joints {js[k - 1].name!r} and {j.name!r} do not "
                       f"share exactly one body (the walk reached body {body!r}{came}; "
                       f"{j.name!r} joins {list(j.bodies)})")
                break
            row[j.name] = 1 if body == j.body_a else -1
            body = j.body_b if body == j.body_a else j.body_a
            if body in seen and not (k == len(js) - 1 and body == start):
                err = f"{NOT_A_CYCLE}: the walk visits body {body!r} twice (after joint " \
                      f"{j.name!r})"
                break
            seen.append(body)
        else:
            if body == start:
                return list(row.values())
            err = (f"{NOT_A_CYCLE}: the walk ends on body {body!r}, not on {start!r} "
                   "where it began")
    raise DescriptionError(err, where)
