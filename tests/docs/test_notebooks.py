"""Every tutorial (docs/tutorials/*.md, a MyST notebook kept as text) runs from top to bottom.

The notebooks are executed as the docs build executes them (MyST-NB runs them with nbclient on a
Jupyter kernel): read with jupytext, run cell by cell by nbclient on the ``python3`` kernel of
this environment, in a scratch folder. A cell that raises — every tutorial asserts the numbers its
text states — fails the test with the cell and its traceback.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

jupytext = pytest.importorskip("jupytext")
nbclient = pytest.importorskip("nbclient")

TUTORIALS = Path(__file__).resolve().parents[2] / "docs" / "tutorials"
NOTEBOOKS = sorted(p for p in TUTORIALS.glob("*.md") if p.name != "index.md")


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
    client = nbclient.NotebookClient(nb, timeout=180, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code and all(c.get("execution_count") for c in code)
    errors = [o for c in code for o in c.outputs if o.output_type == "error"]
    assert errors == []
