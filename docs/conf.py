"""Sphinx configuration of linkage-xval's documentation (MyST Markdown pages, a
sphinx-gallery of example scripts run at every build, the furo theme).

Build: ``sphinx-build -W --keep-going -b html docs docs/_build/html`` (``.ci/docs``).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path[:0] = [str(ROOT), str(HERE / "_ext")]
os.environ.setdefault("MPLBACKEND", "Agg")  # the gallery draws without a display
# no background kernel compiles started by the gallery's and the pages' small calls
os.environ.setdefault("XVAL_BACKGROUND_COMPILE", "0")

project = "linkage-xval"
author = "linkage-xval contributors"
copyright = "2026, linkage-xval contributors"  # noqa: A001 (Sphinx's name)
release = version = "0.1.0"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx_copybutton",
    "sphinx_gallery.gen_gallery",
    "xval_cli",       # reference/cli.md: the command line from xval's own parser
    "xval_engines",   # reference/engines.md: every engine's settings and ranges
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "examples", "auto_examples/*.ipynb", "auto_examples/*.py",
                    "auto_examples/*.zip", "auto_examples/*.json", "sg_execution_times.rst",
                    "gallery/README.txt"]

myst_enable_extensions = ["colon_fence", "dollarmath", "deflist"]
myst_heading_anchors = 3

autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "show-inheritance": False}

sphinx_gallery_conf = {
    "examples_dirs": "gallery",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "write_computation_times": False,
    "abort_on_example_error": True,
    "image_scrapers": ("matplotlib",),
}

html_theme = "furo"
html_title = "linkage-xval 0.1.0"
copybutton_prompt_text = r"\$ |>>> "
copybutton_prompt_is_regexp = True
copybutton_only_copy_prompt_lines = True
