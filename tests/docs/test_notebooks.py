"""Every tutorial (docs/tutorials/*.md, a MyST notebook kept as text) opens as a notebook and runs
from top to bottom.

The notebooks are executed as the docs build executes them (MyST-NB runs them with nbclient on a
Jupyter kernel): read with jupytext, run cell by cell by nbclient on the ``python3`` kernel of
this environment, in a scratch folder, with the docs build's limit per cell
(``nb_execution_timeout`` of docs/conf.py). A cell that raises — every tutorial asserts the
numbers its text states — fails the test with the cell and its traceback.

The Jupyter command the docs show is not run (it starts a server): the test reads it and checks
that it puts jupytext — whose server extension opens a ``.md`` file as a notebook — beside
JupyterLab, and that jupytext reads each tutorial as a notebook of code cells.
"""

from __future__ import annotations

import ast
import importlib.metadata
import importlib.util
import os
import re
import shlex
from pathlib import Path

import pytest

jupytext = pytest.importorskip("jupytext")
nbclient = pytest.importorskip("nbclient")

ROOT = Path(__file__).resolve().parents[2]
TUTORIALS = ROOT / "docs" / "tutorials"
NOTEBOOKS = sorted(p for p in TUTORIALS.glob("*.md") if p.name != "index.md")
PAGES = [ROOT / "README.md",
         *sorted(p for p in (ROOT / "docs").rglob("*.md") if "_build" not in p.parts)]


def _execution_timeout() -> int:
    """``nb_execution_timeout`` of docs/conf.py: the docs build's limit, in seconds, per cell."""
    tree = ast.parse((ROOT / "docs" / "conf.py").read_text(encoding="utf-8"))
    (value,) = [node.value for node in tree.body if isinstance(node, ast.Assign)
                and [getattr(t, "id", None) for t in node.targets] == ["nb_execution_timeout"]]
    return int(ast.literal_eval(value))


def _jupyter_commands() -> list[tuple[str, str]]:
    """``(page, command)`` of every ``jupyter lab`` / ``jupyter notebook`` command the pages show,
    in a code span or a code block (a ``# comment`` dropped)."""
    found = []
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        spans = re.findall(r"`([^`\n]+)`", text) + text.splitlines()
        for span in spans:
            if re.search(r"\bjupyter (lab|notebook)\b", span) and "uv run" in span:
                found.append((str(page.relative_to(ROOT)), shlex.join(shlex.split(span, comments=True))))
    return list(dict.fromkeys(found))


def test_the_documented_jupyter_command_loads_jupytext():
    """``uv run --with jupyterlab jupyter lab`` alone opens the tutorials as plain text: the
    server runs in uv's overlay environment, where jupytext's server extension is not installed.
    Each documented command must add it (``--with jupytext``) to the environment it starts."""
    commands = _jupyter_commands()
    assert commands, "no page shows how to open the tutorials in Jupyter"
    for page, command in commands:
        words = shlex.split(command)
        withs = {words[i + 1].split("[")[0].split("=")[0].split(">")[0]
                 for i, w in enumerate(words[:-1]) if w == "--with"}
        assert {"jupyterlab", "jupytext"} <= withs, f"{page}: {command!r} does not load jupytext"
        assert "docs/tutorials/" in words or "docs/tutorials" in words, f"{page}: {command!r}"
    # what --with jupytext brings: the server extension that opens the .md files as notebooks
    files = [str(f) for f in importlib.metadata.files("jupytext") or []]
    assert any(f.endswith("jupyter_server_config.d/jupytext.json") for f in files), files
    assert importlib.util.find_spec("jupyterlab_jupytext") is not None


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_jupytext_reads_the_tutorial_as_a_notebook(path):
    """What the Jupyter command opens: a notebook (MyST format) of Markdown and code cells."""
    import nbformat

    nb = jupytext.read(path)
    nbformat.validate(nb)
    assert nb.metadata["jupytext"]["text_representation"]["format_name"] == "myst"
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert len(code) >= 3 and all(c.source.strip() for c in code), path.name
    assert any(c.cell_type == "markdown" for c in nb.cells)


def test_the_tutorials_are_notebooks_listed_on_the_tutorials_page():
    index = (TUTORIALS / "index.md").read_text(encoding="utf-8")
    assert len(NOTEBOOKS) >= 3
    for path in NOTEBOOKS:
        text = path.read_text(encoding="utf-8")
        assert text.startswith("---\n") and "format_name: myst" in text, path.name
        assert "```{code-cell}" in text, path.name
        assert f"\n{path.stem}\n" in index, f"{path.name} is not in the toctree of tutorials/index.md"


@pytest.mark.slow                   # a kernel and a notebook each: seconds to a minute
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_tutorial_runs(path, tmp_path, monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", os.environ.get("MUJOCO_GL", "egl"))
    nb = jupytext.read(path)
    client = nbclient.NotebookClient(nb, timeout=_execution_timeout(), kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code and all(c.get("execution_count") for c in code)
    errors = [o for c in code for o in c.outputs if o.output_type == "error"]
    assert errors == []
