"""The validation report: its build, tables, page layout and document.

Modules:

* :mod:`reports.report.build`: The validation report: ``xval report [--out DIR] [--quick]
  [--cases ...]``.
* :mod:`reports.report.console`: The console verdict of ``xval report``: a compact table and
  one line of counts.
* :mod:`reports.report.document`: The report page: collects sections, renders self-contained
  HTML and Markdown.
* :mod:`reports.report.free_section`: The report's "Free motion" section: its pool tasks
  (:mod:`reports.studies.free_studies`) and its page (verdict table, figures per case,
  work-precision grid, IFToMM rows).
* :mod:`reports.report.layout`: The report page, top-down: title, summary card, contents,
  then one section per subject, each opening with a paragraph that says what it shows and
  how to read it.
* :mod:`reports.report.tables`: The report's tables, from the task results (pandas
  DataFrames).
"""
