"""Lecture 3 (collisions): structure of the committed notebook, without executing it.

``tests/test_notebooks.py`` runs every lecture in a fresh kernel; these checks
are the cheap ones: the file is clean, opens with its title and goals, closes
with the exercise link, and embeds an animation.
"""

import re
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[1]
LECTURES = ROOT / "lectures"
PATH = LECTURES / "03_collisions.ipynb"


@pytest.fixture(scope="module")
def nb():
    return nbformat.read(PATH, as_version=4)


def code_cells(nb):
    return [cell for cell in nb.cells if cell.cell_type == "code"]


def test_notebook_is_valid_nbformat_4_for_python3(nb):
    """The file validates as nbformat 4 and names the python3 kernel."""
    nbformat.validate(nb)
    assert nb.nbformat == 4
    assert nb.metadata["kernelspec"]["name"] == "python3"
    assert nb.metadata["kernelspec"]["language"] == "python"


def test_notebook_is_committed_clean(nb):
    """No code cell carries outputs or an execution count, and every cell has an id."""
    for index, cell in enumerate(code_cells(nb)):
        assert cell.outputs == [], f"code cell {index} has outputs"
        assert cell.execution_count is None, f"code cell {index} has an execution count"
    ids = [cell.get("id") for cell in nb.cells]
    assert all(ids) and len(set(ids)) == len(ids), "every cell has a unique id"


def test_first_cell_is_the_title_with_the_goals(nb):
    """The first cell is the '# Lecture 3' title followed by a numbered 'you will be able to' list."""
    first = nb.cells[0]
    assert first.cell_type == "markdown"
    assert re.match(r"# Lecture 3 · Collisions\b", first.source)
    assert "you will be able to" in first.source
    goals = re.findall(r"^\d+\. ", first.source, flags=re.MULTILINE)
    assert len(goals) >= 3, "at least three numbered goals"


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


def test_last_cell_links_the_exercise_that_exists(nb):
    """The closing markdown cell has a summary, questions and a relative link to an existing exercise."""
    last = nb.cells[-1]
    assert last.cell_type == "markdown"
    assert "## Summary" in last.source and "## Questions to think about" in last.source
    links = re.findall(r"\]\((\.\./exercises/[^)]+\.ipynb)\)", last.source)
    assert "../exercises/01_integrator_order.ipynb" in links
    for link in links:
        assert (LECTURES / link).resolve().is_file(), f"linked exercise {link} does not exist"


def test_a_code_cell_embeds_an_animation(nb):
    """At least one code cell builds an animation and shows it as an HTML/JS player."""
    players = [cell.source for cell in code_cells(nb)
               if "render.animate(" in cell.source and "render.to_html(" in cell.source]
    assert players, "no cell with render.animate(...) and render.to_html(...)"


def test_code_cells_are_short(nb):
    """Code cells stay short enough to read next to their prose (at most 15 lines)."""
    long = [(index, len(cell.source.splitlines())) for index, cell in enumerate(nb.cells)
            if cell.cell_type == "code" and len(cell.source.splitlines()) > 15]
    assert long == [], f"cells too long (index, lines): {long}"
