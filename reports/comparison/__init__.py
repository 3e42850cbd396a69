"""One engine run against the analytic solution: the judged quantities, the one analytic
reference, the comparison, and the one run-and-compare.

Modules:

* :mod:`reports.comparison.compare`: One comparison helper shared by the tests and the
  report (cf. Drake's CompareMatrices).
* :mod:`reports.comparison.free_cases`: The free-motion cases the verdicts, studies and
  report run: the IFToMM problems and the built-in cases released under gravity.
* :mod:`reports.comparison.free_compare`: Judging a free trajectory: one engine's free run
  against the exact trajectory.
* :mod:`reports.comparison.free_limits`: Known engine limits of the report's free-motion
  verdicts, and the verdict each row gets from them: ``pass``, ``FAIL``, or ``known limit``.
* :mod:`reports.comparison.iftomm`: The IFToMM benchmark's accuracy rule on a free run
  (Gonzalez et al. 2006): the reference point's position error over the run, m, against
  the benchmark's two precision levels.
* :mod:`reports.comparison.progress`: A progress line for engine runs that take a while
  (``xval plot --engine``, ``xval compare``, ``xval animate --engine``): on standard error,
  only when it is a terminal, and only once a run has lasted :data:`SHOW_AFTER_S` (a short
  run prints nothing).
* :mod:`reports.comparison.quantities`: The quantities a comparison names, and which of them
  the verdict judges.
* :mod:`reports.comparison.reference`: The one analytic reference of an engine run: what the
  verdict, the error figures and the case plots all read.
* :mod:`reports.comparison.runs`: Verdict runs: one engine on one compiled linkage, compared
  with its analytic solution.

The public names below load their module on first use (PEP 562), so importing
the package imports none of its modules.
"""

from __future__ import annotations

from reports.lazy_exports import lazy_getattr

#: public name -> the module that defines it
_EXPORTS = {
    "Verdict": "reports.comparison.runs",
    "run_verdict": "reports.comparison.runs",
    "run_comparison": "reports.comparison.runs",
    "Comparison": "reports.comparison.compare",
    "compare_run": "reports.comparison.compare",
    "verdict": "reports.comparison.compare",
    "Reference": "reports.comparison.reference",
    "reference_of": "reports.comparison.reference",
    "is_engine_reading": "reports.comparison.quantities",
    "judged": "reports.comparison.quantities",
}

__all__ = sorted(_EXPORTS)

__getattr__ = lazy_getattr(__name__, _EXPORTS)
