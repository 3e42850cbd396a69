"""Reports: engine runs judged against the analytic solution, and what is made of them.

``comparison`` is the base; ``figures`` draws on it; ``studies`` and ``regression`` run and
judge with both; ``report`` gathers them; ``explain`` needs only ``analytic``; ``cli`` calls
them all and nothing calls it.

Sub-packages:

* :mod:`reports.cli`: The ``xval`` command line: the command table (:mod:`reports.cli.xval`,
  only the command that runs is imported), option types, output paths, one module per
  command. The only modules that read command-line arguments.
* :mod:`reports.comparison`: One engine run against the analytic solution: the judged
  quantities, the one analytic reference, the comparison, and the one run-and-compare.
* :mod:`reports.explain`: The worked solutions of ``xval explain``, in the course notes'
  method.
* :mod:`reports.figures`: Figures: data in, image (PNG bytes, GIF, MP4) out; no argparse, no
  engine runs of their own.
* :mod:`reports.regression`: Engine regressions: baseline records and checks, their
  messages, the CI formats and the pytest plugin's work.
* :mod:`reports.report`: The validation report: its build, tables, page layout and document.
* :mod:`reports.studies`: Speed against error: the settings grids, hard cases, change point,
  free-motion studies and the report's executor.

The public names below load their module on first use (PEP 562), so importing
the package imports none of its modules.
"""

from __future__ import annotations

from reports.lazy_exports import lazy_getattr

#: public name -> the module that defines it
_EXPORTS = {
    "Verdict": "reports.comparison.runs",
    "run_verdict": "reports.comparison.runs",
    "Comparison": "reports.comparison.compare",
    "compare_run": "reports.comparison.compare",
    "verdict": "reports.comparison.compare",
}

__all__ = sorted(_EXPORTS)

__getattr__ = lazy_getattr(__name__, _EXPORTS)
