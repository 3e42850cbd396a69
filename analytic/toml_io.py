"""Read and write mechanism descriptions as TOML (units converted at the edge).

The file maps 1:1 onto :class:`analytic.mechanism.Mechanism`; see the README
for a complete example.  Units in a file:

* ``[units] length`` (``m``, ``cm``, ``mm`` or ``in``) applies to every length
  in the file: point coordinates, centres of mass, assembly point hints, and a
  prismatic driver's value (length), velocity (length/s) and acceleration
  (length/s^2).
* Angles (``direction``, ``angle``, a revolute driver's ``value``, assembly
  angle hints) are in degrees; a revolute driver's ``velocity`` is in rad/s and
  ``acceleration`` in rad/s^2, as in the course notes.
* Mass kg, inertia kg m^2 about the centre of mass, force N, torque N m,
  gravity m/s^2: always SI.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any

from .errors import DescriptionError
from .mechanism import Assembly, Body, Driver, Load, Mechanism, Prismatic, Revolute

LENGTH_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}

_TOP_KEYS = {"name", "description", "ground", "units", "gravity", "bodies", "joints",
             "driver", "loads", "assembly", "loops"}
_BODY_KEYS = {"points", "mass", "com", "inertia"}
_REV_KEYS = {"name", "type", "bodies", "points"}
_PRI_KEYS = {"name", "type", "guide", "origin", "direction", "slider", "point", "angle"}
_DRV_KEYS = {"joint", "value", "velocity", "acceleration"}
_LOAD_KEYS = {"body", "point", "force", "torque"}


def _check_keys(table: dict, allowed: set[str], where: str) -> None:
    if not isinstance(table, dict):
        raise DescriptionError(f"expected a table, got {type(table).__name__}", where)
    extra = set(table) - allowed
    if extra:
        raise DescriptionError(f"unknown keys {sorted(extra)}; allowed are {sorted(allowed)}",
                               where)


def _num(v: Any, what: str, where: str) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise DescriptionError(f"{what} must be a finite number, got {v!r}", where)
    return float(v)


def _vec(v: Any, what: str, where: str, scale: float = 1.0) -> tuple[float, float]:
    if not isinstance(v, list | tuple) or len(v) != 2:
        raise DescriptionError(f"{what} must be a pair [x, y], got {v!r}", where)
    return (_num(v[0], what, where) * scale, _num(v[1], what, where) * scale)


def _req(table: dict, key: str, where: str) -> Any:
    if key not in table:
        raise DescriptionError(f"missing key {key!r}", where)
    return table[key]


def mechanism_from_dict(doc: dict, source: str = "<dict>") -> Mechanism:
    """Build a :class:`Mechanism` from a parsed TOML document (file units)."""
    _check_keys(doc, _TOP_KEYS, source)
    units = doc.get("units", {})
    _check_keys(units, {"length"}, f"{source}: [units]")
    lu = units.get("length", "m")
    if lu not in LENGTH_UNITS:
        raise DescriptionError(f"unknown length unit {lu!r}; use one of {sorted(LENGTH_UNITS)}",
                               f"{source}: [units]")
    L = LENGTH_UNITS[lu]
    deg = math.pi / 180.0

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
        points = {pn: _vec(pv, f"point {pn!r}", bw, L) for pn, pv in pts.items()}
        mass = _num(bd["mass"], "mass", bw) if "mass" in bd else None
        inertia = _num(bd["inertia"], "inertia", bw) if "inertia" in bd else None
        com = _vec(bd["com"], "com", bw, L) if "com" in bd else (0.0, 0.0)
        bodies.append(Body(bname, points, mass, com, inertia))

    joints = []
    jdocs = _req(doc, "joints", source)
    if not isinstance(jdocs, list):
        raise DescriptionError("joints must be an array of tables [[joints]]", source)
    for i, jd in enumerate(jdocs):
        jw = f"{source}: joint {jd.get('name', i)!r}" if isinstance(jd, dict) else source
        if not isinstance(jd, dict):
            raise DescriptionError(f"joint {i} must be a table", source)
        name = str(_req(jd, "name", jw))
        jtype = _req(jd, "type", jw)
        if jtype == "revolute":
            _check_keys(jd, _REV_KEYS, jw)
            bs, ps = _req(jd, "bodies", jw), _req(jd, "points", jw)
            if not (isinstance(bs, list) and len(bs) == 2 and isinstance(ps, list)
                    and len(ps) == 2):
                raise DescriptionError("a revolute joint needs bodies = [a, b] and "
                                       "points = [pa, pb]", jw)
            joints.append(Revolute(name, str(bs[0]), str(ps[0]), str(bs[1]), str(ps[1])))
        elif jtype == "prismatic":
            _check_keys(jd, _PRI_KEYS, jw)
            joints.append(Prismatic(
                name, str(_req(jd, "guide", jw)), str(_req(jd, "origin", jw)),
                _num(_req(jd, "direction", jw), "direction", jw) * deg,
                str(_req(jd, "slider", jw)), str(_req(jd, "point", jw)),
                _num(jd.get("angle", 0.0), "angle", jw) * deg))
        else:
            raise DescriptionError(f"unknown joint type {jtype!r}; use 'revolute' or "
                                   "'prismatic'", jw)

    dd = _req(doc, "driver", source)
    dw = f"{source}: [driver]"
    _check_keys(dd, _DRV_KEYS, dw)
    djoint = str(_req(dd, "joint", dw))
    jtypes = {j.name: j for j in joints}
    if djoint not in jtypes:
        raise DescriptionError(f"driver joint {djoint!r} is not a joint; joints are "
                               f"{list(jtypes)}", dw)
    revolute = isinstance(jtypes[djoint], Revolute)
    vscale = deg if revolute else L
    rscale = 1.0 if revolute else L
    driver = Driver(djoint, _num(_req(dd, "value", dw), "value", dw) * vscale,
                    _num(_req(dd, "velocity", dw), "velocity", dw) * rscale,
                    _num(dd.get("acceleration", 0.0), "acceleration", dw) * rscale)

    loads = []
    for i, ld in enumerate(doc.get("loads", [])):
        lw = f"{source}: load {i}"
        _check_keys(ld, _LOAD_KEYS, lw)
        loads.append(Load(str(_req(ld, "body", lw)),
                          str(ld["point"]) if "point" in ld else None,
                          _vec(ld.get("force", [0.0, 0.0]), "force", lw),
                          _num(ld.get("torque", 0.0), "torque", lw)))

    ad = doc.get("assembly", {})
    aw = f"{source}: [assembly]"
    _check_keys(ad, {"points", "angles"}, aw)
    assembly = Assembly(
        {k: _vec(v, f"hint {k!r}", aw, L) for k, v in ad.get("points", {}).items()},
        {k: _num(v, f"hint {k!r}", aw) * deg for k, v in ad.get("angles", {}).items()})

    loops = doc.get("loops")
    if loops is not None:
        if not (isinstance(loops, list) and all(isinstance(lp, list) for lp in loops)):
            raise DescriptionError("loops must be a list of lists of joint names", source)
        loops = tuple(tuple(str(n) for n in lp) for lp in loops)

    gravity = _vec(doc["gravity"], "gravity", source) if "gravity" in doc else (0.0, 0.0)
    return Mechanism(
        name=str(doc.get("name", Path(source).stem)),
        ground=str(doc.get("ground", "ground")),
        bodies=tuple(bodies), joints=tuple(joints), driver=driver, loads=tuple(loads),
        gravity=gravity, assembly=assembly, loops=loops,
        description=str(doc.get("description", "")), source=source)


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
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        raise DescriptionError(f"cannot read file: {e.strerror}", str(path)) from None
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise DescriptionError(f"malformed TOML: {e}", str(path)) from None
    return mechanism_from_dict(doc, str(path))
