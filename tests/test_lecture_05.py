"""Lecture 5 (flocks): what the notebook must cover, read from the file (structure: ``test_lectures.py``)."""

from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[1]
PATH = ROOT / "lectures" / "05_flocks.ipynb"


@pytest.fixture(scope="module")
def nb():
    return nbformat.read(PATH, as_version=4)


def test_measures_each_rule_with_the_library(nb):
    """The lecture uses the flocking library and the three measurements, and times both neighbour searches."""
    code = "\n".join(cell.source for cell in nb.cells if cell.cell_type == "code")
    for name in ("Boids(", "Flock(", "polarization(", "spread(", "cell_pairs", "all_pairs"):
        assert name in code, name
