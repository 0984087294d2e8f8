"""Lectures 6 and 7: committed without outputs, linking their exercises (``tests/test_notebooks.py`` runs them)."""

from pathlib import Path

import nbformat
import pytest

LECTURES = Path(__file__).resolve().parents[1] / "lectures"
NOTEBOOKS = ["06_mass_spring.ipynb", "07_stiffness_provot_implicit.ipynb"]


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_lecture_is_committed_clean(name):
    """A valid nbformat-4 notebook for the python3 kernel, with no outputs or execution counts."""
    nb = nbformat.read(LECTURES / name, as_version=4)
    nbformat.validate(nb)
    assert nb.nbformat == 4
    assert nb.metadata.kernelspec.name == "python3"
    code = [cell for cell in nb.cells if cell.cell_type == "code"]
    assert code, "a lecture has code cells"
    assert all(not cell.outputs and cell.execution_count is None for cell in code)


@pytest.mark.parametrize("name, links", [
    ("06_mass_spring.ipynb", ["../exercises/03_provot.ipynb"]),
    ("07_stiffness_provot_implicit.ipynb", ["../exercises/02_stiffness.ipynb", "../exercises/03_provot.ipynb",
                                            "../exercises/04_discretization.ipynb"]),
])
def test_lecture_links_its_exercises(name, links):
    """The closing cell points to the matching exercise notebooks by relative path."""
    nb = nbformat.read(LECTURES / name, as_version=4)
    last = nb.cells[-1]
    assert last.cell_type == "markdown"
    for link in links:
        assert f"]({link})" in last.source
