"""Sphinx configuration of the fembem documentation site (``make docs``).

Everything comes from Debian packages (python3-sphinx, python3-myst-parser, furo,
libjs-mathjax); the site works offline: MathJax is copied from libjs-mathjax into the
build. The reference pages that could drift from the code are generated at build
time by the local extension ``fembem_docs`` (docs/_ext): the configuration and
command-line references, the exit codes, the troubleshooting messages, the API
module list and the demo pages.
"""
from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(DOCS.parent))  # the packages, when not installed

project = "fembem"
author = "the fembem developers"
copyright = "2026, the fembem developers"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "fembem_docs",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
# study/quick: the output of a --quick run of the study, not a page of the site
exclude_patterns = ["_build", "study/quick"]

myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
myst_dmath_double_inline = True

# nitpicky for the project's own references: an unresolved reference to a name of
# fem_py, bem_cpp or coupling is an error. Other names (numpy, PETSc, DOLFINx, ... have
# no inventory offline: no intersphinx, the site builds without a network) and the
# words of NumPy-style type descriptions ("(n, 2) float array") are plain text:
# fembem_docs.docstrings.external_reference.
nitpicky = True
# "more than one target found": a short class name in a docstring's type description
# that two modules define (fem_py.shapes.Arc, coupling.manufactured.Arc) links to the
# first; it is the only warning of this subtype.
suppress_warnings = ["ref.python"]

# each object documented once, in the module that defines it (not where a package's
# __all__ re-exports it)
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented"  # no lists of undocumented params
napoleon_numpy_docstring = True
napoleon_google_docstring = False

# MathJax 2.7 from libjs-mathjax, copied into _static/mathjax by fembem_docs (offline)
mathjax_path = "mathjax/MathJax.js?config=TeX-AMS_SVG"
# MyST marks its pages tex2jax_ignore and its maths class "math": process only those
mathjax2_config = {
    "tex2jax": {"processEscapes": True, "processClass": "math", "ignoreClass": "tex2jax_ignore"}
}

html_theme = "furo"
html_title = "fembem"
html_static_path = []
html_last_updated_fmt = None
