"""workflows/teach.py, the lesson: as a script, and as the notebook made from it, run top to bottom.

teach.py is the one text (jupytext's percent format: a script whose comments
are the notebook's markdown cells). teach.ipynb, for readers who open
notebooks, is generated from it without outputs; the first test keeps the
two from drifting apart, the second runs the notebook as a reader would.
"""

from __future__ import annotations

import subprocess
import sys

from conftest import ROOT

TEACH = ROOT / "workflows" / "teach.py"
NOTEBOOK = ROOT / "workflows" / "teach.ipynb"
REGENERATE = ".venv/bin/jupytext --to ipynb --set-kernel python3 workflows/teach.py"


def cells(nb):
    return [(cell.cell_type, cell.source, cell.metadata.get("tags", [])) for cell in nb.cells]


def test_the_notebook_is_teach_py_without_outputs():
    import jupytext
    import nbformat

    committed = nbformat.read(NOTEBOOK, as_version=4)
    assert cells(committed) == cells(jupytext.read(TEACH)), f"teach.ipynb is not teach.py: {REGENERATE}"
    code = [cell for cell in committed.cells if cell.cell_type == "code"]
    assert all(cell.outputs == [] and cell.execution_count is None for cell in code), f"outputs committed: {REGENERATE}"


def test_the_notebook_runs_top_to_bottom(tmp_path):
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.read(NOTEBOOK, as_version=4)
    at = next(k for k, cell in enumerate(nb.cells) if "parameters" in cell.metadata.get("tags", []))
    # papermill's convention: a cell after the one tagged "parameters" sets them anew
    nb.cells.insert(at + 1, nbformat.v4.new_code_cell(f"n, seed, output = 2000, 3, {str(tmp_path / 'out')!r}"))
    NotebookClient(nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": tmp_path}}).execute()
    outputs = [out for cell in nb.cells if cell.cell_type == "code" for out in cell.outputs]
    text = "".join(out.get("text", "") for out in outputs if out.output_type == "stream")
    assert "grew the lattice cluster: 2000 particles" in text and "What this shows" in text
    pictures = [out for out in outputs if "image/png" in out.get("data", {})]
    assert len(pictures) == 2  # the two clusters, inline
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["dimension.png", "lattice.png", "offlattice.png"]


def test_the_script_refuses_bad_input_in_one_line(tmp_path):
    run = subprocess.run([sys.executable, TEACH, "-n", "100", "-o", tmp_path / "out"], capture_output=True, text=True)
    assert run.returncode == 2 and run.stdout == ""
    assert run.stderr == "teach.py: -n: 100 is not in [2000, 1000000] (fewer leave no decade to fit)\n"
    assert not (tmp_path / "out").exists()
