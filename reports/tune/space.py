"""What ``xval tune`` searches: per engine and mode, the knobs that can set the error or
the cost, each with a few coarse levels inside its settings class's accepted range
(:mod:`sim_models.engines.ranges`; a level outside it is refused by the settings class before
any run, so a stale level here shows as an error, never as a silent clip).

The step is every engine's first knob and is searched continuously (as steps per
revolution, prescribed, or per simulated second, free); the other knobs are discrete,
and a *family* is one level of each.  Levels are written as overrides of the engine's
recommended settings (the same dicts ``--set`` produces), so a candidate is a plain,
picklable dict that any worker or Dask node can run.
"""

from __future__ import annotations

from dataclasses import dataclass

from sim_models.builders.mjcf import HARD_SOLIMP

#: Pseudo-keys of the two solref knobs (time constant s, damping ratio), turned into
#: MuJoCo's direct ``solref`` by :func:`finalize` (two knobs, one setting).
SOLREF_TC, SOLREF_ZETA = "_solref_tc", "_solref_zeta"
#: The recommended direct solref's time constant and damping ratio (``direct_solref(1e-2)``).
SOLREF_DEFAULT = (1e-2, 1.0)
#: MuJoCo's own XML default impedance (softer than the project's near-hard one).
STOCK_SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)


@dataclass(frozen=True)
class Knob:
    """A discrete setting the search varies: ``name`` (in messages), ``levels`` (labels,
    the recommended level first), ``overrides`` (label -> settings overrides), ``why``
    (what it acts on, for the "error set by" line)."""

    name: str
    levels: tuple[str, ...]
    overrides: dict
    why: str = ""

    def apply(self, level: str) -> dict:
        return dict(self.overrides[level])


def _solref_tc(tcs, zeta: float = 1.0) -> Knob:
    """MuJoCo's loop stiffness as a direct solref ``(-1/tc^2, -2 zeta/tc)`` (the
    project's form: with the near-hard impedance it acts as a Baumgarte time constant)."""
    lv = {f"{tc:g} s": {SOLREF_TC: tc} for tc in tcs}
    return Knob("solref time constant", tuple(lv), lv, "the soft loop's time constant")


def _choice(name: str, field: str, values, why: str = "", fmt=str) -> Knob:
    lv = {fmt(v): {field: v} for v in values}
    return Knob(name, tuple(lv), lv, why)


def _mujoco_knobs(free: bool) -> tuple[Knob, ...]:
    damp = {f"{z:g}": {SOLREF_ZETA: z} for z in (1.0, 0.5, 2.0)}
    return (
        _choice("integrator", "integrator", ("RK4", "implicitfast", "Euler"),
                "the integration formula"),
        _solref_tc((1e-2, 2e-2, 3e-3, 1e-3)),
        Knob("solref damping ratio", tuple(damp), damp, "the soft loop's damping"),
        Knob("solimp", ("hard", "stock"), {"hard": {"solimp": HARD_SOLIMP},
                                           "stock": {"solimp": STOCK_SOLIMP}},
             "the loop's impedance (how soft the constraint is)"),
        _choice("solver tolerance", "tolerance", (1e-12, 1e-8, 1e-6),
                "the constraint solver's stopping rule", fmt=lambda v: f"{v:g}"),
        _choice("solver iterations", "iterations", (100, 20), "the constraint solver's "
                "iteration cap"),
    )


def _pybullet_knobs(free: bool) -> tuple[Knob, ...]:
    return (
        _choice("solver iterations", "solver_iterations", (20, 10, 50),
                "the sequential-impulse iterations"),
        _choice("ERP", "erp", (1.0, 0.2), "the loop's position correction",
                fmt=lambda v: f"{v:g}"),
        _choice("residual threshold", "residual_threshold", (1e-30, 1e-7),
                "the solver's early stop", fmt=lambda v: f"{v:g}"),
    )


def _exudyn_knobs(free: bool) -> tuple[Knob, ...]:
    return (
        _choice("spectral radius", "spectral_radius", (0.8, 0.6, 1.0),
                "the generalized-alpha damping", fmt=lambda v: f"{v:g}"),
        _choice("Newton tolerance", "newton_tolerance", (1e-10, 1e-6, 1e-8),
                "the Newton iterations' stop", fmt=lambda v: f"{v:g}"),
    )


def _pinocchio_knobs(free: bool) -> tuple[Knob, ...]:
    return (
        _choice("integrator", "integrator", ("rk4", "euler"), "the integration formula"),
        _choice("Baumgarte gain", "baumgarte", (0.05, 0.0, 0.2), "the loop's drift "
                "correction", fmt=lambda v: f"{v:g}"),
        _choice("constraint solver accuracy", "prox_accuracy", (1e-12, 1e-8),
                "the proximal solver's stop", fmt=lambda v: f"{v:g}"),
        _choice("constraint solver iterations", "prox_max_iter", (20, 5),
                "the proximal iteration cap"),
    )


def _warp_knobs(free: bool) -> tuple[Knob, ...]:
    return (
        _choice("solver iterations", "iterations", (100, 20) if not free else (1000, 100),
                "the constraint solver's iteration cap"),
        _choice("solver tolerance", "tolerance", (1e-10, 1e-6), "the solver's stop",
                fmt=lambda v: f"{v:g}"),
    )


KNOBS = {"mujoco": _mujoco_knobs, "pybullet": _pybullet_knobs, "exudyn": _exudyn_knobs,
         "pinocchio": _pinocchio_knobs, "mujoco_warp": _warp_knobs}


def engine_knobs(engine: str, free: bool, limit: int | None = None) -> tuple[Knob, ...]:
    """The discrete knobs of ``engine`` (``limit``: the first ``limit`` only, for
    measuring how the search grows with the knobs); () for an engine with none."""
    make = KNOBS.get(engine)
    knobs = make(free) if make else ()
    return knobs if limit is None else knobs[:limit]


def finalize(overrides: dict) -> dict:
    """``overrides`` with the solref knobs' pseudo-keys made into ``solref``."""
    out = dict(overrides)
    if SOLREF_TC in out or SOLREF_ZETA in out:
        tc = float(out.pop(SOLREF_TC, SOLREF_DEFAULT[0]))
        z = float(out.pop(SOLREF_ZETA, SOLREF_DEFAULT[1]))
        out["solref"] = (-1.0 / tc ** 2, -2.0 * z / tc)
    return out


def steps_overrides(engine: str, steps: float, unit_time: float, fields) -> dict:
    """The overrides giving ``steps`` steps per ``unit_time`` seconds (one revolution,
    or one simulated second): ``timestep`` and, where the engine has it,
    ``steps_per_rev`` (Exudyn, Pinocchio, MuJoCo Warp take the smaller step)."""
    n = max(1, int(round(steps)))
    out: dict = {"timestep": unit_time / n}
    if "steps_per_rev" in fields:
        out["steps_per_rev"] = n
    return out


__all__ = ["KNOBS", "Knob", "SOLREF_TC", "SOLREF_ZETA", "STOCK_SOLIMP", "engine_knobs",
           "finalize", "steps_overrides"]
