"""Sphinx configuration of lorisnb's manual (``make docs``; built by ``docs/build.py`` from a staged
copy of this folder, the notebooks and the pages it generates). Everything the pages load is served
from the manual itself: MathJax 3 from ``_static/mathjax``, no widget script from a CDN."""

from __future__ import annotations

import sys
from pathlib import Path

import lorisnb

sys.path.insert(0, str(Path(__file__).parent))  # cli_parser: the command line's parser for the reference

project = "lorisnb"
author = "lorisnb"
copyright = "lorisnb contributors"  # noqa: A001 (Sphinx's name)
release = lorisnb.__version__
version = release

extensions = [
    "myst_nb",  # MyST Markdown pages and executed notebooks (it loads myst_parser itself)
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinxarg.ext",  # the command-line reference, from lorisnb.cli.build_parser
]

exclude_patterns = ["_build", "_*.md", "**/_*.md", "Thumbs.db", ".DS_Store", "requirements.txt", "**.ipynb_checkpoints"]
myst_enable_extensions = ["colon_fence", "dollarmath", "deflist"]
myst_heading_anchors = 3

# notebooks: build.py executes them (in parallel, with a temporary output_dir; an error fails the build)
# before Sphinx renders them with their outputs
nb_execution_mode = "off"
nb_ipywidgets_js = {}  # no widget manager from a CDN: the explorers' last state shows as text
nb_merge_streams = True

# API reference from docstrings
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_typehints = "description"
autodoc_member_order = "bysource"
napoleon_google_docstring = True  # lorisnb's docstrings: "Args:", "Returns:"
napoleon_numpy_docstring = False

# offline: MathJax 3 from the manual's own files (build.py copies them into mathjax_static/mathjax)
mathjax_path = "mathjax/tex-chtml.js"
html_static_path = ["mathjax_static"]
html_theme = "sphinx_book_theme"
html_title = f"lorisnb {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "use_repository_button": False,
    "use_download_button": False,
    "show_toc_level": 2,
}
html_last_updated_fmt = None
html_show_sourcelink = False
html_copy_source = False
smartquotes = False  # "--eps" stays two hyphens (not an en dash) in the command line's help and in prose
