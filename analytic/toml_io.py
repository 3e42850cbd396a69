"""Read and write mechanism descriptions as TOML (units converted at the edge).

The file maps 1:1 onto :class:`analytic.mechanism.Mechanism`; see the README
for a complete example.  Units in a file:

* ``[units] length`` (``m``, ``cm``, ``mm`` or ``in``) applies to every length
  in the file: point coordinates, centres of mass, assembly point hints, and a
  prismatic driver's value (length), velocity (length/s) and acceleration
  (length/s^2).
* Angles (``direction``, ``angle``, a revolute driver's ``value``, assembly
  angle hints) are in degrees; a revolute driver's ``velocity`` is in rad/s and
  ``acceleration`` in rad/s^2, as in the course notes, unless ``[driver]
  velocity_unit`` (``rad/s``, ``rpm``, ``deg/s``) or ``acceleration_unit``
  (``rad/s^2``, ``rpm/s``, ``deg/s^2``) says otherwise.
* Mass kg, inertia kg m^2 about the centre of mass, force N, torque N m,
  gravity m/s^2: always SI.
"""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path
from typing import Any

from .errors import DescriptionError
from .mechanism import (
    MAX_ACCEL,
    MAX_ANGLE,
    MAX_GRAVITY,
    MAX_INERTIA,
    MAX_LENGTH,
    MAX_LOAD,
    MAX_MASS,
    MAX_RATE,
    Assembly,
    Body,
    Driver,
    Load,
    Mechanism,
    Prismatic,
    Revolute,
    check_range,
)
from .motion_spec import (
    MAX_DURATION,
    FreeMotion,
    JointDamper,
    JointSpring,
    Motor,
    PointDamper,
    PointSpring,
)

LENGTH_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
DEG = math.pi / 180.0

_TOP_KEYS = {"name", "description", "ground", "units", "gravity", "bodies", "joints",
             "driver", "loads", "assembly", "loops", "motion", "springs", "dampers", "motors"}
_BODY_KEYS = {"points", "mass", "com", "inertia"}
_REV_KEYS = {"name", "type", "bodies", "points"}
_PRI_KEYS = {"name", "type", "guide", "origin", "direction", "slider", "point", "angle"}
_DRV_KEYS = {"joint", "value", "velocity", "acceleration", "velocity_unit",
             "acceleration_unit"}
#: A revolute driver's rate units (``velocity_unit``, ``acceleration_unit``): factor to SI.
RATE_UNITS = {"rad/s": 1.0, "rpm": 2.0 * math.pi / 60.0, "deg/s": math.pi / 180.0}
ACCEL_UNITS = {"rad/s^2": 1.0, "rpm/s": 2.0 * math.pi / 60.0, "deg/s^2": math.pi / 180.0}
_LOAD_KEYS = {"body", "point", "force", "torque"}


def _check_keys(table: Any, allowed: set[str], where: str) -> dict:
    if not isinstance(table, dict):
        raise DescriptionError(f"expected a table, got {_kind(table)}", where)
    extra = set(table) - allowed
    if extra:
        raise DescriptionError(f"unknown keys {sorted(extra)}; allowed are {sorted(allowed)}",
                               where)
    return table


def _kind(v: Any) -> str:
    """The TOML name of a value's type, for messages."""
    return {dict: "a table", list: "an array", str: "a string", bool: "a boolean",
            int: "an integer", float: "a float"}.get(type(v), type(v).__name__)


def _num(v: Any, what: str, where: str, limit: float | None = None, unit: str = "",
         scale: float = 1.0, lo: float | None = None) -> float:
    """A finite number; with ``limit`` (SI) also in range, stated in the file's unit."""
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise DescriptionError(f"{what} must be a finite number, got {v!r}", where)
    if limit is not None:
        check_range(float(v) * scale, limit, what, where, unit, scale, lo)
    return float(v) * scale


def _vec(v: Any, what: str, where: str, scale: float = 1.0, limit: float | None = None,
         unit: str = "") -> tuple[float, float]:
    if not isinstance(v, list | tuple) or len(v) != 2:
        raise DescriptionError(f"{what} must be a pair [x, y], got {v!r}", where)
    return (_num(v[0], what, where, limit, unit, scale),
            _num(v[1], what, where, limit, unit, scale))


def _str(v: Any, what: str, where: str) -> str:
    if not isinstance(v, str) or not v:
        raise DescriptionError(f"{what} must be a non-empty string, got {v!r}", where)
    return v


def _table(v: Any, what: str, where: str) -> dict:
    if not isinstance(v, dict):
        raise DescriptionError(f"{what} must be a table, got {_kind(v)} {v!r}", where)
    return v


def _req(table: dict, key: str, where: str) -> Any:
    if key not in table:
        raise DescriptionError(f"missing key {key!r}", where)
    return table[key]


def _length_unit(doc: dict, source: str) -> tuple[float, str]:
    uw = f"{source}: [units]"
    units = _check_keys(doc.get("units", {}), {"length"}, uw)
    lu = units.get("length", "m")
    if not isinstance(lu, str) or lu not in LENGTH_UNITS:
        raise DescriptionError(f"unknown length unit {lu!r}; use one of {sorted(LENGTH_UNITS)}",
                               uw)
    return LENGTH_UNITS[lu], lu


def _bodies(doc: dict, source: str, L: float, lu: str) -> list[Body]:
    bodies_doc = _req(doc, "bodies", source)
    if not isinstance(bodies_doc, dict) or not bodies_doc:
        raise DescriptionError("[bodies] must be a non-empty table", source)
    bodies = []
    for bname, bd in bodies_doc.items():
        bw = f"{source}: body {bname!r}"
        _check_keys(bd, _BODY_KEYS, bw)
        pts = bd.get("points", {})
        if not isinstance(pts, dict):
            raise DescriptionError("points must be a table name = [x, y]", bw)
        points = {pn: _vec(pv, f"point {pn!r}", bw, L, MAX_LENGTH, lu)
                  for pn, pv in pts.items()}
        mass = (_num(bd["mass"], "mass", bw, MAX_MASS, "kg", lo=0.0) if "mass" in bd
                else None)
        inertia = (_num(bd["inertia"], "inertia", bw, MAX_INERTIA, "kg m^2", lo=0.0)
                   if "inertia" in bd else None)
        com = _vec(bd["com"], "com", bw, L, MAX_LENGTH, lu) if "com" in bd else (0.0, 0.0)
        bodies.append(Body(bname, points, mass, com, inertia))
    return bodies


def _joints(doc: dict, source: str) -> list:
    joints = []
    jdocs = _req(doc, "joints", source)
    if not isinstance(jdocs, list):
        raise DescriptionError("joints must be an array of tables [[joints]]", source)
    for i, jd in enumerate(jdocs):
        if not isinstance(jd, dict):
            raise DescriptionError(f"joint {i} must be a table, got {_kind(jd)}", source)
        jw = f"{source}: joint {jd.get('name', i)!r}"
        name = _str(_req(jd, "name", jw), "name", jw)
        jtype = _req(jd, "type", jw)
        if jtype == "revolute":
            _check_keys(jd, _REV_KEYS, jw)
            bs, ps = _req(jd, "bodies", jw), _req(jd, "points", jw)
            if not (isinstance(bs, list) and len(bs) == 2 and isinstance(ps, list)
                    and len(ps) == 2):
                raise DescriptionError("a revolute joint needs bodies = [a, b] and "
                                       "points = [pa, pb]", jw)
            joints.append(Revolute(name, _str(bs[0], "bodies[0]", jw),
                                   _str(ps[0], "points[0]", jw), _str(bs[1], "bodies[1]", jw),
                                   _str(ps[1], "points[1]", jw)))
        elif jtype == "prismatic":
            _check_keys(jd, _PRI_KEYS, jw)
            joints.append(Prismatic(
                name, _str(_req(jd, "guide", jw), "guide", jw),
                _str(_req(jd, "origin", jw), "origin", jw),
                _num(_req(jd, "direction", jw), "direction", jw, MAX_ANGLE, "deg", DEG),
                _str(_req(jd, "slider", jw), "slider", jw),
                _str(_req(jd, "point", jw), "point", jw),
                _num(jd.get("angle", 0.0), "angle", jw, MAX_ANGLE, "deg", DEG)))
        else:
            raise DescriptionError(f"unknown joint type {jtype!r}; use 'revolute' or "
                                   "'prismatic'", jw)
    return joints


def _driver(doc: dict, source: str, joints: list, L: float, lu: str) -> Driver:
    dw = f"{source}: [driver]"
    dd = _check_keys(_req(doc, "driver", source), _DRV_KEYS, dw)
    djoint = _str(_req(dd, "joint", dw), "joint", dw)
    jtypes = {j.name: j for j in joints}
    if djoint not in jtypes:
        raise DescriptionError(f"driver joint {djoint!r} is not a joint; joints are "
                               f"{list(jtypes)}", dw)
    if isinstance(jtypes[djoint], Revolute):
        value = _num(_req(dd, "value", dw), "value", dw, MAX_ANGLE, "deg", DEG)
        vu = _unit_key(dd, "velocity_unit", RATE_UNITS, "rad/s", dw)
        au = _unit_key(dd, "acceleration_unit", ACCEL_UNITS, "rad/s^2", dw)
        rate = (vu, au, RATE_UNITS[vu], ACCEL_UNITS[au])
    else:
        value = _num(_req(dd, "value", dw), "value", dw, MAX_LENGTH, lu, L)
        for k in ("velocity_unit", "acceleration_unit"):
            if k in dd:
                raise DescriptionError(f"{k} is for a revolute driver; a prismatic driver's "
                                       f"rates are in the [units] length ({lu}/s, {lu}/s^2)",
                                       dw)
        rate = (f"{lu}/s", f"{lu}/s^2", L, L)
    return Driver(djoint, value,
                  _num(_req(dd, "velocity", dw), "velocity", dw, MAX_RATE, rate[0], rate[2]),
                  _num(dd.get("acceleration", 0.0), "acceleration", dw, MAX_ACCEL, rate[1],
                       rate[3]))


def _unit_key(dd: dict, key: str, units: dict, default: str, where: str) -> str:
    """A driver's rate unit (``velocity_unit = "rpm"``), checked against ``units``."""
    u = dd.get(key, default)
    if not isinstance(u, str) or u not in units:
        raise DescriptionError(f"{key} {u!r} is not a unit; use one of "
                               f"{', '.join(repr(k) for k in units)}", where)
    return u


def _loads(doc: dict, source: str) -> list[Load]:
    lds = doc.get("loads", [])
    if not isinstance(lds, list):
        raise DescriptionError(f"loads must be an array of tables [[loads]], got {_kind(lds)}",
                               source)
    loads = []
    for i, ld in enumerate(lds):
        lw = f"{source}: load {i}"
        _check_keys(ld, _LOAD_KEYS, lw)
        loads.append(Load(_str(_req(ld, "body", lw), "body", lw),
                          _str(ld["point"], "point", lw) if "point" in ld else None,
                          _vec(ld.get("force", [0.0, 0.0]), "force", lw, 1.0, MAX_LOAD, "N"),
                          _num(ld.get("torque", 0.0), "torque", lw, MAX_LOAD, "N m")))
    return loads


def _assembly(doc: dict, source: str, L: float, lu: str) -> Assembly:
    aw = f"{source}: [assembly]"
    ad = _check_keys(doc.get("assembly", {}), {"points", "angles"}, aw)
    pts = _table(ad.get("points", {}), "points", aw)
    angs = _table(ad.get("angles", {}), "angles", aw)
    return Assembly(
        {k: _vec(v, f"hint {k!r}", aw, L, MAX_LENGTH, lu) for k, v in pts.items()},
        {k: _num(v, f"hint {k!r}", aw, MAX_ANGLE, "deg", DEG) for k, v in angs.items()})


def _loops(doc: dict, source: str) -> tuple[tuple[str, ...], ...] | None:
    loops = doc.get("loops")
    if loops is None:
        return None
    if not (isinstance(loops, list) and all(isinstance(lp, list) for lp in loops)):
        raise DescriptionError("loops must be a list of lists of joint names", source)
    return tuple(tuple(_str(n, f"loops entry {i}: joint name", source) for n in lp)
                 for i, lp in enumerate(loops, 1))


_MOTION_KEYS = {"joint", "value", "rate", "rate_unit", "duration", "samples"}
_SPRING_KEYS = {"joint", "bodies", "points", "stiffness", "free_length", "free_angle"}
_DAMPER_KEYS = {"joint", "bodies", "points", "coefficient"}
_MOTOR_KEYS = {"joint", "effort", "table"}


def _motion(doc: dict, source: str, joints: list, L: float, lu: str) -> FreeMotion | None:
    """The free-motion sections (``[motion]``, ``[[springs]]``, ``[[dampers]]``,
    ``[[motors]]``), file units converted to SI; ``None`` when there is no ``[motion]``."""
    if "motion" not in doc:
        for key in ("springs", "dampers", "motors"):
            if key in doc:
                raise DescriptionError(f"[[{key}]] act in free motion only: add a [motion] "
                                       "table (initial joint, value, rate, duration)", source)
        return None
    mw = f"{source}: [motion]"
    md = _check_keys(doc["motion"], _MOTION_KEYS, mw)
    jt = _named_joint(_str(_req(md, "joint", mw), "joint", mw), joints, mw)
    if isinstance(jt, Revolute):
        ru = _unit_key(md, "rate_unit", RATE_UNITS, "rad/s", mw)
        value = _num(_req(md, "value", mw), "value", mw, MAX_ANGLE, "deg", DEG)
        rate = _num(md.get("rate", 0.0), "rate", mw, MAX_RATE, ru, RATE_UNITS[ru])
    else:
        value = _num(_req(md, "value", mw), "value", mw, MAX_LENGTH, lu, L)
        rate = _num(md.get("rate", 0.0), "rate", mw, MAX_RATE, f"{lu}/s", L)
    d = _req(md, "duration", mw)
    if isinstance(d, int | float) and not isinstance(d, bool) and math.isfinite(d) and d <= 0:
        # said as the range it is (0 itself is refused), not as "0 to MAX_DURATION"
        raise DescriptionError(f"duration = {d:g} s is out of range: the accepted range is "
                               f"0 < duration <= {MAX_DURATION:g} s", mw)
    duration = _num(d, "duration", mw, MAX_DURATION, "s", lo=0.0)
    samples = md.get("samples", 201)
    if isinstance(samples, bool) or not isinstance(samples, int):
        raise DescriptionError(f"samples must be an integer, got {samples!r}", mw)
    return FreeMotion(
        jt.name, value, rate, duration, samples,
        tuple(_element(d, f"{source}: spring {i}", _SPRING_KEYS, joints, L, lu)
              for i, d in enumerate(_array(doc, "springs", source))),
        tuple(_element(d, f"{source}: damper {i}", _DAMPER_KEYS, joints, L, lu)
              for i, d in enumerate(_array(doc, "dampers", source))),
        tuple(_motor(d, f"{source}: motor {i}", joints)
              for i, d in enumerate(_array(doc, "motors", source))))


def _array(doc: dict, key: str, source: str) -> list:
    v = doc.get(key, [])
    if not isinstance(v, list):
        raise DescriptionError(f"{key} must be an array of tables [[{key}]], got {_kind(v)}",
                               source)
    return v


def _named_joint(name: str, joints: list, where: str):
    for j in joints:
        if j.name == name:
            return j
    raise DescriptionError(f"unknown joint {name!r}; joints are {[j.name for j in joints]}",
                           where)


def _element(d: Any, where: str, keys: set, joints: list, L: float, lu: str):
    """A spring (stiffness) or damper (coefficient): on a ``joint``, or between
    ``bodies = [a, b]`` at ``points = [pa, pb]``."""
    _check_keys(d, keys, where)
    spring = "stiffness" in keys
    k = _num(_req(d, "stiffness" if spring else "coefficient", where),
             "stiffness" if spring else "coefficient", where)
    if "joint" in d:
        if "bodies" in d or "points" in d:
            raise DescriptionError("give either joint = name or bodies/points, not both",
                                   where)
        jt = _named_joint(_str(d["joint"], "joint", where), joints, where)
        if not spring:
            return JointDamper(jt.name, k)
        if isinstance(jt, Revolute):
            if "free_length" in d:
                raise DescriptionError("a revolute joint's spring has free_angle (deg), not "
                                       "free_length", where)
            return JointSpring(jt.name, k, _num(d.get("free_angle", 0.0), "free_angle", where,
                                                MAX_ANGLE, "deg", DEG))
        if "free_angle" in d:
            raise DescriptionError("a prismatic joint's spring has free_length, not "
                                   "free_angle", where)
        return JointSpring(jt.name, k, _num(d.get("free_length", 0.0), "free_length", where,
                                            MAX_LENGTH, lu, L))
    bs, ps = _req(d, "bodies", where), _req(d, "points", where)
    if not (isinstance(bs, list) and len(bs) == 2 and isinstance(ps, list) and len(ps) == 2):
        raise DescriptionError("needs joint = name, or bodies = [a, b] and points = [pa, pb]",
                               where)
    ends = (_str(bs[0], "bodies[0]", where), _str(ps[0], "points[0]", where),
            _str(bs[1], "bodies[1]", where), _str(ps[1], "points[1]", where))
    if not spring:
        return PointDamper(*ends, k)
    if "free_angle" in d:
        raise DescriptionError("a spring between points has free_length, not free_angle",
                               where)
    return PointSpring(*ends, k, _num(_req(d, "free_length", where), "free_length", where,
                                      MAX_LENGTH, lu, L))


def _motor(d: Any, where: str, joints: list) -> Motor:
    """A motor: ``effort`` (constant, N m or N) or ``table = [[t, effort], ...]``."""
    _check_keys(d, _MOTOR_KEYS, where)
    jt = _named_joint(_str(_req(d, "joint", where), "joint", where), joints, where)
    if ("effort" in d) == ("table" in d):
        raise DescriptionError("a motor needs exactly one of effort (constant) or table "
                               "([[time s, effort], ...])", where)
    if "effort" in d:
        return Motor(jt.name, _num(d["effort"], "effort", where))
    tab = d["table"]
    if not isinstance(tab, list) or not all(isinstance(r, list) and len(r) == 2 for r in tab):
        raise DescriptionError("table must be an array of [time s, effort] pairs", where)
    rows = [(_num(r[0], f"table row {i} time", where), _num(r[1], f"table row {i} effort",
                                                             where))
            for i, r in enumerate(tab)]
    return Motor(jt.name, 0.0, tuple(r[0] for r in rows), tuple(r[1] for r in rows))


def mechanism_from_dict(doc: dict, source: str = "<dict>") -> Mechanism:
    """Build a :class:`Mechanism` from a parsed TOML document (file units).

    Every value is checked where it is read: its type, that it is finite, and
    that it lies in the accepted range of :mod:`analytic.mechanism` (stated in
    the file's units when it is not).
    """
    _check_keys(doc, _TOP_KEYS, source)
    L, lu = _length_unit(doc, source)
    bodies = _bodies(doc, source, L, lu)
    joints = _joints(doc, source)
    driver = _driver(doc, source, joints, L, lu)
    gravity = (_vec(doc["gravity"], "gravity", source, 1.0, MAX_GRAVITY, "m/s^2")
               if "gravity" in doc else (0.0, 0.0))
    for key in ("name", "ground", "description"):
        if key in doc and not isinstance(doc[key], str):
            raise DescriptionError(f"{key} must be a string, got {_kind(doc[key])}", source)
    return Mechanism(
        name=str(doc.get("name", Path(source).stem)),
        ground=str(doc.get("ground", "ground")),
        bodies=tuple(bodies), joints=tuple(joints), driver=driver,
        loads=tuple(_loads(doc, source)), gravity=gravity,
        assembly=_assembly(doc, source, L, lu), loops=_loops(doc, source),
        description=str(doc.get("description", "")), source=source,
        motion=_motion(doc, source, joints, L, lu))


def decode_text(data: bytes, where: str) -> str:
    """A TOML file's text: UTF-8 (a leading byte-order mark is dropped), or a one-line
    :class:`DescriptionError` that says what the file looks like instead."""
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise DescriptionError("the file is UTF-16 text; TOML files must be UTF-8 (save it "
                               "as UTF-8)", where)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise DescriptionError(f"not a UTF-8 text file (byte 0x{data[e.start]:02x} at "
                               f"offset {e.start}); TOML files must be UTF-8 text",
                               where) from None
    if "\x00" in text:
        raise DescriptionError(f"not a text file (a NUL byte at offset {text.index(chr(0))})",
                               where)
    return text


def load_mechanism(path: str | Path) -> Mechanism:
    """Read a mechanism TOML file.

    Raises
    ------
    DescriptionError
        File missing or unreadable, malformed TOML (with line and column), or an
        inconsistent description; the message names the file and the part at fault.
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as e:
        raise DescriptionError(f"cannot read file: {e.strerror}", str(path)) from None
    text = decode_text(data, str(path))
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise DescriptionError(f"malformed TOML: {e}", str(path)) from None
    return mechanism_from_dict(doc, str(path))


def mechanism_to_toml(mech: Mechanism) -> str:
    """The TOML text of a description (SI lengths, degrees), readable by
    :func:`load_mechanism`; floats are written with ``repr`` so lengths, masses and
    rates read back exactly (angles to the rounding of the degree conversion)."""
    def f(x: float) -> str:
        return repr(float(x))

    def pair(v) -> str:
        return f"[{f(v[0])}, {f(v[1])}]"

    def q(s: str) -> str:
        return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'

    deg = math.degrees
    out = [f"name = {q(mech.name)}", f"ground = {q(mech.ground)}",
           f"gravity = {pair(mech.gravity)}"]
    if mech.description:  # a TOML basic string: JSON's escapes are TOML's
        out.insert(1, f"description = {json.dumps(mech.description, ensure_ascii=False)}")
    if mech.loops is not None:
        out.append("loops = [" + ", ".join("[" + ", ".join(q(n) for n in lp) + "]"
                                           for lp in mech.loops) + "]")
    out += ["", "[units]", 'length = "m"']
    for b in mech.bodies:
        out += ["", f"[bodies.{q(b.name)}]",
                "points = { " + ", ".join(f"{q(k)} = {pair(v)}" for k, v in b.points.items())
                + " }"]
        if b.mass is not None:
            out += [f"mass = {f(b.mass)}", f"com = {pair(b.com)}", f"inertia = {f(b.inertia)}"]
    for j in mech.joints:
        out += ["", "[[joints]]", f"name = {q(j.name)}"]
        if isinstance(j, Revolute):
            out += ['type = "revolute"', f"bodies = [{q(j.body_a)}, {q(j.body_b)}]",
                    f"points = [{q(j.point_a)}, {q(j.point_b)}]"]
        else:
            out += ['type = "prismatic"', f"guide = {q(j.guide)}", f"origin = {q(j.origin)}",
                    f"direction = {f(deg(j.direction))}", f"slider = {q(j.slider)}",
                    f"point = {q(j.point)}", f"angle = {f(deg(j.angle))}"]
    d = mech.driver
    rev = isinstance(mech.joint(d.joint), Revolute)
    out += ["", "[driver]", f"joint = {q(d.joint)}",
            f"value = {f(deg(d.value) if rev else d.value)}",
            f"velocity = {f(d.velocity)}", f"acceleration = {f(d.acceleration)}"]
    for ld in mech.loads:
        out += ["", "[[loads]]", f"body = {q(ld.body)}"]
        if ld.point is not None:
            out.append(f"point = {q(ld.point)}")
        out += [f"force = {pair(ld.force)}", f"torque = {f(ld.torque)}"]
    if mech.motion is not None:
        out += _motion_toml(mech, f, q)
    a = mech.assembly
    if a.points or a.angles:
        out += ["", "[assembly]"]
        if a.points:
            out.append("points = { " + ", ".join(f"{q(k)} = {pair(v)}"
                                                  for k, v in a.points.items()) + " }")
        if a.angles:
            out.append("angles = { " + ", ".join(f"{q(k)} = {f(deg(v))}"
                                                  for k, v in a.angles.items()) + " }")
    return "\n".join(out) + "\n"


def _motion_toml(mech: Mechanism, f, q) -> list[str]:
    """The ``[motion]``, ``[[springs]]``, ``[[dampers]]`` and ``[[motors]]`` lines of
    :func:`mechanism_to_toml` (SI lengths, degrees for angles, rad/s)."""
    fm = mech.motion
    deg = math.degrees

    def rev(name: str) -> bool:
        return isinstance(mech.joint(name), Revolute)

    out = ["", "[motion]", f"joint = {q(fm.joint)}",
           f"value = {f(deg(fm.value) if rev(fm.joint) else fm.value)}",
           f"rate = {f(fm.rate)}", f"duration = {f(fm.duration)}", f"samples = {fm.samples}"]
    for el in fm.springs + fm.dampers:
        spring = isinstance(el, PointSpring | JointSpring)
        out += ["", "[[springs]]" if spring else "[[dampers]]"]
        if isinstance(el, PointSpring | PointDamper):
            out += [f"bodies = [{q(el.body_a)}, {q(el.body_b)}]",
                    f"points = [{q(el.point_a)}, {q(el.point_b)}]"]
        else:
            out.append(f"joint = {q(el.joint)}")
        if not spring:
            out.append(f"coefficient = {f(el.coefficient)}")
            continue
        out.append(f"stiffness = {f(el.stiffness)}")
        if isinstance(el, PointSpring):
            out.append(f"free_length = {f(el.free_length)}")
        elif rev(el.joint):
            out.append(f"free_angle = {f(deg(el.free_value))}")
        else:
            out.append(f"free_length = {f(el.free_value)}")
    for mo in fm.motors:
        out += ["", "[[motors]]", f"joint = {q(mo.joint)}"]
        if mo.times:
            out.append("table = [" + ", ".join(f"[{f(t)}, {f(e)}]"
                                               for t, e in zip(mo.times, mo.efforts,
                                                               strict=True)) + "]")
        else:
            out.append(f"effort = {f(mo.effort)}")
    return out
