"""The validation report: its build, tables, page layout and document.

Modules:

* :mod:`reports.report.build`: The validation report: ``xval report [--out DIR] [--quick]
  [--cases ...]``.
* :mod:`reports.report.console`: The console verdict of ``xval report``: a compact table and
  one line of counts.
* :mod:`reports.report.document`: The report's pages: collect sections, render HTML and
  Markdown.
* :mod:`reports.report.first_screen`: The report's first screen: what passed, what failed
  and why, for the prescribed and the free runs, with one overview figure and links to
  the details.
* :mod:`reports.report.free_section`: The report's "Free motion" section: its pool tasks
  (:mod:`reports.studies.free_studies`) and its page (verdict table, figures per case,
  work-precision grid, IFToMM rows).
* :mod:`reports.report.layout`: The report's pages, top-down: title, the first screen,
  then one section per subject, each opening with a paragraph that says what it shows and
  how to read it; each case's figures on a page of its own.
* :mod:`reports.report.tables`: The report's tables, from the task results (pandas
  DataFrames).
"""
