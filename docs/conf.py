"""Sphinx configuration of the dlasweep documentation (``make docs`` builds it into docs/_build/html)."""

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(DOCS.parent))

import dlasweep  # noqa: E402

project = "dlasweep"
author = "The dlasweep developers"
copyright = "2026, The dlasweep developers"
version = release = dlasweep.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "myst_nb",  # MyST Markdown pages and the executed lesson notebook
    "tables",  # docs/_ext/tables.py: the generated tables and the lesson notebook
]

source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "**.ipynb_checkpoints", "_generated/*.md"]
templates_path = ["_templates"]

myst_enable_extensions = ["colon_fence", "deflist"]
myst_heading_anchors = 3

# The lesson is run at every build, at the small size tables.py gives it, so that its pictures are real.
nb_execution_mode = "force"
nb_execution_timeout = 900
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True

autosummary_generate = True
autosummary_imported_members = True
autodoc_typehints = "none"  # the numpydoc sections give the types, in words
autodoc_default_options = {"members": False}
numpydoc_show_class_members = False
numpydoc_xref_param_type = False
numpydoc_validation_checks = set()

# References to other projects' objects: no inventory is fetched at build time, so they stay plain text.
nitpick_ignore_regex = [
    (r"py:.*", r"(numpy|np|xarray|xr|dask|distributed|matplotlib|pathlib|os|numba|netCDF4)\..*"),
]

html_theme = "pydata_sphinx_theme"
html_title = f"dlasweep {release}"
html_static_path = ["_static"]
html_css_files = ["custom.css"]
html_theme_options = {
    "navigation_with_keys": False,
    "header_links_before_dropdown": 6,
    "show_toc_level": 2,
    "navbar_align": "left",
    "footer_start": ["copyright"],
    "footer_end": [],
    "secondary_sidebar_items": ["page-toc"],
}
# The guide's pages stand alone (their sections are on the right); the API pages list each other on the left.
html_sidebars = {"*": [], "_generated/*": [], "api": ["sidebar-nav-bs"], "api/**": ["sidebar-nav-bs"]}
html_show_sourcelink = False
