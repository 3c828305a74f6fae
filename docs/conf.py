"""Sphinx configuration of clearsweep's documentation.

Build (from the repository root, with ``pip install -e ".[docs]"``)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html

Markdown pages through myst-parser, the API reference from the numpy-style docstrings
(autodoc, autosummary, napoleon), the examples gallery run by sphinx-gallery at build
time (docs/examples), the configuration schema generated from the typed config
(docs/_ext/config_schema.py) and benchmarks/README.md included as it is.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE / "_ext"))
# the gallery runs in this process and its examples in worker-free sweeps; keep BLAS quiet
os.environ.setdefault("OMP_NUM_THREADS", "1")

from clearsweep.version import __version__  # noqa: E402

project = "clearsweep"
author = "the clearsweep authors"
copyright = "the clearsweep authors, MIT licence"
version = release = __version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
    "config_schema",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
templates_path = ["_templates"]
exclude_patterns = ["_build", "examples", "data", "figures", "Thumbs.db", ".DS_Store"]

# --- Markdown
myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3

# --- API reference
autosummary_generate = True
# members defined in each module only: names a module re-exports (config re-exports
# ConfigError from schema) are documented where they are defined
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
autodoc_typehints = "description"
autodoc_member_order = "bysource"
napoleon_numpy_docstring = True
napoleon_google_docstring = False

# --- examples gallery: every script under docs/examples runs at each build
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "image_scrapers": ("gallery_figures.scrape_figures",),
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
    "capture_repr": (),
    "abort_on_example_error": True,
}

# --- HTML
html_theme = "pydata_sphinx_theme"
html_title = f"clearsweep {release}"
html_theme_options = {"navigation_depth": 2, "show_toc_level": 2}
html_static_path: list[str] = []
