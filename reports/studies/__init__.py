"""Speed against error: the settings grids, hard cases, change point, free-motion studies
and the report's executor.

Modules:

* :mod:`reports.studies.change_point`: The change-point study: a parallelogram four-bar
  through its singular positions.
* :mod:`reports.studies.free_studies`: Free motion in the report: the verdicts at each
  engine's recommended free-motion settings, and speed against error (a grid of integrators,
  steps and loop-constraint settings per engine), with IFToMM-style rows.
* :mod:`reports.studies.runs`: The studies' engine runs: the same sessions and run loop as
  the verdict runs.
* :mod:`reports.studies.scheduler`: A priority front for the report's process pool (or Dask
  executor).
* :mod:`reports.studies.speed_accuracy`: Speed against error: settings grids, hard cases, a
  long run and scene economy.
"""
