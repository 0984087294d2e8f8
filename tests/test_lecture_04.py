"""Lecture 4 (emitters, lifetimes and rendering): structure of the committed notebook, without running it.

``tests/test_notebooks.py`` executes every lecture in a fresh kernel. These are the cheap checks: the file is
clean nbformat 4, opens with its title and goals, measures what the slides claim with the library's emitters,
closes with a link to an existing exercise, and embeds an animation player.
"""

import re
from pathlib import Path

import nbformat
import pytest

LECTURES = Path(__file__).resolve().parents[1] / "lectures"
PATH = LECTURES / "04_emitters_and_rendering.ipynb"


@pytest.fixture(scope="module")
def nb():
    return nbformat.read(PATH, as_version=4)


def code_source(nb):
    return "\n".join(cell.source for cell in nb.cells if cell.cell_type == "code")


def test_valid_nbformat_4_for_the_python3_kernel(nb):
    """The file validates as nbformat 4 and names the python3 kernel."""
    nbformat.validate(nb)
    assert nb.nbformat == 4
    assert nb.metadata["kernelspec"] == {"name": "python3", "display_name": "Python 3", "language": "python"}


def test_committed_without_outputs_and_with_cell_ids(nb):
    """No code cell has outputs or an execution count; every cell has its own id."""
    for index, cell in enumerate(nb.cells):
        if cell.cell_type == "code":
            assert cell.outputs == [], f"code cell {index} has outputs"
            assert cell.execution_count is None, f"code cell {index} has an execution count"
    ids = [cell.get("id") for cell in nb.cells]
    assert all(ids) and len(set(ids)) == len(ids)


def test_opens_with_the_title_and_what_the_reader_will_be_able_to_do(nb):
    """The first cell is the '# Lecture 4 ·' title with a numbered list of at least four goals."""
    first = nb.cells[0]
    assert first.cell_type == "markdown"
    assert re.match(r"# Lecture 4 · Emitters", first.source)
    assert "you will be able to" in first.source
    assert len(re.findall(r"^\d+\. ", first.source, flags=re.MULTILINE)) >= 4


def test_sections_follow_the_slides(nb):
    """Section titles cover births, Reeves, initial states, staggering, lifetimes, rendering, hierarchies, grass."""
    titles = " ".join(line.lower() for cell in nb.cells if cell.cell_type == "markdown"
                      for line in cell.source.splitlines() if line.startswith("## "))
    for topic in ("births", "reeves", "initial", "stagger", "lifetimes", "motion blur", "systems of particle systems",
                  "grass", "summary", "questions"):
        assert topic in titles, f"no section about {topic!r}"


def test_the_measurements_use_the_library(nb):
    """The slide's t_last = t is compared with the exact emitter, and every shape, the burst and the blur are used."""
    source = code_source(nb)
    assert "carry=False" in source and "floor(rate * t" in source  # the literal rule against floor(rate t)
    assert "rate_spread=" in source  # Reeves' stochastic count
    for name in ("Point(", "Disk(", "SphereSurface(", "Cone(", "ParticleEmitter(", "ColorRamp("):
        assert name in source, f"{name} is not used"
    assert 'when="death"' in source and "blur=" in source


def test_closing_cell_links_an_existing_exercise(nb):
    """The last cell is markdown with a summary, questions and a relative link to 00_warmup, which exists."""
    last = nb.cells[-1]
    assert last.cell_type == "markdown"
    assert "## Summary" in last.source and "## Questions to think about" in last.source
    links = re.findall(r"\]\((\.\./exercises/[^)]+\.ipynb)\)", last.source)
    assert "../exercises/00_warmup.ipynb" in links
    for link in links:
        assert (LECTURES / link).resolve().is_file(), f"{link} does not exist"


def test_a_code_cell_builds_an_animation_player(nb):
    """Some code cell builds an animation with render.animate... and embeds it with render.to_html."""
    players = [cell.source for cell in nb.cells if cell.cell_type == "code"
               and "render.animate" in cell.source and "HTML(render.to_html(" in cell.source]
    assert players


def test_code_cells_are_short(nb):
    """No code cell is longer than 15 lines."""
    long = [(index, len(cell.source.splitlines())) for index, cell in enumerate(nb.cells)
            if cell.cell_type == "code" and len(cell.source.splitlines()) > 15]
    assert long == []
