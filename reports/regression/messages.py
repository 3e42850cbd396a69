"""What a baseline check says, as lines of text: ``xval baseline check``'s report and the
pytest plugin's failure text both print them (:mod:`reports.regression.baseline` holds the checks).
"""

from __future__ import annotations

import math
from collections import Counter

from reports.regression import baseline as bl


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
            if w and c.record.free:
                worst += "; trusted horizon " + _horizon_text(c)
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


__all__ = ["report_lines", "versions_line"]
