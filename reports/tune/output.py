"""What ``xval tune`` prints and writes: the summary lines, the Pareto table, the figure,
the settings file and the tuned MJCF of a :class:`reports.tune.tune.TuneResult`."""

from __future__ import annotations

import math
from pathlib import Path

from reports.tune.search import COST_MATTERS, ERROR_MATTERS, Point
from reports.tune.tune import TuneResult


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, tuple):
        return "(" + ",".join(_fmt(x) for x in v) + ")"
    return str(v)


def mode_text(res: TuneResult) -> str:
    c = res.case
    return f"free motion, {c.duration:g} s" if c.free and c.duration else \
        ("free motion" if c.free else "prescribed")


def point_row(res: TuneResult, p: Point) -> list[str]:
    """A table row: the knobs' levels, steps per unit, model cost, worst error, pass."""
    cost = res.cost(p)
    return [*p.family, f"{p.steps}", f"{cost * 1e3:.3g}" if math.isfinite(cost) else "-",
            f"{p.error:.2g}", "pass" if p.passed else "fail"]


def table(res: TuneResult, points: list[Point]) -> str:
    unit = "rev" if not res.case.free else "sim s"
    head = [k.name for k in res.tuner.knobs] + [f"steps/{unit}", f"ms CPU/{unit} (model)",
                                                "worst error", "verdict"]
    rows = [head] + [point_row(res, p) for p in points]
    w = [max(len(r[i]) for r in rows) for i in range(len(head))]
    return "\n".join("  " + "  ".join(c.rjust(w[i]) for i, c in enumerate(r)) for r in rows)


def summary_lines(res: TuneResult) -> list[str]:
    """The lines ``xval tune`` prints (see :mod:`reports.cli.tune`)."""
    s, t = res.search, res.tuner
    fam = res.family or "all judged quantities"
    of = "of its scale" if res.case.free else "of peak"
    out = [f"== tune {s_case(res)} / {res.engine} ({mode_text(res)}): tolerance "
           f"{res.tolerance:g} {of} on {fam}"]
    knobs = ", ".join(["step"] + [k.name for k in t.knobs])
    out.append(f"search: {s.runs} runs, {s.spent:.3g} s CPU of a {res.budget:g} s budget"
               f"{' (spent: stopped)' if s.budget_hit else ''}, {res.search_wall:.3g} s "
               f"wall; knobs: {knobs}")
    if s.not_mattering:
        out.append(f"stopped mattering (screened: at equal steps each level moves the error "
                   f"less than {ERROR_MATTERS:g}x and the step's CPU less than "
                   f"{COST_MATTERS - 1:.0%}; not refined): "
                   f"{', '.join(s.not_mattering)}")
    if s.not_tried:
        out.append(f"not tried (the budget was spent first): {', '.join(s.not_tried)}")
    if res.answer is None:
        out.append(f"NO SETTING PASSES: {res.limit_text}")
        return out
    ch = ", ".join(f"{k} {_fmt(a)} -> {_fmt(b)}" for k, (a, b) in res.changed.items()) \
        or "none (the recommended settings are the cheapest found)"
    out.append(f"answer: {res.answer.steps} steps per "
               f"{'simulated s' if res.case.free else 'revolution'}; changed: {ch}")
    out.append(f"settings: {res.settings.describe()}")
    if res.verification is not None:
        v = res.verification
        word = "PASS" if res.passed else "FAIL"
        reason = "" if v.ok else f" (run failed: {v.reason})"
        of = "of its scale" if res.case.free else "of peak"
        out.append(f"verification (a fresh run): {word}, worst {res.verify_quantity} "
                   f"{res.verify_error:.3g} {of} (tolerance {res.tolerance:g}){reason}")
        u = "simulated s" if res.case.free else "revolution"
        out.append(f"CPU: {res.cpu_tuned * 1e3:.3g} ms per {u} (process CPU of the run), "
                   f"recommended {res.cpu_recommended * 1e3:.3g} ms: ratio "
                   f"{res.cpu_ratio:.3g} (medians of 3 alternated runs each in one process; "
                   f"spread {res.cpu_spread:.0%})")
        if res.recommended is not None:
            a, r = res.cost(res.answer), res.cost(res.recommended)
            out.append(f"stepping only (cost model, steps x per-step CPU of the bare loop): "
                       f"{a * 1e3:.3g} ms against {r * 1e3:.3g} ms, ratio {a / r:.3g}")
    out.append(f"knob: {res.knob_text}")
    return out


def s_case(res: TuneResult) -> str:
    return Path(res.case.case).name if "/" in res.case.case else res.case.case


def full_text(res: TuneResult) -> str:
    lines = summary_lines(res)
    if res.front:
        lines += ["Pareto front (no cheaper run has a lower error; model cost = steps x "
                  "per-step CPU of the bare loop):", table(res, res.front[:12])]
        lines += _answer_off_front(res)
    if res.alternatives:
        lines += ["next-cheapest passing alternatives (other knob levels):",
                  table(res, res.alternatives)]
    return "\n".join(lines)


def _answer_off_front(res: TuneResult) -> list[str]:
    """Why the answer is not a row of the front, when it is not: a cheaper passing run
    on the front lies within the cost tie (timing noise cannot order the two), and the
    answer was preferred for fewer steps or fewer knobs moved (:meth:`Tuner.best`)."""
    from reports.tune.search import COST_TIE
    if res.answer is None or any(p is res.answer for p in res.front):
        return []
    passing = [p for p in res.front if p.passed]
    if not passing:
        return []
    cheap = min(passing, key=res.cost)
    return [f"the answer is not on the front: its model cost "
            f"{res.cost(res.answer) * 1e3:.3g} ms is within {COST_TIE - 1:.0%} of the "
            f"front's cheapest passing run ({res.cost(cheap) * 1e3:.3g} ms), which timing "
            "noise cannot order; among such runs the answer takes the fewest steps, then "
            "the fewest knobs moved"]


def figure(res: TuneResult) -> bytes:
    """Model cost against worst error of every finished run, the front, the tolerance
    and the answer (PNG bytes)."""
    import matplotlib
    matplotlib.use("Agg")
    import io

    import matplotlib.pyplot as plt
    pts = [p for p in res.search.points.values()
           if p.m.ok and math.isfinite(p.error) and p.error > 0 and
           math.isfinite(res.cost(p))]
    fig, ax = plt.subplots(figsize=(7.4, 4.6))
    for passed, col in ((False, "tab:gray"), (True, "tab:blue")):
        sel = [p for p in pts if p.passed == passed]
        ax.scatter([res.cost(p) * 1e3 for p in sel], [p.error for p in sel], s=14, c=col,
                   label="passes" if passed else "fails", alpha=0.7)
    fr = [p for p in res.front if p.error > 0]
    ax.step([res.cost(p) * 1e3 for p in fr], [p.error for p in fr], where="post",
            color="tab:red", lw=1, label="Pareto front")
    ax.axhline(res.tolerance, color="k", ls="--", lw=0.8, label=f"tolerance {res.tolerance:g}")
    if res.answer is not None:
        ax.scatter([res.cost(res.answer) * 1e3], [res.answer.error], marker="*", s=160,
                   c="tab:red", zorder=5, label="answer")
    ax.set_xscale("log")
    ax.set_yscale("log")
    unit = "simulated s" if res.case.free else "revolution"
    ax.set_xlabel(f"model CPU per {unit}, ms (steps x per-step CPU)")
    ax.set_ylabel("worst normalised error")
    ax.set_title(f"xval tune {s_case(res)} / {res.engine} ({mode_text(res)})", fontsize=10)
    ax.legend(fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=150, bbox_inches="tight")
    plt.close(fig)
    return buf.getvalue()


# ============================================================================ --json
def _levels(res: TuneResult, p: Point) -> dict:
    return {k.name: lv for k, lv in zip(res.tuner.knobs, p.family, strict=True)}


def _candidate(res: TuneResult, p: Point, front: set) -> dict:
    return {"levels": _levels(res, p), "steps_per_unit": p.steps, "error": p.error,
            "worst_quantity": p.worst_quantity, "passed": p.passed, "run_ok": p.m.ok,
            "reason": p.m.reason, "model_cost_s": res.cost(p),
            "run_cpu_s": p.m.cpu / p.m.units if p.m.units else None,
            "on_front": id(p) in front, "answer": p is res.answer}


def _jsonable(v):
    return list(v) if isinstance(v, tuple) else v


def json_document(res: TuneResult, files: dict | None = None) -> dict:
    """The ``--json`` object of a result (its keys: :data:`reports.cli.tune.JSON_KEYS`,
    the command's help)."""
    from reports.comparison.compare import json_safe
    s, a, c = res.search, res.answer, res.case
    front = {id(p) for p in res.front}
    pts = sorted(s.points.values(), key=lambda p: (res.cost(p), p.error))
    answer = None if a is None else {
        "levels": _levels(res, a), "steps_per_unit": a.steps, "error": a.error,
        "worst_quantity": a.worst_quantity, "model_cost_s": res.cost(a),
        "changed": {k: [_jsonable(x), _jsonable(y)] for k, (x, y) in res.changed.items()},
        "settings": res.settings.describe()}
    ver = None
    if res.verification is not None:
        v = res.verification
        step = res.cost(a) / res.cost(res.recommended) if res.recommended else None
        ver = {"passed": res.passed, "error": res.verify_error,
               "quantity": res.verify_quantity, "run_ok": v.ok, "reason": v.reason,
               "cpu_s": res.cpu_tuned, "recommended_cpu_s": res.cpu_recommended,
               "cpu_ratio": res.cpu_ratio, "cpu_spread": res.cpu_spread,
               "stepping_only_ratio": step}
    return json_safe({
        "case": c.case, "engine": res.engine, "mode": "free" if c.free else "prescribed",
        "duration_s": c.duration, "unit": res.unit, "tolerance": res.tolerance,
        "quantity": res.family or "all", "budget_s": res.budget, "seed": res.seed,
        "passed": res.passed, "answer": answer, "verification": ver,
        "knob": res.knob_text or None, "limit": res.limit_text or None,
        "search": {"runs": s.runs, "cpu_s": s.spent, "wall_s": res.search_wall,
                   "budget_hit": s.budget_hit,
                   "knobs": ["step"] + [k.name for k in res.tuner.knobs],
                   "stopped_mattering": list(s.not_mattering),
                   "not_tried": list(s.not_tried)},
        "candidates": [_candidate(res, p, front) for p in pts],
        "files": files or {}})


def tuned_document(res: TuneResult) -> dict:
    """What the settings file records about the search (its ``tuned`` object)."""
    return {"case": res.case.case, "free": res.case.free, "duration_s": res.case.duration,
            "tolerance": res.tolerance, "quantity": res.family or "all",
            "verified": res.passed, "verify_error": res.verify_error,
            "verify_quantity": res.verify_quantity, "cpu_ratio": res.cpu_ratio,
            "knob": res.knob_text, "budget_s": res.budget, "seed": res.seed,
            "runs": res.search.runs}


def write_settings(res: TuneResult, path: str) -> None:
    from reports.comparison.settings_file import write_settings_file
    tuned = {k: (v if not (isinstance(v, float) and not math.isfinite(v)) else None)
             for k, v in tuned_document(res).items()}
    write_settings_file(path, {res.engine: res.settings}, "free" if res.case.free else "run",
                        tuned)


def model_text(res: TuneResult) -> tuple[str, list]:
    """The tuned MJCF of the case's own model (MuJoCo; :mod:`reports.tune.model`)."""
    of = "of its scale" if res.case.free else "of peak"
    header = (f"case {s_case(res)} ({mode_text(res)}), tolerance {res.tolerance:g} {of}, "
              f"verified {'PASS' if res.passed else 'FAIL'} at {res.verify_error:.3g}.")
    if res.case.own:  # the user's file, only the tuned attributes changed
        from reports.tune.own import tuned_text
        new = {k: v for k, (_old, v) in res.changed.items()}
        return tuned_text(res.case, new, {k: _why(res, k) for k in new}, header)
    from reports.tune.measure import free_reference, prescribed_tree
    from reports.tune.model import tuned_model_text
    from sim_models.builders.mjcf import MujocoSettings
    from sim_models.builders.viewer_model import viewer_xml
    mech = free_reference(res.case.case, res.case.duration)[0] if res.case.free else \
        prescribed_tree(res.case.case).mech
    base = MujocoSettings()
    new = {k: getattr(res.settings, k) for k in res.settings.as_dict()
           if hasattr(base, k) and getattr(base, k) != getattr(res.settings, k)}
    why = {k: _why(res, k) for k in new}
    not_mjcf = {"invweight_scale": getattr(res.settings, "invweight_scale",
                                           base.invweight_scale)}
    return tuned_model_text(viewer_xml(mech, base), new, why, not_mjcf, header)


def _why(res: TuneResult, fld: str) -> str:
    """Why a setting changed: the knob that moved it and what the answer measured."""
    t, a = res.tuner, res.answer
    if fld == "timestep":
        of = "of its scale" if res.case.free else "of peak"
        return (f"the step: {a.steps} steps per "
                f"{'simulated s' if res.case.free else 'revolution'}, the least that passes "
                f"{res.tolerance:g} {of} in this family (verified {res.verify_error:.3g})")
    moved = [f"{k.name} {k.levels[0]} -> {lv}" for k, lv in zip(t.knobs, a.family, strict=True)
             if lv != k.levels[0] and any(f in k.apply(lv) or f == "solref" and
                                          any(x.startswith("_solref") for x in k.apply(lv))
                                          for f in (fld,))]
    return (f"knob {'; '.join(moved)}: the cheapest passing family found "
            f"(verified {res.verify_error:.3g})") if moved else "tuned"


__all__ = ["figure", "full_text", "json_document", "model_text",
           "summary_lines", "table", "tuned_document", "write_settings"]
