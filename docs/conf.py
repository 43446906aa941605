"""Sphinx configuration of the pendulum_lqg documentation (Markdown pages through MyST).

Build, with warnings as errors:

    uv run --group docs sphinx-build -W -b html docs docs/_build/html
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))          # autodoc imports the package from this checkout

import pendulum_lqg  # noqa: E402

project = "pendulum_lqg"
author = "the pendulum_lqg authors"
copyright = "pendulum_lqg authors, MIT licence"  # noqa: A001 - Sphinx's name
release = pendulum_lqg.__version__
version = ".".join(release.split(".")[:2])

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
]
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store"]

# MyST: $…$ / $$…$$ maths, amsmath environments, ::: fences; anchors for every heading down to ###
# so that links such as [text](gymnasium.md#the-reward) are checked by the build.
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
myst_dmath_double_inline = True

# autodoc / napoleon: the package's docstrings are numpydoc.
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "show-inheritance": True}
nitpicky = False

html_theme = "furo"
html_title = f"pendulum_lqg {release}"
html_static_path: list[str] = []
