"""Every notebook in notebooks/ runs from top to bottom (working directory notebooks/) without an error.

Notebooks assert their own results in their cells; EXPECTED lists text that must appear in a notebook's output.
"""
from __future__ import annotations

import pytest

from conftest import PROJECT

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

NOTEBOOKS = sorted((PROJECT / "notebooks").glob("*.ipynb"))
EXPECTED = {"02_fitting.ipynb": ("check grid", "fitted.tir"),
            "06_fmu.ipynb": ("fmpy validate: no problems", "time in the air 0.000 s")}


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_executes(path):
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(path.parent)}})
    client.execute()
    text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []))
    for expected in EXPECTED.get(path.name, ()):
        assert expected in text, f"{path.name}: output lacks {expected!r}"
