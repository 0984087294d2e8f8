"""Lectures 1 and 2 run top to bottom in a fresh Jupyter kernel and are committed clean.

Each notebook is executed with nbclient and a real ``python3`` kernel, from the
``lectures/`` folder as working directory (so relative links and files resolve
as they do for a student). Any cell that raises fails the test and names the
cell. The notebooks are executed in memory; the files on disk are not touched.
"""

import time
from pathlib import Path

import nbclient
import nbformat
import pytest

LECTURES = Path(__file__).resolve().parents[1] / "lectures"
NOTEBOOKS = ["01_state_and_steppers.ipynb", "02_forces.ipynb"]


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_lecture_is_committed_without_outputs(name):
    """The notebook file holds no outputs and no execution counts (nbformat v4, python3 kernel)."""
    nb = nbformat.read(LECTURES / name, as_version=4)
    nbformat.validate(nb)
    assert nb.nbformat == 4
    assert nb.metadata["kernelspec"]["name"] == "python3"
    for index, cell in enumerate(nb.cells):
        if cell.cell_type == "code":
            assert cell.outputs == [], f"{name}: cell {index} has outputs"
            assert cell.execution_count is None, f"{name}: cell {index} has an execution count"


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_lecture_runs_in_a_fresh_kernel(name):
    """Every cell of the lecture executes without an error in a new python3 kernel."""
    nb = nbformat.read(LECTURES / name, as_version=4)
    client = nbclient.NotebookClient(
        nb, timeout=180, kernel_name="python3", resources={"metadata": {"path": str(LECTURES)}}
    )
    start = time.perf_counter()
    try:
        client.execute()
    except nbclient.exceptions.CellExecutionError as error:
        pytest.fail(f"{name} failed to run:\n{error}")
    elapsed = time.perf_counter() - start
    errors = [
        (index, output.get("ename"))
        for index, cell in enumerate(nb.cells)
        if cell.cell_type == "code"
        for output in cell.outputs
        if output.output_type == "error"
    ]
    assert errors == [], f"{name}: cells with errors {errors}"
    # at least one animation player (HTML with its JavaScript) is embedded: the lecture's motion
    players = [
        o for c in nb.cells if c.cell_type == "code" for o in c.outputs
        if "<script" in o.get("data", {}).get("text/html", "")
    ]
    assert players, f"{name}: no embedded animation player"
    print(f"{name}: executed in {elapsed:.1f} s")
