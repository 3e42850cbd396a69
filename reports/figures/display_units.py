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
scale in its own row (:func:`row_scales`: the largest magnitude of the same kind in the
same row, a turn for an angle; never a value of another row) is shown as 0, and a zero
never carries a sign (:func:`snap`, :func:`text`).  One rule for ``xval solve`` and every
row of ``xval sweep --csv``, in memory or streamed (:func:`snap_rows`).
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


#: Quantity kinds (what :meth:`DisplayUnits.factor` and ``unit`` know).
KINDS = ("length", "velocity", "acceleration", "angle", "omega", "alpha", "force",
         "moment", "power", "time", "ratio")


def snap(values, scale: float):
    """``values`` with magnitudes below :data:`NOISE` x ``scale`` set to 0 and no
    negative zero (arrays or scalars; NaN stays NaN)."""
    v = np.asarray(values, float)
    out = np.where(np.abs(v) < NOISE * scale, 0.0, v) + 0.0  # + 0.0: -0.0 -> 0.0
    return float(out) if np.ndim(out) == 0 else out


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
            "fy": "force", "normal": "force", "magnitude": "force"}.get(last, "ratio")


#: Columns that hold the input itself (the value solved at and its rates): shown exactly
#: as solved, never snapped (a row's printed input reproduces the row).
INPUT_COLUMNS = ("input", "input_velocity", "input_acceleration")
#: Quantity kinds never snapped: diagnostics, codes and ratios are shown as computed.
UNSNAPPED = ("residual", "status", "ratio")


def row_scales(cols: dict, revolute: bool) -> dict[str, np.ndarray]:
    """The round-off scale of each quantity kind, row by row (``(N,)`` each; SI, angles
    in deg): what a row and a quantity justify, never another row's values.

    * an angle: a turn (360 deg);
    * a length, velocity, acceleration, angular rate or force: the largest finite
      magnitude of that kind in the same row (the input's own value left out), and for
      the rates at least what the row's motion implies with its largest coordinate ``L``
      as lever: a velocity ``omega L``, an angular rate ``v / L``, an angular
      acceleration ``omega^2`` and ``a / L``, an acceleration ``alpha L``;
    * a moment (joint couple, drive torque): that, or the row's force scale times its
      largest coordinate (the lever of the forces, m) when larger;
    * the drive power: that, or the drive effort's scale times the input rate.

    ``cols`` maps column names of the sweep table (:mod:`analytic.sweep`;
    :func:`column_kind`) to arrays of the same length (one element: ``xval solve``)."""
    kinds = {c: column_kind(c, revolute) for c in cols}
    n = len(np.atleast_1d(next(iter(cols.values())))) if cols else 0

    def peak(kind):
        m = np.zeros(n)
        for c, k in kinds.items():
            if k == kind and c != "input":
                a = np.abs(np.atleast_1d(np.asarray(cols[c], float)))
                m = np.fmax(m, np.where(np.isfinite(a), a, 0.0))
        return m
    sc = {k: peak(k) for k in ("length", "velocity", "acceleration", "omega", "alpha",
                               "force")}
    # the row's motion sets the kinematic scales even where every value of a kind is
    # round-off (a rod's alpha at a dead centre: 4e-12 rad/s^2 at 200 rad/s)
    lever = np.where(sc["length"] > 0, sc["length"], np.inf)
    sc["velocity"] = np.maximum(sc["velocity"], sc["omega"] * sc["length"])
    sc["omega"] = np.maximum(sc["omega"], sc["velocity"] / lever)
    sc["alpha"] = np.maximum.reduce([sc["alpha"], sc["omega"] ** 2,
                                     sc["acceleration"] / lever])
    sc["acceleration"] = np.maximum(sc["acceleration"], sc["alpha"] * sc["length"])
    sc["angle"] = np.full(n, 360.0)
    sc["moment"] = np.maximum(peak("moment"), sc["force"] * sc["length"])
    rate = np.abs(np.atleast_1d(np.asarray(cols.get("input_velocity", 0.0), float)))
    effort = sc["moment"] if revolute else sc["force"]
    sc["power"] = np.maximum(peak("power"), effort * np.where(np.isfinite(rate), rate, 0.0))
    return sc


def snap_rows(cols: dict, revolute: bool) -> dict[str, np.ndarray]:
    """``cols`` (SI, angles in deg; see :func:`row_scales`) with round-off noise set to
    0: a value below :data:`NOISE` of its own row's scale of its kind.  The one rule of
    ``xval solve`` and of the sweep table, in memory or streamed block by block (a row
    is snapped from its own values only, so the block size changes no cell).  The
    input columns, ratios, residuals and codes are left as computed (a zero loses its
    sign)."""
    scales = row_scales(cols, revolute)
    out = {}
    for c, v in cols.items():
        k = column_kind(c, revolute)
        if k == "status":
            out[c] = v
        elif c in INPUT_COLUMNS or k not in scales:
            out[c] = np.asarray(v, float) + 0.0  # + 0.0: -0.0 -> 0.0
        else:
            out[c] = snap(np.atleast_1d(np.asarray(v, float)), scales[k])
    return out


def _angle_factor(units: DisplayUnits) -> float:
    """deg -> ``units.angle``: exactly 1 for degrees, pi/180 for radians (the factor
    :func:`numpy.radians` uses, so an input printed in rad is the value solved at)."""
    return 1.0 if units.angle == "deg" else units.A * math.pi / 180.0


def column_name(col: str, units: DisplayUnits, revolute: bool) -> str:
    """The CSV name of a sweep-table column: the quantity, then its unit in brackets
    (``crank.angle [deg]``, ``crank.omega [rad/s]``, ``O2.fx [N]``,
    ``jacobian_condition [-]``), whatever the units; ``singular`` (a code) has none."""
    kind = column_kind(col, revolute)
    base = col.replace(".angle_deg", ".angle").replace("transmission_deg", "transmission")
    return base if kind == "status" else f"{base} [{units.unit(kind)}]"


def convert_frame(frame, units: DisplayUnits, revolute: bool):
    """The sweep table in ``units``, round-off noise snapped to 0 row by row
    (:func:`snap_rows`), each column named with its unit (:func:`column_name`).  Angle
    columns come in degrees and leave in ``units.angle``."""
    snapped = snap_rows({c: frame[c].to_numpy() for c in frame.columns}, revolute)
    out = frame.copy()
    for c in frame.columns:
        kind = column_kind(c, revolute)
        if kind == "status":
            continue
        f = _angle_factor(units) if kind == "angle" else units.factor(kind)
        out[c] = snapped[c] * f if f != 1.0 else snapped[c]
    out.columns = [column_name(c, units, revolute) for c in frame.columns]
    return out


# ============================================================================ solve result
def _flatten(r: dict) -> dict:
    """The quantities of an ``xval solve`` result under the sweep table's column names."""
    cols = {"input_velocity": r["input"]["velocity"]}
    for b, d in r["bodies"].items():
        cols.update({f"{b}.angle_deg": d["angle_deg"], f"{b}.omega": d["omega"],
                     f"{b}.alpha": d["alpha"]})
    for p, d in r["points"].items():
        for key, (cx, cy) in (("position", ("x", "y")), ("velocity", ("vx", "vy")),
                              ("acceleration", ("ax", "ay"))):
            cols[f"{p}.{cx}"], cols[f"{p}.{cy}"] = d[key]
    for j, d in r["sliders"].items():
        cols.update({f"{j}.{k}": d[k] for k in ("s", "v", "a")})
    for j, d in r["joints"].items():
        cols[f"{j}.fx"], cols[f"{j}.fy"] = d["force"]
        cols[f"{j}.magnitude"] = d["magnitude"]
        for k in ("normal", "moment"):
            if k in d:
                cols[f"{j}.{k}"] = d[k]
    dr = r.get("drive")
    if dr:
        for k in ("torque", "force", "power"):
            if k in dr:
                cols[f"drive.{k}"] = dr[k]
    for k, v in r.get("transmission_deg", {}).items():
        cols[f"transmission_deg.{k}"] = v
    return {k: np.array([v], float) for k, v in cols.items()}


def convert_result(res: dict, units: DisplayUnits) -> dict:
    """The ``xval solve`` result dict (SI, angles in deg; see :mod:`reports.cli.xval`) in
    ``units``, round-off noise snapped by the sweep table's rule (:func:`snap_rows`:
    the same numbers as the sweep's row at that input), with a ``units`` entry when
    not the default.  Keys are unchanged (``angle_deg`` holds the angle in
    ``units.angle``)."""
    import copy
    r = copy.deepcopy(res)
    inp = r["input"]
    rev = "angle_deg" in inp
    s = {k: float(v[0]) for k, v in snap_rows(_flatten(res), rev).items()}
    degA, L, W = _angle_factor(units), units.L, units.W
    if rev:
        inp["angle_deg"] = inp["angle_deg"] * degA + 0.0
        inp["velocity"] = inp["velocity"] * W + 0.0
    else:
        inp["s"] = inp["s"] * L + 0.0
        inp["velocity"] = inp["velocity"] * L + 0.0
        inp["acceleration"] = inp["acceleration"] * L + 0.0
    for b, d in r["bodies"].items():
        d["angle_deg"] = s[f"{b}.angle_deg"] * degA
        d["omega"] = s[f"{b}.omega"] * W
        d["alpha"] = s[f"{b}.alpha"]
    for p, d in r["points"].items():
        d["position"] = [s[f"{p}.x"] * L, s[f"{p}.y"] * L]
        d["velocity"] = [s[f"{p}.vx"] * L, s[f"{p}.vy"] * L]
        d["acceleration"] = [s[f"{p}.ax"] * L, s[f"{p}.ay"] * L]
    for j, d in r["sliders"].items():
        for k in ("s", "v", "a"):
            d[k] = s[f"{j}.{k}"] * L
    for j, d in r["joints"].items():
        d["force"] = [s[f"{j}.fx"], s[f"{j}.fy"]]
        for k in ("magnitude", "normal", "moment"):
            if k in d:
                d[k] = s[f"{j}.{k}"]
    dr = r.get("drive")
    if dr:
        for k in ("torque", "force", "power"):
            if k in dr:
                dr[k] = s[f"drive.{k}"]
    if "transmission_deg" in r:
        r["transmission_deg"] = {k: s[f"transmission_deg.{k}"] * degA
                                 for k in r["transmission_deg"]}
    if not units.is_si:
        r["units"] = {"length": units.length, "angle": units.angle,
                      "angular_speed": units.speed, "note": units.header()}
    return r


# ============================================================================ figures
#: The quantity kind of each curve figure of :func:`reports.figures.case_figures.curve_figures`
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
    """A copy of a :class:`~reports.figures.case_figures.CurveFigure` or ``ErrorFigure`` with its
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
           "column_kind", "column_name", "convert_frame", "convert_result", "row_scales",
           "snap", "snap_rows", "text",
           "convert_figure", "FIGURE_KINDS"]
