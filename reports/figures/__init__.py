"""Figures: data in, image (PNG bytes, GIF, MP4) out; no argparse, no engine runs of their
own.

Modules:

* :mod:`reports.figures.animation`: The linkage moving through a cycle, drawn frame by frame
  and written as GIF, MP4 or HTML (the frames: :mod:`reports.figures.poses`; the command
  ``xval animate``: :mod:`reports.cli.animate`).
* :mod:`reports.figures.case_figures`: The figures of one case: drawn from the runs' own
  analytic reference.
* :mod:`reports.figures.display_units`: Display units of ``xval solve``, ``sweep`` and
  ``plot`` (``--units mm,deg,rpm``).
* :mod:`reports.figures.free_plots`: ``xval plot`` and ``xval animate`` of a released
  linkage (free motion).
* :mod:`reports.figures.free_report_plots`: Figures of free motion (PNG bytes): the released
  joint's trajectory with engine markers on the exact curve, the error against time with the
  tolerance and each engine's trusted horizon, the energy and loop-closure drift, and the
  work-precision plot.
* :mod:`reports.figures.overview`: The report's overview figure: one cell per case and
  engine, prescribed and free runs, coloured by the verdict and labelled with the worst
  error over its tolerance.
* :mod:`reports.figures.plots`: Figures of the validation report (matplotlib, Agg backend,
  PNG bytes out).
* :mod:`reports.figures.poses`: What an animation shows, frame by frame: the bodies' poses
  from the analytic solution, from a free trajectory, or from an engine's run (its body
  angles and frame origins at its samples, through
  :meth:`sim_models.builders.tree.SimTree.propagate`), with the input, the clock and the
  joint forces (:class:`Frames`). Drawn by :mod:`reports.figures.animation`; ``xval animate`` is
  :mod:`reports.cli.animate`.
* :mod:`reports.figures.study_plots`: Figures of the speed/accuracy studies
  (:mod:`reports.studies.speed_accuracy`); PNG bytes out.
"""
