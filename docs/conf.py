"""Sphinx configuration of the documentation site (`make docs`: docs/_build/html).

Sphinx because the package's docstrings are numpydoc (the convention of scipy and xarray,
whose sites it builds): autodoc and numpydoc render them as they are, and myst-nb reads the
pages and the tutorials as MyST markdown and executes the tutorials when the site is built.
The site builds offline: no intersphinx inventory is fetched, and the theme's assets ship with
it. Every warning fails the build (``make docs`` runs ``sphinx-build -W``).
"""
from pathlib import Path
import sys

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))

project = "vibroimpact"
author = "The vibroimpact developers"
copyright = "the vibroimpact developers, BSD-3-Clause"


def _version():
    try:
        import vibroimpact

        return vibroimpact.__version__
    except Exception:       # a copy without git or metadata: the site still builds
        return "unknown"


release = version = _version()

extensions = [
    "myst_nb",                  # MyST markdown pages and executed notebooks
    "sphinx.ext.autodoc",
    "numpydoc",                 # the docstrings' Parameters/Returns/Examples sections
    "sphinx.ext.mathjax",
    "config_reference",         # the config reference, generated from the schema
]
exclude_patterns = ["_build", "jupyter_execute", ".jupyter_cache", "**.ipynb_checkpoints"]
source_suffix = {".md": "myst-nb"}
root_doc = "index"

# MyST: the pages' $...$ and $$...$$ maths, ::: fences, headings as link targets
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
# tutorials: executed at every build from scratch, a failing cell fails the build
nb_execution_mode = "force"
nb_execution_timeout = 600
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True

autodoc_member_order = "bysource"
autodoc_typehints = "none"          # the numpydoc sections give the types, with units
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

html_theme = "furo"
html_title = f"vibroimpact {version}"
html_static_path = []
