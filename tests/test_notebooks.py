"""The example notebook of the docs runs in a real Jupyter kernel and shows what the docs say it shows.

``docs/notebooks/first_decomposition.ipynb`` is executed by nbclient in a Python kernel (ipykernel,
of the ``dev`` extra that ``.ci/setup`` installs) that imports this checkout's hht3d: every cell
must run without error, and the outputs must hold the HTML summaries of the surface and the
result, the viewer in its frame and the figure.
"""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path

import pytest

import hht3d

NOTEBOOK = Path(__file__).resolve().parents[1] / "docs" / "notebooks" / "first_decomposition.ipynb"
#: Seconds a cell may take (the whole notebook takes about 5 s here).
CELL_TIMEOUT = 300

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(
        importlib.util.find_spec("ipykernel") is None or importlib.util.find_spec("nbclient") is None,
        reason="no Jupyter kernel: ipykernel and nbclient come with the dev extra (.ci/setup installs it)",
    ),
]


def _executed(tmp_path, monkeypatch):
    import nbformat
    from nbclient import NotebookClient

    # The kernel is a new process: it must import the hht3d under test, not another installed copy.
    package_root = str(Path(hht3d.__file__).resolve().parents[1])
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(p for p in (package_root, os.environ.get("PYTHONPATH")) if p))
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    client = NotebookClient(
        notebook, kernel_name="python3", timeout=CELL_TIMEOUT, resources={"metadata": {"path": str(tmp_path)}}
    )
    client.execute()  # raises CellExecutionError on the first cell that fails
    return [cell for cell in notebook.cells if cell.cell_type == "code"]


def test_the_example_notebook_runs_and_shows_the_summaries_the_viewer_and_a_figure(tmp_path, monkeypatch):
    cells = _executed(tmp_path, monkeypatch)
    outputs = [output for cell in cells for output in cell.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    assert all(cell.execution_count for cell in cells), "a cell did not run"
    html = [o.data["text/html"] for o in outputs if "text/html" in o.get("data", {})]
    assert any(h.startswith("<div") and "<b>Surface: spot</b>" in h and ">boundary loops<" in h for h in html)
    summary = next(h for h in html if "<b>HHTResult: spot</b>" in h)
    assert ">energy share<" in summary and ">3<" in summary and ">residue<" in summary
    viewer = next(h for h in html if h.startswith("<iframe srcdoc="))
    assert "height:500px" in viewer and "plotly" in viewer
    printed = "".join(o.text for o in outputs if o.output_type == "stream")
    assert printed.startswith("HHTResult('spot': 3 IMFs of 2,930 vertices, shares ")
    assert [o for o in cells[-1].outputs if "image/png" in o.get("data", {})], "the figure is not drawn"
