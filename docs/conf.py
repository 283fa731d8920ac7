"""Sphinx configuration of the quickrelease documentation.

Build from the repository root with ``sphinx-build -W -b html docs docs/_build/html`` (warnings are
errors). The gallery (``docs/examples/*.py``) is executed at build time, so every figure of the site is
drawn by the code of this version; the CLI reference is rendered from the Typer app's ``--help``.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")

from gallery_scraper import figures_in_globals  # noqa: E402

import quickrelease  # noqa: E402

project = "quickrelease"
author = "quickrelease developers"
copyright = "quickrelease developers, MIT licence"
release = quickrelease.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "cli_reference",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "examples/README.rst", "Thumbs.db", ".DS_Store"]
templates_path = ["_templates"]

# MyST: the user guide is Markdown (it was the README); headings get anchors for links within a page.
# Equations: $...$ inline and $$...$$ (or \begin{align}) displayed, typeset by MathJax in the browser
# (sphinx.ext.mathjax); a displayed equation may carry a label, $$...$$ (eq-name), cited as {eq}`eq-name`.
myst_enable_extensions = ["colon_fence", "deflist", "dollarmath", "amsmath"]
myst_heading_anchors = 4

# API reference: autosummary writes one page per public object from the docstrings (numpy style).
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
autodoc_typehints = "none"
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()

# Gallery: each docs/examples/plot_*.py runs at build time; its figures land in auto_examples/.
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "image_scrapers": (figures_in_globals, "matplotlib"),
    "reset_modules": ("matplotlib",),
    "show_memory": False,
    "plot_gallery": "True",
    "min_reported_time": 1,
    "capture_repr": (),
}

html_theme = "furo"
html_title = f"quickrelease {release}"
html_static_path: list[str] = []
html_show_sourcelink = False
html_copy_source = False

nitpicky = False

# The docstrings write absolute values as |x| (plain-text mathematics), which reStructuredText would read as
# a substitution reference: escape such bars (not inside ``literals``) before the docstring is parsed.
_BARS = re.compile(r"(?<![`\\|])\|(?=[^\s|`])([^|`\n]*?[^\s|`\\])\|(?![`|_])")


def _escape_bars(app, what, name, obj, options, lines):
    for i, line in enumerate(lines):
        parts = line.split("``")  # odd parts are inline literals: left alone
        lines[i] = "``".join(_BARS.sub(r"\\|\1\\|", part) if k % 2 == 0 else part for k, part in enumerate(parts))


def setup(app):
    app.connect("autodoc-process-docstring", _escape_bars, priority=100)
suppress_warnings = ["config.cache"]
