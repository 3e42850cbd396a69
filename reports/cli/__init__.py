"""The ``xval`` command line: the command table (:mod:`reports.cli.xval`, only the command
that runs is imported), option types, output paths, one module per command.  The only
modules that read command-line arguments.

Modules:

* :mod:`reports.cli.animate`: ``xval animate CASE|FILE --out F.gif|F.mp4|F.html``: the
  linkage moving through a cycle (drawn by :mod:`reports.figures.animation` from
  :mod:`reports.figures.poses`); the options, the output checks and the engine runs asked
  for.
* :mod:`reports.cli.baseline`: ``xval baseline record`` and ``xval baseline check`` (see
  :mod:`reports.regression.baseline`, :mod:`reports.regression.baseline_record` and
  :mod:`reports.regression.baseline_check`).
* :mod:`reports.cli.cases`: ``xval cases``: the built-in cases, the hard ones and the
  free-motion ones, each with the first line of its description. Reads the case files' heads
  only (no solver, no numpy).
* :mod:`reports.cli.compare`: ``xval compare CASE|FILE``: engines run on a linkage and
  compared with the analytic solution (:func:`reports.comparison.runs.run_verdict`), as
  tables, JSON, JUnit XML or a Markdown summary.
* :mod:`reports.cli.explain`: ``xval explain CASE|FILE [--angle DEG | --value M] [--format
  md|html|tex] [--out F]``: the worked solution of one configuration in the course notes'
  method and notation.
* :mod:`reports.cli.models`: ``xval models [CASE|FILE] [--out DIR]``: the MJCF/URDF files of
  one case, or of every built-in case (:func:`sim_models.builders.model_files.write_models`).
* :mod:`reports.cli.options`: Command-line option types of ``xval``: every number and path
  is checked where it enters.
* :mod:`reports.cli.paths`: Where the command line may write: file names made from a
  description's ``name``, and no output that is one of the command's own inputs or another
  of its outputs.
* :mod:`reports.cli.plot`: ``xval plot CASE|FILE``: the full-cycle curves of one linkage,
  with engine runs overlaid.
* :mod:`reports.cli.report`: ``xval report``'s run: the options into a
  :class:`reports.report.build.ReportConfig`, progress by phase, the console verdict and the
  wall time (the report itself is :mod:`reports.report.build`).
* :mod:`reports.cli.simulate`: ``xval simulate CASE|FILE``: a released linkage's exact
  trajectory, tabulated.
* :mod:`reports.cli.simulate_engines`: ``xval simulate CASE --engine NAME|all``: the engines
  released from the exact state, each judged against the exact trajectory
  (:mod:`reports.comparison.free_compare`).
* :mod:`reports.cli.solve`: The commands ``xval solve`` and ``xval sweep``: the analytic
  solver on the command line.
* :mod:`reports.cli.studies`: ``python -m reports.cli.studies [--quick] [--out DIR]
  [--workers N] [--serial]``: the whole speed/accuracy study
  (:func:`reports.studies.study.run_study`) printed as tables, and with ``--out`` written as
  CSV tables and PNG figures (:func:`reports.studies.study.write_study`).
* :mod:`reports.cli.view`: ``xval view CASE|FILE``: MuJoCo's viewer on the harness's own
  session of a linkage.
* :mod:`reports.cli.xval`: The ``xval`` command line: the command table, the parser,
  ``main``.

The public names below load their module on first use (PEP 562), so importing
the package imports none of its modules.
"""

from __future__ import annotations

from reports.lazy_exports import lazy_getattr

#: public name -> the module that defines it
_EXPORTS = {
    "main": "reports.cli.xval",
}

__all__ = sorted(_EXPORTS)

__getattr__ = lazy_getattr(__name__, _EXPORTS)
