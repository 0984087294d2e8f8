"""Lecture 3 (collisions): what the notebook must cover, read from the file.

``tests/test_lectures.py`` checks the structure every lecture shares and
``tests/test_notebooks.py`` executes it.
"""

from pathlib import Path

import nbformat
import pytest

PATH = Path(__file__).resolve().parents[1] / "lectures" / "03_collisions.ipynb"


@pytest.fixture(scope="module")
def nb():
    return nbformat.read(PATH, as_version=4)


def code_cells(nb):
    return [cell for cell in nb.cells if cell.cell_type == "code"]


def test_sections_cover_the_slides_topics(nb):
    """Section titles name detection, the normal, the response, overshooting and the animations."""
    titles = " ".join(line for cell in nb.cells if cell.cell_type == "markdown"
                      for line in cell.source.splitlines() if line.startswith("## ")).lower()
    for topic in ("detecting", "normal", "response", "overshooting", "animation", "summary", "questions"):
        assert topic in titles, f"no section about {topic!r}"


def test_both_overshooting_fixes_are_run_side_by_side(nb):
    """Code cells use both Collider methods and the bounce study that plots them."""
    source = "\n".join(cell.source for cell in code_cells(nb))
    assert '"project"' in source and '"backtrack"' in source
    assert "bounce_study(" in source and "0.8" in source
