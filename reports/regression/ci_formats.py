"""Verdicts in the formats CI systems read: JUnit XML and a Markdown job summary.

One :class:`CiCase` per (case, engine), built from ``xval compare``'s results
(:func:`from_compare`) or from ``xval baseline check``'s (:func:`from_baseline`).

JUnit XML (the Ant/Jenkins layout that Jenkins, GitLab, GitHub actions' test reporters,
Azure Pipelines and CircleCI read; valid against the Jenkins xunit plugin's
``junit-10.xsd``, which allows ``file`` on ``testsuite`` but not on ``testcase``)::

    <testsuites name=... tests= failures= errors= time=>
      <testsuite name=... file="<model path>" tests= failures= errors= skipped="0" time=
                 timestamp= hostname=>                   (one per model file)
        <properties><property name="python" value="3.11.2"/>
          <property name="linkage-xval" .../><property name="engine.mujoco" value=
          "mujoco 3.3.7"/>...</properties>
        <testcase classname="xval.<command>.<engine>" name="<case>" time="<s>">
          <failure message="<worst quantity, its error, where>" type="tolerance|drift|...">
            every quantity, the settings</failure>          (a failed verdict)
          <error message=... type="refused">...</error>      (the run could not be judged)
          <system-out>worst error now, settings and notes (a precision limit: a passing
                      testcase whose output starts "precision limit (float32): ...")</system-out>
        </testcase> ...

``<command>`` is ``compare`` or ``baseline``, so the two commands' results uploaded from
one job never share a test name (GitLab drops duplicates).

``time`` attributes are seconds with a decimal point (the schema's ``xs:decimal``: no
exponent).  The Markdown summary is one table, worst first, for a CI job summary page.
"""

from __future__ import annotations

import datetime as _dt
import math
import os
import platform
import socket
import sys
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from analytic.errors import OutputError
from analytic.input_display import format_input  # the one input convention of every output
from analytic.mechanism import Prismatic
from reports.comparison.compare import limit_word
from reports.regression.baseline import versions


@dataclass(frozen=True)
class CiCase:
    """One (case, engine) verdict.

    ``status``: "pass", "limit" (over the tolerance but within the engine's arithmetic
    floor: a precision limit, not a failure; ``kind`` says "precision limit (float32)"),
    "fail" (a failed verdict) or "error" (the run could not be judged: refused, nothing
    to compare, model gone).  ``quantity``/``error``/``at``:
    the quantity named first (the worst failing one, else the largest error), its error
    relative to peak and where (text with unit).  ``kind``: why it failed ("tolerance",
    "drift", "missing", "run failed", "model changed", ...).  ``message``: one line;
    ``details``: the full listing."""

    case: str
    engine: str
    status: str
    quantity: str = ""
    error: float = math.nan
    at: str = ""
    tolerance: float = math.nan
    baseline: float = math.nan
    kind: str = ""
    message: str = ""
    details: str = ""
    settings: str = ""
    time: float = 0.0
    notes: tuple[str, ...] = field(default_factory=tuple)
    file: str = ""           # the model file (path as given / relative to the cwd)
    version: str = ""        # the engine's version, e.g. "mujoco 3.3.7"

    def worst_line(self) -> str:
        """The worst error now (for passing cases too), with its limit."""
        if not self.quantity:
            return "worst: nothing compared"
        base = f", baseline {self.baseline:.3g}" if math.isfinite(self.baseline) else ""
        return f"worst: {self.quantity} error {self.error:.3g} of peak" + \
            (f" at {self.at}" if self.at else "") + f" (tolerance {self.tolerance:g}{base})"


# ============================================================================ builders
def _at(value: float, unit: str) -> str:
    return format_input(value, unit)


def from_compare(case: str, results, revolute: bool, file: str = "") -> list[CiCase]:
    """``xval compare``'s verdicts (:class:`reports.comparison.runs.Verdict`; ``file``: the
    model file, empty for a built-in case)."""
    unit = "deg" if revolute else "m"
    out = []
    for v in results:
        r, comps, ok = v.run, v.comparisons, v.ok
        judged = v.judged()
        bad = [c for c in judged if not c.accepted]
        limited = [c for c in judged if c.limited]
        pool = bad or judged
        worst = max(pool, key=lambda c: c.normalised if math.isfinite(c.normalised)
                    else math.inf, default=None)
        kind, msg = "", ""
        if not r.ok:
            kind = "run failed"
            msg = f"the run failed: {r.reason}"
        elif worst is not None and not ok:
            kind = "tolerance"
        elif ok and limited:  # over the tolerance, within the engine's arithmetic floor
            w = max(limited, key=lambda c: c.normalised)
            kind = limit_word(w.precision)
            worst = w
            msg = (f"{kind}: {w.quantity}: error {w.normalised:.3g} of peak at "
                   f"{_at(w.at, unit)} exceeds the tolerance {w.tolerance:g} but is within "
                   f"the engine's {w.precision} floor {w.floor:.2g}")
        if worst is not None and not ok:
            where = f" at {_at(worst.at, unit)}" if math.isfinite(worst.at) else ""
            msg = (msg + "; " if msg else "") + (
                f"{worst.quantity}: error {worst.normalised:.3g} of peak{where} exceeds "
                f"the tolerance {worst.tolerance:g}" if worst.measured else
                f"{worst.quantity}: not measured from {_at(worst.at, unit)} on")
            if v.near_event:
                msg += f" ({v.near_event})"
        lines = [str(c) for c in comps] + [f"settings: {r.engine} {r.settings_text}"]
        lines += [f"note: {n}" for n in r.notes]
        out.append(CiCase(
            case=case, engine=r.engine,
            status=("limit" if limited else "pass") if ok else "fail",
            quantity=worst.quantity if worst else "",
            error=worst.normalised if worst else math.nan,
            at=_at(worst.at, unit) if worst else "",
            tolerance=worst.tolerance if worst else math.nan, kind=kind, message=msg,
            details="\n".join(lines), settings=f"{r.engine} {r.settings_text}",
            time=float(r.wall), notes=tuple(r.notes), file=file,
            version=versions(r.engine)["engine"]))
    return out


def from_baseline(checks, base_dir: Path | None = None) -> list[CiCase]:
    """``xval baseline check``'s :class:`reports.regression.baseline_check.RunCheck` list
    (``base_dir``: the baseline file's folder, where recorded model paths start)."""
    out = []
    for chk in checks:
        rec = chk.record
        w = chk.worst()
        bad = chk.failures()
        status = "pass" if chk.passed else ("error" if chk.problems and not chk.quantities
                                            else "fail")
        kind = ""
        parts = list(chk.problems)
        if bad:
            kind = {"over-tolerance": "tolerance", "not-finite": "run failed"}.get(
                bad[0].status, bad[0].status)
            parts.append(bad[0].message())
        elif chk.problems:
            kind = _problem_kind(chk.problems[0])
        changed = chk.versions_changed()
        rest = [q for q in chk.quantities if not q.failed]
        lines = list(chk.problems) + [q.message() for q in bad + rest]
        if changed:
            lines.append("versions changed: " + ", ".join(
                f"{k} {a} -> {b}" for k, a, b in ((k, *v) for k, v in changed.items())))
        if chk.settings_text:
            lines.append(f"settings: {chk.settings_text}")
        lines += [f"note: {n}" for n in chk.notes]
        loose = [q.message() for q in chk.loose()]
        file = ""
        if rec.model.kind == "file" and base_dir is not None:
            p = os.path.normpath(base_dir / rec.model.name)
            rel = os.path.relpath(p)
            file = Path(p if rel.startswith("..") else rel).as_posix()
        out.append(CiCase(
            case=rec.case, engine=rec.engine, status=status,
            quantity=w.quantity if w else "", error=w.error if w else math.nan,
            at=_at(w.at, w.at_unit) if w else "", tolerance=w.tolerance if w else math.nan,
            baseline=w.base if w else math.nan, kind=kind, message="; ".join(parts),
            details="\n".join(lines), settings=chk.settings_text, time=chk.wall,
            notes=(*(f"warning: {m}" for m in loose), *chk.notes), file=file,
            version=chk.versions_now.get("engine", rec.versions.get("engine", ""))))
    return out


def _problem_kind(problem: str) -> str:
    """A run-level problem's JUnit ``type`` (see
    :func:`reports.regression.baseline_check.check_run`)."""
    if "changed since the baseline" in problem:
        return "model changed"
    if any(w in problem for w in ("no longer exists", "is gone", "is not available")):
        return "gone"
    return "run failed"


# ============================================================================ JUnit
def _counts(cases: Sequence[CiCase]) -> dict:
    return {"tests": str(len(cases)), "failures": str(sum(c.status == "fail" for c in cases)),
            "errors": str(sum(c.status == "error" for c in cases)),
            "time": _secs(sum(c.time for c in cases))}


def _tool_version() -> str:
    try:
        return version("linkage-xval")
    except PackageNotFoundError:
        return "unknown"


def junit_xml(suite: str, cases: Sequence[CiCase], properties: dict | None = None,
              command: str = "compare") -> str:
    """The JUnit XML document: one ``testsuite`` per model file (its ``file``
    attribute), one ``testcase`` per entry, classname ``xval.<command>.<engine>``."""
    suite = _clean(suite)  # a path or name may carry what XML cannot: every text cleaned
    root = ET.Element("testsuites", {"name": suite, **_counts(cases)})
    files = list(dict.fromkeys(c.file for c in cases)) or [""]
    for f in files:
        group = [c for c in cases if c.file == f]
        attrs = {"name": f"{suite}: {f}" if f and len(files) > 1 else suite,
                 **_counts(group), "skipped": "0",
                 "timestamp": _dt.datetime.now().replace(microsecond=0).isoformat(),
                 "hostname": socket.gethostname() or "localhost"}
        ts = ET.SubElement(root, "testsuite", {**attrs, **({"file": _clean(f)} if f else {})})
        engines = {f"engine.{c.engine}": c.version for c in group if c.version}
        props = ET.SubElement(ts, "properties")
        for k, v in {"linkage-xval": _tool_version(), **dict(sorted(engines.items())),
                     "python": platform.python_version(), "platform": platform.platform(),
                     **(properties or {})}.items():
            ET.SubElement(props, "property", {"name": _clean(k), "value": _clean(v)})
        for c in group:
            _testcase(ts, c, command)
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, "unicode") + "\n"


def _testcase(ts, c: CiCase, command: str) -> None:
    tc = ET.SubElement(ts, "testcase", {"classname": _clean(f"xval.{command}.{c.engine}"),
                                        "name": _clean(c.case), "time": _secs(c.time)})
    if c.status in ("fail", "error"):
        tag = "failure" if c.status == "fail" else "error"
        el = ET.SubElement(tc, tag, {"message": _clean(c.message or c.kind),
                                     "type": c.kind or tag})
        el.text = _clean(c.details)
    # the current error, passing cases too; a precision limit is a passing testcase
    # (JUnit has no such outcome, and junit-10.xsd allows no properties in a testcase)
    # whose output starts with the verdict: "precision limit (float32): ..."
    so = ET.SubElement(tc, "system-out")
    so.text = _clean("\n".join([*([c.message] if c.status == "limit" else []),
                                c.worst_line(), *([f"settings: {c.settings}"]
                                                  if c.settings else []),
                                *[f"note: {n}" for n in c.notes]]))


def _secs(t: float) -> str:
    return f"{max(float(t), 0.0):.3f}" if math.isfinite(t) else "0.000"


def _clean(text: str) -> str:
    """XML 1.0 forbids most control characters (an engine message might carry one), lone
    surrogates (a file name's undecodable bytes) and U+FFFE/U+FFFF."""
    return "".join(ch for ch in str(text) if ch in "\t\n\r" or (
        ord(ch) >= 0x20 and not 0xD800 <= ord(ch) <= 0xDFFF and ch not in "\ufffe\uffff"))


# ============================================================================ Markdown
def markdown_summary(title: str, cases: Sequence[CiCase], intro: Sequence[str] = (),
                     error_label: str = "error / peak") -> str:
    """A Markdown table of the verdicts, failures first, with the failure messages
    (``error_label``: the error column's heading, e.g. ``error / range`` for free motion)."""
    fails = [c for c in cases if c.status in ("fail", "error")]
    head = f"## {title}: {'PASS' if not fails else 'FAIL'} " \
           f"({len(cases) - len(fails)} of {len(cases)} passed)"
    has_base = any(math.isfinite(c.baseline) for c in cases)
    cols = ["case", "engine", "verdict", "worst quantity", error_label, "at"]
    cols += ["baseline", "growth"] if has_base else []
    cols += ["tolerance"]
    rows = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for c in sorted(cases, key=lambda c: (c.status in ("pass", "limit"), c.case, c.engine)):
        verdict = {"pass": "pass", "limit": c.kind}.get(c.status, f"**{c.status.upper()}**")
        cells = [c.case, c.engine, verdict,
                 f"`{c.quantity}`" if c.quantity else "", _g(c.error), c.at]
        if has_base:
            grow = c.error / c.baseline if math.isfinite(c.error) and c.baseline > 0 \
                else math.nan
            cells += [_g(c.baseline), f"{grow:.3g}x" if math.isfinite(grow) else ""]
        cells.append(_g(c.tolerance))
        rows.append("| " + " | ".join(_md(x) for x in cells) + " |")
    out = [head, "", *intro, *([""] if intro else []), *rows]
    if fails:
        out += ["", "### Failures", ""]
        out += [f"- **{c.case} / {c.engine}** ({c.kind or c.status}): {_md(c.message)}"
                for c in fails]
    return "\n".join(out) + "\n"


def _g(x: float) -> str:
    return f"{x:.3g}" if math.isfinite(x) else ""


def _md(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


# ============================================================================ writing
def write_text(path: str, text: str, what: str) -> None:
    """Write ``text`` to ``path`` (``-``: standard output); :class:`OutputError` if not."""
    if path == "-":
        sys.stdout.write(text)
        return
    try:
        Path(path).write_text(text, encoding="utf-8")
    except OSError as e:
        raise OutputError(f"cannot write {what} {path!r}: {e.strerror}") from None


def write_outputs(suite: str, cases: Sequence[CiCase], junit: str | None = None,
                  summary: str | None = None, intro: Sequence[str] = (),
                  properties: dict | None = None, command: str = "compare",
                  error_label: str = "error / peak") -> None:
    """Write the JUnit XML to ``junit`` and the Markdown summary to ``summary`` (paths,
    ``-``: standard output; None: not asked for); ``error_label`` heads the summary's
    error column."""
    if junit:
        write_text(junit, junit_xml(suite, cases, properties, command), "JUnit file")
    if summary:
        write_text(summary, markdown_summary(suite, cases, intro, error_label), "summary")


def write_compare_outputs(mech, results, given: str, junit: str | None = None,
                          summary: str | None = None) -> None:
    """``xval compare --junit/--summary`` of ``results`` (:class:`reports.comparison.runs.
    Verdict` per engine) on ``mech``, given as ``given`` (a built-in name or a file)."""
    if not (junit or summary):
        return
    file = Path(given).as_posix() if given.endswith(".toml") else ""  # not a built-in
    cases = from_compare(mech.name, results, not isinstance(mech.driver_joint, Prismatic),
                         file)
    write_outputs(f"xval compare {mech.name}", cases, junit, summary)


__all__ = ["CiCase", "from_baseline", "from_compare", "junit_xml",
           "markdown_summary", "write_compare_outputs", "write_outputs", "write_text"]
