"""Speed against error: the settings grids, hard cases, change point, free-motion studies
and the report's executor.

Modules:

* :mod:`reports.studies.change_point`: The change-point study: a parallelogram four-bar
  through its singular positions.
* :mod:`reports.studies.free_studies`: Free motion in the report: the verdicts at each
  engine's recommended free-motion settings, and speed against error (a grid of integrators,
  steps and loop-constraint settings per engine), with IFToMM-style rows.
* :mod:`reports.studies.hard_cases`: The hard cases of the speed/accuracy study: the
  slider-crank at high speed, the near-toggle four-bar, the parallelogram through its change
  points, and the long run.
* :mod:`reports.studies.runs`: The studies' engine runs: the same sessions and run loop as
  the verdict runs.
* :mod:`reports.studies.scene`: Scene economy: what MuJoCo's scene costs (contacts, gravity,
  extra geoms), each variant's errors and speed through the verdict runs' session.
* :mod:`reports.studies.scheduler`: A priority front for the report's process pool (or Dask
  executor).
* :mod:`reports.studies.speed_accuracy`: Speed against error: the settings grids, their
  tasks and executor, timing, errors.
* :mod:`reports.studies.study`: The whole speed/accuracy study: the grids, the hard cases
  and the scene economy run together (:func:`run_study`) and written as CSV tables and PNG
  figures (:func:`write_study`).
"""
