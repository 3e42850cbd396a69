"""Engine regressions: baseline records and checks, their messages, the CI formats and the
pytest plugin's work.

Modules:

* :mod:`reports.regression.baseline`: Baselines: what each engine run's errors were, so a
  later run can tell when they drift (the records, the file format and the check's
  constants).
* :mod:`reports.regression.baseline_check`: Checking a baseline (``xval baseline check``,
  the pytest plugin): every recorded run re-run and each quantity judged against its
  record.
* :mod:`reports.regression.baseline_free`: Free-motion runs in a baseline file
  (:mod:`reports.regression.baseline`): an engine released from the exact state, judged by
  :func:`reports.comparison.free_compare.compare_free`, recorded and checked by the same
  record / check cycle as the prescribed runs (``xval baseline record --free``, ``xval
  baseline check``, the pytest plugin).
* :mod:`reports.regression.baseline_record`: Recording a baseline (``xval baseline
  record``): every model run in every engine, merged into a file, and the command that
  records a file again.
* :mod:`reports.regression.baseline_settings`: A baseline run's engine settings: written
  in full, checked when a file is read, rebuilt for a check, overridden by ``--set``.
* :mod:`reports.regression.baseline_store`: A baseline file read (every value checked
  against the command line's ranges) and written.
* :mod:`reports.regression.ci_formats`: Verdicts in the formats CI systems read: JUnit XML
  and a Markdown job summary.
* :mod:`reports.regression.messages`: What a baseline check says, as lines of text: ``xval
  baseline check``'s report and the pytest plugin's failure text both print them
  (:mod:`reports.regression.baseline_check` holds the checks).
* :mod:`reports.regression.model_identity`: A mechanism's identity by content: what a
  baseline compares to tell a changed model.
* :mod:`reports.regression.pytest_plugin`: The work behind linkage-xval's pytest plugin:
  engine-against-analytic assertions and baseline checks in your own suite (the objects
  behind its fixtures).
* :mod:`reports.regression.run_cache`: The pytest plugin's session run cache: one
  :class:`reports.regression.run_cache.RunCache` object per process, shared by the
  project's own engine tests.
"""
