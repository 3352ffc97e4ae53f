"""Sphinx configuration of the seds_casadi documentation.

Build: ``python -m sphinx -W -b html docs docs/_build/html`` (about a minute; CI runs it through
``tests/test_docs.py``). The examples' gallery is not executed unless ``SEDS_DOCS_RUN_EXAMPLES``
is set (``quick``: the examples' reduced size, ``full``: the paper's sizes, minutes to hours);
otherwise each example page shows the figure saved in ``docs/`` where there is one.
``SEDS_DOCS_EXAMPLES=REGEX`` runs only the scripts whose path matches.
"""

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

from seds_gallery import ExampleArgv  # noqa: E402

import seds_casadi  # noqa: E402

project = "seds_casadi"
author = "the seds_casadi authors"
copyright = "2026, the seds_casadi authors"
release = version = seds_casadi.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "sphinxarg.ext",
    "seds_api",
    "seds_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "auto_examples/*.ipynb", "auto_examples/*.py",
                    "auto_examples/*.zip", "auto_examples/*.json", "auto_examples/*.md5"]
templates_path = []

# options such as --out stay two hyphens (no en dash), in the pages and in --help's text
smartquotes = False

# no network, neither for the build nor for reading the site: no intersphinx inventories, and
# MathJax (3.2.2) ships with the site, from the pip package sphinx-mathjax-offline (the docs
# extra): it copies MathJax into _static/mathjax and points the pages at it, so the equations
# render from a file:// copy on a machine without internet. SEDS_DOCS_MATHJAX=URL takes another
# copy instead (a CDN, or Debian's libjs-mathjax 2:
# file:///usr/share/javascript/mathjax/MathJax.js?config=TeX-AMS-MML_HTMLorMML)
if os.environ.get("SEDS_DOCS_MATHJAX"):
    mathjax_path = os.environ["SEDS_DOCS_MATHJAX"]
    if "MathJax.js" in mathjax_path:  # MathJax 2: MyST marks the pages' text tex2jax_ignore
        mathjax2_config = {"tex2jax": {"processClass": "math", "ignoreClass": "tex2jax_ignore"}}
else:
    extensions.append("sphinx-mathjax-offline")
suppress_warnings = []
nitpicky = False

# --- autodoc / numpydoc ---------------------------------------------------------------------
autodoc_default_options = {"member-order": "bysource"}
autodoc_typehints = "none"  # numpydoc's Parameters sections give the types
autosummary_generate = False
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks = set()

# --- MyST -----------------------------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# --- the examples' gallery --------------------------------------------------------------------
RUN_EXAMPLES = os.environ.get("SEDS_DOCS_RUN_EXAMPLES", "").lower()
if RUN_EXAMPLES not in ("", "0", "quick", "full"):
    raise ValueError(f"SEDS_DOCS_RUN_EXAMPLES={RUN_EXAMPLES!r}: use quick, full or leave it unset")


sphinx_gallery_conf = {
    "examples_dirs": str(HERE.parent / "examples"),
    "gallery_dirs": "auto_examples",
    "plot_gallery": RUN_EXAMPLES in ("quick", "full"),
    "reset_argv": ExampleArgv(quick=RUN_EXAMPLES == "quick"),
    # SEDS_DOCS_EXAMPLES=REGEX runs only the matching scripts (the others show their saved figure)
    "filename_pattern": os.environ.get("SEDS_DOCS_EXAMPLES", r"\.py$"),
    "download_all_examples": False,
    "show_memory": False,
    "show_signature": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "image_scrapers": ("matplotlib",),
    "capture_repr": (),
    "abort_on_example_error": True,
    "write_computation_times": False,
}

# --- HTML -----------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"seds_casadi {release}"
html_static_path = []
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "header_links_before_dropdown": 6,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": [],
}
html_show_sourcelink = False
html_copy_source = False
