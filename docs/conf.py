"""Sphinx configuration of the pendulum_lqg documentation (Markdown pages through MyST).

Build, with warnings as errors:

    uv run --group docs sphinx-build -W -b html docs docs/_build/html

The pages are MyST Markdown read by MyST-NB; the tutorials (``docs/tutorials/*.md``, MyST
notebooks kept as text) are executed on every build, and a failing cell fails the build.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))          # autodoc imports the package from this checkout

import pendulum_lqg  # noqa: E402

project = "pendulum_lqg"
author = "the pendulum_lqg authors"
copyright = "pendulum_lqg authors, MIT licence"
release = pendulum_lqg.__version__
version = ".".join(release.split(".")[:2])

extensions = [
    "myst_nb",                 # MyST Markdown (myst-parser) and executable MyST notebooks
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    # MathJax 3 from the built site (_static/mathjax), not from a CDN: the maths renders offline
    "sphinx-mathjax-offline",
    "sphinx.ext.viewcode",
]
source_suffix = {".md": "myst-nb"}     # a page is a notebook when its front matter says so
root_doc = "index"
# leaderboard/: the score files and the generated board, included by leaderboard.md
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "leaderboard", "_generated"]

# MyST: $…$ / $$…$$ maths, amsmath environments, ::: fences; anchors for every heading down to ###
# so that links such as [text](gymnasium.md#the-reward) are checked by the build.
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
myst_dmath_double_inline = True

# MyST-NB: execute every notebook on every build (never a stale cached output), in its own folder;
# an exception in a cell fails the build, and so does a cell that runs longer than the timeout
# (each tutorial is meant to run in well under a minute on two cores).
nb_execution_mode = "force"
nb_execution_timeout = 180
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True

# autodoc / napoleon: the package's docstrings are numpydoc.
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
# Attributes sections as fields of their class: an attribute that also has a ``#:`` comment would
# otherwise be described twice
napoleon_use_ivar = True
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "show-inheritance": True}
nitpicky = False

html_theme = "furo"
html_title = f"pendulum_lqg {release}"
html_static_path = ["_static"]
html_css_files = ["custom.css"]        # 1 280 px wide pages: nothing cut off (see the file)


# ---- the package's docstrings, read as numpydoc ---------------------------------------------------
# The docstrings follow the house style (docs/../STYLE: numpydoc sections), with two habits that
# napoleon would misread:
#
# * a field written ``name : description`` on one line (numpydoc's slot after the colon is the
#   *type*): napoleon would pass the description to Sphinx as a type, Sphinx would try every word
#   of it as a cross-reference ("n" in "(n, n) array" matching attributes of several classes) and
#   an inline literal broken over two lines would become an unterminated one. The hook rewrites
#   such a field as ``name`` with the description indented below it, numpydoc's form without a
#   type (the annotations still give the types, autodoc_typehints = "description").
# * a paragraph after the last field of a Parameters / Attributes section, separated by a blank
#   line: numpydoc has no place for it, so it is put under a "Notes" heading.
#
# * an absolute value written ``|x|`` in prose: reStructuredText reads ``|x|`` as a substitution
#   (the package defines none); the hook escapes the bars outside inline literals and roles. So
#   too a star-argument in a shape or call written in prose, ``(n, *tail)``, which would open an
#   emphasis: a ``*`` after ``(`` or ``, `` with no closing ``*`` on the line.
# * an attribute comment ``#: h·[diag(Q), R]: the cost of …``: napoleon takes the text before the
#   first colon of an attribute's docstring as its type. The package's attribute comments are
#   prose (the annotation gives the type), so the hook keeps them as written: it puts back, after
#   napoleon, the lines it had before.
#
# Gymnasium environments document themselves in Markdown (Gymnasium's convention, followed by
# CartPoleLQGEnv: "## Description", "## Action Space", tables); reStructuredText cannot read that,
# and the Gymnasium page of this site is written from it, so the API reference links there instead.

import re  # noqa: E402

_FIELD_SECTIONS = {"Parameters", "Other Parameters", "Attributes", "Returns", "Yields",
                   "Keyword Arguments"}
_FIELD = re.compile(r"^(?P<name>[^:\s][^:]*?)\s+:\s+(?P<text>\S.*)$")


def _numpydoc_fields(lines: list[str]) -> list[str]:
    out: list[str] = []
    section: str | None = None
    base = 0
    after_blank = False
    i = 0
    while i < len(lines):
        line, stripped = lines[i], lines[i].strip()
        nxt = lines[i + 1].strip() if i + 1 < len(lines) else ""
        if stripped and nxt and set(nxt) == {"-"} and len(nxt) >= len(stripped):
            section = stripped if stripped in _FIELD_SECTIONS else None
            base = len(line) - len(line.lstrip())
            after_blank = False
            out += [line, lines[i + 1]]
            i += 2
            continue
        if section is not None and stripped:
            indent = len(line) - len(line.lstrip())
            m = _FIELD.match(stripped) if indent == base else None
            if indent == base and after_blank and m is None:
                out += [" " * base + "Notes", " " * base + "-----"]
                section = None
            elif m is not None:
                out += [" " * indent + m.group("name"), " " * (indent + 4) + m.group("text")]
                after_blank = False
                i += 1
                continue
            after_blank = False
        elif section is not None:
            after_blank = True
        out.append(line)
        i += 1
    return out


_LITERAL_OR_ROLE = re.compile(r"(``.+?``|:\w+:`[^`]*`|`[^`]*`_?)")


_STAR_ARGUMENT = re.compile(r"(?:(?<=\()|(?<=, ))\*(?=[A-Za-z_])(?![^*]*\*)")


def _escape_bars(line: str) -> str:
    parts = _LITERAL_OR_ROLE.split(line)
    return "".join(p if i % 2 else _STAR_ARGUMENT.sub(r"\\*", p.replace("|", "\\|"))
                   for i, p in enumerate(parts))


def _process_docstring(app, what, name, obj, options, lines):
    if any(line.strip() == "## Description" for line in lines):
        lines[:] = [f"This class documents itself in Markdown, Gymnasium's convention "
                    f"(``help({name.rsplit('.', 1)[-1]})``); the same content — spaces with "
                    "units, reward, starting state, episode end, every keyword — is the "
                    ":doc:`Gymnasium page <gymnasium>`.", ""]
        return
    lines[:] = [_escape_bars(line) for line in _numpydoc_fields(lines)]
    if what in ("attribute", "data", "property"):
        _ATTRIBUTE_TEXT[name] = list(lines)


#: attribute docstrings as the hook left them, put back after napoleon (see above)
_ATTRIBUTE_TEXT: dict[str, list[str]] = {}


def _restore_attribute_text(app, what, name, obj, options, lines):
    if what in ("attribute", "data", "property") and name in _ATTRIBUTE_TEXT:
        lines[:] = _ATTRIBUTE_TEXT.pop(name)


def setup(app):
    # before napoleon (priority 500), which turns the numpydoc sections into fields
    app.connect("autodoc-process-docstring", _process_docstring, priority=400)
    app.connect("autodoc-process-docstring", _restore_attribute_text, priority=600)
