"""Display units of ``xval solve``, ``sweep`` and ``plot`` (``--units mm,deg,rpm``).

SI inside, converted here at the edge and nowhere else.  A choice names up to three
units, in any order: a length (``m``, ``cm``, ``mm``, ``in``), an angle (``deg``,
``rad``) and a speed (``rad/s``, ``rpm``).  Defaults: m, deg, rad/s (what the tables
printed before the option existed).  What each choice converts:

* lengths: point coordinates, slider positions ``s``; linear velocities (unit/s) and
  accelerations (unit/s^2); a prismatic input;
* angles: body angles, a revolute input, transmission angles;
* speeds: angular velocities (omega, a revolute input's rate).

Angular accelerations stay rad/s^2; forces N, torques and couples N m, power W
(every header says so: :meth:`DisplayUnits.header`).

Round-off noise: a value whose magnitude is below :data:`NOISE` of its quantity's
scale (the largest magnitude of the same kind in the same table) is shown as 0, and a
zero never carries a sign (:func:`snap`, :func:`text`).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from analytic.errors import LinkageError

#: Magnitudes below this fraction of their quantity's scale are round-off of a zero
#: (the solver's residuals are ~1e-15 of scale; a real value 1e-12 of its peak is
#: below any printed digit of the tables anyway).
NOISE = 1e-12

LENGTHS = {"m": 1.0, "cm": 100.0, "mm": 1000.0, "in": 1.0 / 0.0254}
ANGLES = {"deg": 180.0 / math.pi, "rad": 1.0}
SPEEDS = {"rad/s": 1.0, "rpm": 60.0 / (2.0 * math.pi)}


class UnitsError(LinkageError):
    """A ``--units`` value names an unknown unit or the same kind twice."""


@dataclass(frozen=True)
class DisplayUnits:
    """The units a table or figure is shown in; the factors multiply SI values."""

    length: str = "m"
    angle: str = "deg"
    speed: str = "rad/s"

    @classmethod
    def parse(cls, text: str | None) -> DisplayUnits:
        """``"mm,deg,rpm"`` (any order, any subset; ``None`` or ``""``: the defaults; a
        :class:`DisplayUnits` is returned as it is)."""
        if isinstance(text, DisplayUnits):
            return text
        if not text:
            return cls()
        got: dict[str, str] = {}
        for tok in (t.strip() for t in re.split(r"[,\s]+", text.strip())):
            if not tok:
                continue
            key = tok.lower().replace("rad/sec", "rad/s")
            kind = ("length" if key in LENGTHS else "angle" if key in ANGLES
                    else "speed" if key in SPEEDS else None)
            if kind is None:
                raise UnitsError(
                    f"option --units: unknown unit {tok!r}; lengths {'|'.join(LENGTHS)}, "
                    f"angles {'|'.join(ANGLES)}, speeds {'|'.join(SPEEDS)} "
                    "(e.g. --units mm,deg,rpm)")
            if kind in got:
                raise UnitsError(f"option --units: two {kind} units ({got[kind]!r} and "
                                 f"{tok!r}); give one of each kind")
            got[kind] = key
        return cls(**got)

    # -- factors (SI -> display) ---------------------------------------------------
    @property
    def L(self) -> float:
        return LENGTHS[self.length]

    @property
    def A(self) -> float:
        return ANGLES[self.angle]

    @property
    def W(self) -> float:
        return SPEEDS[self.speed]

    @property
    def is_si(self) -> bool:
        return self == DisplayUnits()

    # -- labels ---------------------------------------------------------------------
    def unit(self, kind: str) -> str:
        """The unit text of a quantity kind (see :data:`KINDS`)."""
        return {"length": self.length, "velocity": f"{self.length}/s",
                "acceleration": f"{self.length}/s^2", "angle": self.angle,
                "omega": self.speed, "alpha": "rad/s^2", "force": "N", "moment": "N m",
                "power": "W", "residual": "W", "time": "s", "ratio": "-"}[kind]

    def factor(self, kind: str) -> float:
        """SI -> display factor of a quantity kind (angles from radians)."""
        return {"length": self.L, "velocity": self.L, "acceleration": self.L,
                "angle": self.A, "omega": self.W}.get(kind, 1.0)

    def header(self) -> str:
        """The line every output states its units in."""
        return (f"units: lengths {self.length}, angles {self.angle}, angular speeds "
                f"{self.speed}; angular accelerations rad/s^2, forces N, torques N m, "
                "power W")

    def input_kinds(self, revolute: bool) -> tuple[str, str, str]:
        """Kinds of the input's value, rate and acceleration."""
        return ("angle", "omega", "alpha") if revolute else \
            ("length", "velocity", "acceleration")


def units_option(text: str) -> DisplayUnits:
    """The argparse type of ``--units`` (an error is one line, status 2)."""
    import argparse
    try:
        return DisplayUnits.parse(text)
    except UnitsError as e:
        raise argparse.ArgumentTypeError(str(e).removeprefix("option --units: ")) from None


UNITS_HELP = ("display units, e.g. mm,deg,rpm: a length m|cm|mm|in, an angle deg|rad, an "
              "angular speed rad/s|rpm (default m,deg,rad/s)")


#: Quantity kinds (what :meth:`DisplayUnits.factor` and ``unit`` know).
KINDS = ("length", "velocity", "acceleration", "angle", "omega", "alpha", "force",
         "moment", "power", "time", "ratio")


def snap(values, scale: float):
    """``values`` with magnitudes below :data:`NOISE` x ``scale`` set to 0 and no
    negative zero (arrays or scalars; NaN stays NaN)."""
    v = np.asarray(values, float)
    out = np.where(np.abs(v) < NOISE * scale, 0.0, v) + 0.0  # + 0.0: -0.0 -> 0.0
    return float(out) if np.ndim(out) == 0 else out


def scale_of(*arrays) -> float:
    """The scale of a quantity: the largest finite magnitude among ``arrays``."""
    m = 0.0
    for a in arrays:
        a = np.abs(np.asarray(a, float))
        a = a[np.isfinite(a)]
        if a.size:
            m = max(m, float(a.max()))
    return m


def text(v: float, spec: str = ".6g") -> str:
    """``format(v, spec)`` without a sign on a zero (``-0.000000`` -> ``0.000000``)."""
    s = format(float(v), spec)
    if s.startswith("-") and not any(c in "123456789" for c in s.split("e")[0]):
        s = s[1:]
    return s


# ============================================================================ sweep tables
def column_kind(col: str, revolute: bool) -> str:
    """The quantity kind of a column of the sweep table (:mod:`analytic.sweep`)."""
    if col == "input":
        return "angle" if revolute else "length"
    if col == "input_velocity":
        return "omega" if revolute else "velocity"
    if col == "input_acceleration":
        return "alpha" if revolute else "acceleration"
    if col.startswith("transmission_deg") or col.endswith(".angle_deg"):
        return "angle"
    if col.startswith("jacobian_"):
        return "ratio"
    if col == "power_residual":
        return "residual"  # a diagnostic: shown as it is, never snapped
    if col == "singular":
        return "status"  # a code (analytic.singular), no unit: as it is
    if col == "drive.power":
        return "power"
    if col == "drive.torque" or col.endswith(".moment"):
        return "moment"
    if col == "drive.force":
        return "force"
    if col == "time":
        return "time"
    last = col.rsplit(".", 1)[-1]
    return {"x": "length", "y": "length", "s": "length", "vx": "velocity",
            "vy": "velocity", "v": "velocity", "ax": "acceleration", "ay": "acceleration",
            "a": "acceleration", "omega": "omega", "alpha": "alpha", "fx": "force",
            "fy": "force", "normal": "force"}.get(last, "ratio")


def convert_frame(frame, units: DisplayUnits, revolute: bool, rename: bool | None = None):
    """The sweep table in ``units`` with round-off noise snapped to 0 (per kind: the
    scale is the kind's largest magnitude in the table).  Angle columns come in degrees
    and leave in ``units.angle``.  With ``rename`` (default: when not the SI default),
    each column name gets its unit: ``crank.omega [rpm]``, ``crank.angle [rad]``."""
    out = frame.copy()
    kinds = {c: column_kind(c, revolute) for c in frame.columns}
    if rename is None:
        rename = not units.is_si
    for kind in set(kinds.values()) - {"residual", "status"}:
        cols = [c for c, k in kinds.items() if k == kind]
        f = units.factor(kind)
        if kind == "angle":  # the table's angles are degrees
            f = units.A * math.pi / 180.0
        vals = {c: np.asarray(frame[c], float) * f for c in cols}
        s = scale_of(*vals.values())
        if kind == "angle":
            s = max(s, 2 * math.pi * units.A)  # an angle's scale is a turn
        for c in cols:
            out[c] = snap(vals[c], s)
    if rename:
        def name(c):
            base = c.replace(".angle_deg", ".angle").replace("transmission_deg",
                                                              "transmission")
            return base if kinds[c] == "status" else f"{base} [{units.unit(kinds[c])}]"
        out.columns = [name(c) for c in frame.columns]
    return out


# ============================================================================ solve result
def convert_result(res: dict, units: DisplayUnits) -> dict:
    """The ``xval solve`` result dict (SI, angles in deg; see :mod:`reports.cli`) in
    ``units``, noise snapped per kind (scale: the kind's largest magnitude in the
    result; a couple's and torque's at least the largest force times the largest
    coordinate), with a ``units`` entry when not the default.  Keys are unchanged
    (``angle_deg`` holds the angle in ``units.angle``)."""
    import copy
    r = copy.deepcopy(res)
    inp = r["input"]
    rev = "angle_deg" in inp
    degA = units.A * math.pi / 180.0
    L = units.L
    # input
    if rev:
        inp["angle_deg"] = snap(inp["angle_deg"] * degA, 2 * math.pi * units.A)
        inp["velocity"] = inp["velocity"] * units.W + 0.0
    else:
        inp["s"] = inp["s"] * L
        inp["velocity"] = inp["velocity"] * L
        inp["acceleration"] = inp["acceleration"] * L
    b = r["bodies"]
    sw = scale_of([d["omega"] for d in b.values()]) * units.W
    # an angular acceleration's own scale is omega^2 too: a link whose alpha is exactly
    # 0 at this input (round-off 4e-12 rad/s^2 at 200 rad/s) is not judged by itself
    sa = max(scale_of([d["alpha"] for d in b.values()]),
             scale_of([d["omega"] for d in b.values()]) ** 2)
    for d in b.values():
        d["angle_deg"] = snap(d["angle_deg"] * degA, 2 * math.pi * units.A)
        d["omega"] = snap(d["omega"] * units.W, sw)
        d["alpha"] = snap(d["alpha"], sa)
    pts, sl = r["points"], r["sliders"]
    size = _size(pts)  # m, before conversion: the lever of a couple
    for key, ks in (("position", "s"), ("velocity", "v"), ("acceleration", "a")):
        sc = L * scale_of([d[key] for d in pts.values()], [d[ks] for d in sl.values()])
        for d in pts.values():
            d[key] = [snap(x * L, sc) for x in d[key]]
        for d in sl.values():
            d[ks] = snap(d[ks] * L, sc)
    j = r["joints"]
    sf = scale_of([d["force"] for d in j.values()],
                  [d.get("normal", 0.0) for d in j.values()])
    sm = max(scale_of([d["moment"] for d in j.values() if "moment" in d]), sf * size)
    for d in j.values():
        d["force"] = [snap(x, sf) for x in d["force"]]
        d["magnitude"] = snap(d["magnitude"], sf)
        if "normal" in d:
            d["normal"] = snap(d["normal"], sf)
        if "moment" in d:
            d["moment"] = snap(d["moment"], sm)
    dr = r.get("drive")
    if dr:
        eff = "torque" if "torque" in dr else "force"
        se = max(abs(dr[eff]), sm if eff == "torque" else sf)
        dr[eff] = snap(dr[eff], se)
        dr["power"] = snap(dr["power"], max(abs(dr["power"]), se * abs(res["input"]["velocity"])))
    if "transmission_deg" in r:
        r["transmission_deg"] = {k: v * degA for k, v in r["transmission_deg"].items()}
    if not units.is_si:
        r["units"] = {"length": units.length, "angle": units.angle,
                      "angular_speed": units.speed, "note": units.header()}
    return r


def _size(pts: dict) -> float:
    """The largest coordinate magnitude among the points, m (a couple's lever scale)."""
    return scale_of([d["position"] for d in pts.values()])


# ============================================================================ figures
#: The quantity kind of each curve figure of :func:`reports.case_figures.curve_figures`
#: (angles there are degrees), and of its axis by label.
FIGURE_KINDS = {"angle": "angle", "omega": "omega", "alpha": "alpha",
                "slider": "acceleration", "slider_s": "length", "drive": None,
                "forces": "force", "transmission": "angle"}


def _axis_kind(label: str) -> str | None:
    if label.startswith("input angle"):
        return "angle"
    if label.startswith("input ("):
        return "length"
    return None  # time (s)


def _factor(kind: str | None, units: DisplayUnits) -> float:
    if kind is None:
        return 1.0
    return units.A * math.pi / 180.0 if kind == "angle" else units.factor(kind)


def _relabel(label: str, kind: str | None, units: DisplayUnits) -> str:
    if kind is None or "(" not in label:
        return label
    return f"{label[:label.rindex('(')]}({units.unit(kind)})"


def convert_figure(fig, units: DisplayUnits):
    """A copy of a :class:`~reports.case_figures.CurveFigure` or ``ErrorFigure`` with its
    axes in ``units`` (values, markers, events, ranges and labels); an error figure's
    errors are ratios and stay as they are."""
    import dataclasses
    xk = _axis_kind(fig.xlabel)
    fx = _factor(xk, units)
    xl = _relabel(fig.xlabel, xk, units)
    if hasattr(fig, "panels"):  # ErrorFigure: only its axis converts
        panels = {e: {**p, "x": np.asarray(p["x"], float) * fx,
                      "worst": (p["worst"][0], p["worst"][1], p["worst"][2] * fx)}
                  for e, p in fig.panels.items()}
        return dataclasses.replace(fig, xlabel=xl, panels=panels)
    yk = FIGURE_KINDS.get(fig.name)
    fy = _factor(yk, units)
    curves = []
    for c in fig.curves:
        y = np.asarray(c.y, float) * fy
        mk = {e: (np.asarray(x, float) * fx, np.asarray(v, float) * fy, j)
              for e, (x, v, j) in c.markers.items()}
        curves.append(dataclasses.replace(c, x=np.asarray(c.x, float) * fx, y=y, markers=mk))
    scale = lambda r: None if r is None else (r[0] * fx, r[1] * fx)  # noqa: E731
    return dataclasses.replace(
        fig, xlabel=xl, ylabel=_relabel(fig.ylabel, yk, units), curves=curves,
        events=[(k, v * fx) for k, v in fig.events], feasible=scale(fig.feasible),
        covered=scale(fig.covered))


__all__ = ["ANGLES", "DisplayUnits", "KINDS", "LENGTHS", "NOISE", "SPEEDS", "UnitsError",
           "column_kind", "convert_frame", "convert_result", "scale_of", "snap", "text",
           "units_option", "UNITS_HELP", "convert_figure", "FIGURE_KINDS"]
