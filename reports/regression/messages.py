"""What a baseline check says, as lines of text: ``xval baseline check``'s report and the
pytest plugin's failure text both print them (:mod:`reports.regression.baseline_check`
holds the checks); and the failure message of the plugin's ``assert_agrees``
(:func:`disagreement`).
"""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path

from analytic.input_display import format_input  # the one input convention
from reports.regression import baseline as bl
from reports.regression.baseline_check import severity
from reports.regression.baseline_record import record_command


def report_lines(base: bl.Baseline, checks, factor: float) -> list[str]:
    """What ``xval baseline check`` prints: a header, the versions that changed, one line
    per run, and under each failed run every failing quantity, its settings and versions."""
    failed = [c for c in checks if not c.passed]
    out = [f"baseline {base.path}: {len(checks)} runs (recorded {base.recorded or '?'}); "
           f"drift factor {factor:g}, floor {bl.DRIFT_FLOOR:g} of peak",
           versions_line(checks)]
    for c in checks:
        w = c.worst()
        if c.passed:
            ratio = f", {w.ratio:.3g}x" if w and math.isfinite(w.ratio) else ""
            worst = f"worst {w.quantity} {w.error:.3g} {w.scale_word} (baseline " \
                    f"{w.base:.3g}{ratio})" if w else "nothing compared"
            if c.record.free:  # a pass here is "no drift", not the free verdict
                worst = "no drift from the recorded run: " + worst
                if w:
                    worst += "; trusted horizon " + _horizon_text(c) + _free_verdict(c)
            out.append(f"pass  {c.record.label}: {worst}")
            continue
        first = c.problems[0] if c.problems else c.failures()[0].message()
        out.append(f"FAIL  {c.record.label}: {first}")
        rest = c.problems[1:] + [q.message() for q in c.failures()][0 if c.problems else 1:]
        out += [f"        {m}" for m in rest]
        if c.settings_text:
            out.append(f"        settings: {c.settings_text}")
        ch = c.versions_changed()
        if ch:
            out.append("        versions changed: " +
                       ", ".join(f"{k} {a} -> {b}" for k, (a, b) in ch.items()))
    for c in checks:
        out += [f"warning: {c.record.label}: {q.message()}" for q in c.loose()]
    for c in checks:
        out += [f"note: {c.record.label}: {q.message()}" for q in c.quantities
                if q.status == "new"]
        out += [f"note: {c.record.label}: {n}" for n in c.notes]
    out.append(f"result: {'FAIL' if failed else 'PASS'}: {len(failed)} of {len(checks)} "
               "runs failed" + (" (drift, tolerance, or a run, quantity or model gone or "
                                "changed)" if failed else ""))
    return out


def _free_verdict(c) -> str:
    """A free run's verdict against the exact trajectory, beside a drift check's pass:
    a run recorded while it fails its tolerances (a first-order engine that loses the
    trajectory) passes the drift check when it fails no more than recorded, and the
    line says that its verdict still fails."""
    over = [q for q in c.quantities if math.isfinite(q.error) and q.error > q.tolerance]
    if not over:
        return "; verdict against the exact trajectory: pass"
    w = max(over, key=lambda q: q.error / q.tolerance)
    return (f"; verdict against the exact trajectory: FAIL, as recorded ({len(over)} "
            f"quantities over their tolerance, worst {w.quantity} {w.error:.3g} of range > "
            f"{w.tolerance:g})")


def _horizon_text(c) -> str:
    """A free run's trusted horizon now and recorded (the earliest of its quantities)."""
    now = min((q.horizon for q in c.quantities if math.isfinite(q.error)), default=math.nan)
    rec = min((q.horizon for q in c.record.quantities), default=math.nan)

    def t(h):
        return "whole run" if math.isinf(h) else f"{h:.4g} s"
    return f"{t(now)} (recorded {t(rec)})"


def versions_line(checks) -> str:
    """Versions that differ from the recorded ones, with how many runs each affects."""
    changed: Counter = Counter()
    for c in checks:
        for k, (a, b) in c.versions_changed().items():
            changed[(k, a, b)] += 1
    if not changed:
        return "versions: unchanged since the baseline"
    return "versions changed since the baseline: " + "; ".join(
        f"{k} {a} -> {b} ({n} runs)" for (k, a, b), n in sorted(changed.items()))


def _at_text(run_, at: float) -> str:
    if not math.isfinite(at):
        return "at an unreached sample"
    return f"at input {format_input(at, 'm' if run_.extra.get('prismatic_driver') else 'deg')}"


def _unit(quantity: str, run_) -> str:
    """SI unit of a compared quantity (see :func:`reports.comparison.compare.compare_run`)."""
    kind = quantity.rsplit(".", 1)[-1]
    if kind == "alpha":
        return "rad/s^2"
    if kind == "a":
        return "m/s^2"
    if kind == "effort":
        return "N" if run_.extra.get("prismatic_driver") else "N m"
    return "N"


def disagreement(label: str, run_, comps, tolerance: float, settings_text: str) -> str:
    """The failure message of :meth:`reports.regression.pytest_plugin.Xval.assert_agrees`:
    every failing quantity with its error (relative to peak and absolute), where in the
    cycle, then the settings."""
    bad = sorted((c for c in comps if not c.accepted),
                 key=lambda c: c.normalised if math.isfinite(c.normalised) else math.inf,
                 reverse=True)
    lines = [f"{label}: {len(bad)} of {len(comps)} quantities disagree with the analytic "
             f"solution by more than {tolerance:g} of peak"]
    if not run_.ok:
        lines.append(f"  the run failed: {run_.reason}")
    for c in bad:
        unit = _unit(c.quantity, run_)
        lines.append(f"  {c.quantity}: error {c.normalised:.3g} of peak {_at_text(run_, c.at)}"
                     f" (max |error| {c.max_abs:.4g} {unit}, peak {c.peak:.4g} {unit})")
    lines.append(f"  settings: {settings_text}")
    req = run_.request
    lines.append(f"  run: {req.revolutions} revolutions, {req.samples} samples"
                 + (" by time" if run_.by_time else " of the last revolution"))
    return "\n".join(lines)


def failure_text(base, checks, factor: float, root: Path) -> str:
    """An ``assert_baseline`` failure: first line the worst failing quantity (its growth,
    the factor and where) or the run's problem, then the check's report of the failed
    runs, then how to record them again."""
    failed = [c for c in checks if not c.passed]
    worst = max(failed, key=lambda c: (not c.problems, *(_sev(c))))
    first = worst.problems[0] if worst.problems else worst.failures()[0].message()
    lines = report_lines(base, checks, factor)
    keep = [ln for ln in lines if not ln.startswith("pass ")]
    again = bl.Baseline(tuple(c.record for c in failed), base.path, base.recorded)
    return "\n".join([f"{worst.record.label}: {first}", *keep,
                      "if the change is intended, record again: pytest --xval-update, or "
                      f"(from {root}): {record_command(again, root)}"])


def _sev(c) -> tuple:
    f = c.failures()
    return severity(f[0]) if f else (0, 0.0)


__all__ = ["disagreement", "failure_text", "report_lines", "versions_line"]
