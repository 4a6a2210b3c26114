"""Every notebook in notebooks/ runs from top to bottom (working directory notebooks/) without an error.

Notebooks assert their own results in their cells; EXPECTED lists text that must appear in a notebook's output.

The kernel is ipykernel's built-in 'python3' spec for the interpreter running pytest (sys.executable), whether or
not a 'python3' kernel is registered with Jupyter: a registered spec could point at another Python without
mftyre. The project root is put on PYTHONPATH so the notebooks import this checkout even when it is not installed.
"""
from __future__ import annotations

import os

import pytest

from conftest import PROJECT

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")

NOTEBOOKS = sorted((PROJECT / "notebooks").glob("*.ipynb"))
EXPECTED = {"02_fitting.ipynb": ("check grid", "fitted.tir"),
            "04_gap_finder.ipynb": ("ACCEPTED", "shrink"),
            "06_fmu.ipynb": ("fmpy validate: no problems", "time in the air 0.000 s")}


def _kernel_manager():
    from jupyter_client.kernelspec import KernelSpecManager
    from jupyter_client.manager import KernelManager

    # no kernel directories: only the native ipykernel spec, launched with sys.executable
    return KernelManager(kernel_name="python3", kernel_spec_manager=KernelSpecManager(kernel_dirs=[]))


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_executes(path, monkeypatch):
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(PROJECT), os.environ.get("PYTHONPATH")])))
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(nb, km=_kernel_manager(), timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(path.parent)}})
    client.execute()  # raises CellExecutionError (with the cell and traceback) on any error
    text = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []))
    for expected in EXPECTED.get(path.name, ()):
        assert expected in text, f"{path.name}: output lacks {expected!r}"
    for cell in nb.cells:  # every cell that draws shows its figure (matplotlib.use("Agg") hid them in 07)
        if cell.cell_type == "code" and "plt.subplots" in cell.source:
            assert any("image/png" in o.get("data", {}) for o in cell.get("outputs", [])), \
                f"{path.name}: a cell draws a figure but shows none:\n{cell.source[:200]}"
