"""Lectures 1 and 2 are committed clean.

``tests/test_notebooks.py`` executes them (with every lecture) in a fresh
Jupyter kernel, from the ``lectures/`` folder as working directory, and checks
that each embeds an animation player.
"""

from pathlib import Path

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
