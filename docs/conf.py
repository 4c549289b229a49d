"""Sphinx configuration of the autobones documentation (``sphinx-build -W docs docs/_build``)."""
import os
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, ROOT)  # the checkout's autobones, even when another copy is installed
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "_ext"))

import autobones  # noqa: E402

project = "autobones"
author = "the autobones developers"
copyright = "autobones developers, MIT licence"
version = release = autobones.__version__

extensions = [
    "myst_parser",            # the pages are Markdown, as the README was
    "sphinx.ext.autodoc",     # the API reference from the docstrings
    "numpydoc",               # which are written numpydoc style
    "sphinx.ext.doctest",     # `sphinx-build -b doctest`: the Examples sections run on the sample heads
    "cli_reference",          # the CLI reference from the argparse parser itself (docs/_ext)
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build"]
html_theme = "furo"
html_title = f"autobones {release}"
myst_heading_anchors = 4
myst_enable_extensions = ["colon_fence"]

# numpydoc: no autosummary stubs for every member (the reference pages list what they show)
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks = set()
autodoc_member_order = "bysource"
autodoc_typehints = "none"

# The doctests import the checkout (above) and write the sample heads on first use (autobones.samples.path).
doctest_global_setup = "import autobones\nfrom autobones import samples"
