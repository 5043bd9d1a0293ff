"""Sphinx configuration of the taichi-pneuma site: MyST Markdown pages, an API reference from the docstrings
(autodoc + napoleon), the example gallery (sphinx-gallery, executed at every build) and pages generated at build
time from the code and the benchmark results (_generate.py; the scene-key tables are committed, and written by
python docs/_generate.py), so that none of them can drift.

    pip install ".[docs]" && python -m sphinx -W --keep-going -n -b html docs docs/_build/html
"""

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path[:0] = [str(ROOT), str(DOCS)]  # the package (the gallery scripts import only it), _generate

import _generate  # noqa: E402

import taichi_pneuma  # noqa: E402

_generate.write_all(DOCS / "_generated")

project = "taichi-pneuma"
author = "the taichi-pneuma authors"
copyright = "2026, the taichi-pneuma authors"
release = version = taichi_pneuma.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
# pages that are only included into others (guide/scene_keys_*.md: committed, python docs/_generate.py writes them)
exclude_patterns = [
    "_build",
    "_generated/*.md",
    "guide/scene_keys_*.md",
    "gallery/*.ipynb",
    "gallery/*.py",
    "gallery/*.zip",
]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
suppress_warnings = ["myst.header"]  # pages included into others start below their first heading level

html_theme = "pydata_sphinx_theme"
html_title = f"taichi-pneuma {release}"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}
html_static_path = []

autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
autodoc_typehints = "none"  # the docstrings state the types; signatures keep the argument names and defaults
autodoc_preserve_defaults = True
napoleon_google_docstring = True
napoleon_numpy_docstring = False
nitpicky = True
# no inventory of other projects is fetched (the build runs offline): their types are named, not linked
nitpick_ignore_regex = [
    (r"py:.*", r"(matplotlib|numpy|np|scipy|taichi|ti|concurrent|argparse|pathlib|os|ray|logging|websockets)\..*")
]

sphinx_gallery_conf = {
    "examples_dirs": "../examples",
    "gallery_dirs": "gallery",
    "filename_pattern": r"/plot_",  # every gallery script runs at build time
    "ignore_pattern": r"(^|/)(?!plot_)[^/]*\.py$",  # the other scripts in examples/ are tools and helpers
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "matplotlib_animations": False,
    "reset_modules": ("matplotlib",),
}


def setup(app):
    """Docstrings are read as plain text first (_generate.plain_docstring), then by napoleon for their Args:
    and Returns: sections, except those of attributes and properties, whose first line napoleon would read
    as "type: description" (these state what the value is, not its type)."""
    from sphinx.ext import napoleon

    for listener in list(app.events.listeners["autodoc-process-docstring"]):
        if listener.handler is napoleon._process_docstring:
            app.disconnect(listener.id)
    app.connect("autodoc-process-docstring", _generate.plain_docstring, priority=400)
    app.connect(
        "autodoc-process-docstring",
        lambda app, what, *rest: (
            None if what in ("attribute", "property", "data") else napoleon._process_docstring(app, what, *rest)
        ),
    )
