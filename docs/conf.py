"""Sphinx configuration of the nonholo documentation.

Build: ``python -m pip install -e ".[docs]"`` then
``python -m sphinx -W -b html docs docs/_build/html`` (warnings are errors: broken
cross-references, public names without a page or without the sections of their
docstring convention, a gallery copy that is not current).
"""
from __future__ import annotations

import shutil
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(DOCS / "ext"))

import nonholo  # noqa: E402
from docutils import nodes  # noqa: E402
from docutils.parsers.rst import roles  # noqa: E402

# matplotlib's own role, in the docstrings nonholo.viz.style.NotebookFigure inherits
roles.register_generic_role("mpltype", nodes.literal)

project = "nonholo"
author = "nonholo authors"
copyright = "nonholo authors, MIT licence"
release = version = nonholo.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_nb",
    "gallery",     # docs/ext/gallery.py: the stored executed notebooks checked
    "reference",   # docs/ext/reference.py: benchmark pages, API completeness, Raises sections
]

source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "ext", "**.ipynb_checkpoints", "jupyter_execute"]
templates_path = ["_templates"]

# -- the API reference: one page per public module, class and function ----------------------
# autosummary writes its pages into api/generated/ and keeps pages of names that are gone:
# every build starts without them, so a removed function leaves no page that fails to import
shutil.rmtree(Path(__file__).resolve().parent / "api" / "generated", ignore_errors=True)
autosummary_generate = True
autosummary_imported_members = False
autosummary_ignore_module_all = True
autodoc_default_options = {"member-order": "bysource"}
autodoc_typehints = "none"          # the types are in the numpydoc sections
autodoc_preserve_defaults = True
add_module_names = False

# numpydoc: the docstring convention of NumPy, SciPy, python-control and geomstats
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks = {"GL08", "PR01", "PR02", "RT01", "YD01"}
# Every public object is checked (numpydoc's checks above and the Raises check of
# docs/ext/reference.py) but NotebookFigure, which is matplotlib's Figure: its parameters
# and the set() matplotlib writes for every subclass are matplotlib's, documented there
numpydoc_validation_exclude = {r"^nonholo\.viz\.style\.NotebookFigure(\.|$)"}

nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", r"(derivations|nonholo\.generated)(\..*)?"),   # SymPy and generated code: the guide
    (r"py:data", r"STYLE"),   # nonholo.viz.style's matplotlib style, a value without a doc comment
    (r"py:.*", r"(abc|ast|enum|dataclasses|numpy|np|scipy|matplotlib|pyarrow|dask|distributed|sympy|numba|nbformat|"
               r"nbclient|argparse|pathlib|typing|collections|concurrent|threading|"
               r"multiprocessing|sphinx|tqdm)(\..*)?"),
    (r"py:.*", r"(int|float|str|bool|bytes|dict|list|tuple|set|object|callable|None|type|"
               r"Exception|ValueError|TypeError|KeyError|OSError|RuntimeError|"
               r"FileNotFoundError|Path|ndarray|array_like|iterable|sequence|mapping|optional|"
               r"default|of|or|shape)"),
]

# -- notebooks and Markdown -------------------------------------------------------------------
nb_execution_mode = "off"           # the gallery is stored executed: docs/gallery/index.md
nb_merge_streams = True
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
suppress_warnings = ["myst.header"]

# -- HTML ------------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = "nonholo"
html_static_path = []
html_theme_options = {
    "navigation_with_keys": False,
    "collapse_navigation": True,
    "navigation_depth": 2,
    "show_toc_level": 2,
    "header_links_before_dropdown": 6,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
# no left sidebar on the pages of single functions and classes: the theme renders the
# navigation tree on every page, and for the API's hundreds of pages that cost most of the
# build's time (they keep the top bar, the breadcrumbs and their module's page)
html_sidebars = {"index": [], "api/generated/**": []}
html_show_sourcelink = False
