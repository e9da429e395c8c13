"""The tutorial notebook (examples/tutorial.ipynb) runs end to end: diagram graph,
two simulations, the panels, the inline replay, a live Meshcat run and a tiny sweep."""
from pathlib import Path

import nbformat
from nbclient import NotebookClient

NOTEBOOK = Path(__file__).resolve().parents[1] / "examples" / "tutorial.ipynb"


def test_tutorial_notebook_runs_end_to_end(tmp_path):
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    NotebookClient(notebook, timeout=600, kernel_name="python3",
                   resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = [output for cell in notebook.cells if cell.cell_type == "code"
               for output in cell.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    kinds = [kind for o in outputs for kind in o.get("data", {})]
    assert kinds.count("image/svg+xml") == 1                # the diagram graph
    assert kinds.count("image/png") == 3                    # panels a, b, e
    assert "text/markdown" in kinds                         # the sweep's summary
    text = "".join(o.get("text", "") for o in outputs)
    assert "dac          ok" in text and "model-based  ok" in text
    out = tmp_path / "tutorial_output"
    assert (out / "animation_dac.html").stat().st_size > 100_000
    assert (out / "sweep" / "summary.md").exists()
