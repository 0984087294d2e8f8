"""Lecture 5 (flocks): structure of the committed notebook, checked without executing it."""

import re
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[1]
PATH = ROOT / "lectures" / "05_flocks.ipynb"
EXERCISES = ["../exercises/00_warmup.ipynb"]


@pytest.fixture(scope="module")
def nb():
    return nbformat.read(PATH, as_version=4)


def test_valid_nbformat_4_with_python3_kernel(nb):
    """The notebook validates as nbformat 4 and names the python3 kernel."""
    nbformat.validate(nb)
    assert nb.nbformat == 4
    assert nb.metadata.kernelspec == {"name": "python3", "display_name": "Python 3", "language": "python"}


def test_committed_clean(nb):
    """No code cell carries outputs or an execution count, and every cell has an id."""
    code = [cell for cell in nb.cells if cell.cell_type == "code"]
    assert code
    assert [k for k, cell in enumerate(code) if cell.outputs or cell.execution_count is not None] == []
    ids = [cell.get("id") for cell in nb.cells]
    assert all(ids) and len(set(ids)) == len(ids)


def test_opens_with_title_and_goals(nb):
    """The first cell is the '# Lecture 5' title followed by the 'you will be able to' list."""
    first = nb.cells[0]
    assert first.cell_type == "markdown"
    assert re.match(r"# Lecture 5 · \S", first.source)
    goals = first.source.split("you will be able to", 1)
    assert len(goals) == 2, "the title cell says what the reader will be able to do"
    assert len(re.findall(r"^\s*(?:\d+\.|[*-]) ", goals[1], flags=re.M)) >= 3


def test_closes_with_summary_questions_and_exercise_link(nb):
    """The last cell has a Summary, questions, and links the exercise by a relative path that exists."""
    last = nb.cells[-1]
    assert last.cell_type == "markdown"
    assert "## Summary" in last.source and "## Questions to think about" in last.source
    for link in EXERCISES:
        assert f"]({link})" in last.source
        assert (PATH.parent / link).resolve().is_file(), link


def test_builds_an_animation(nb):
    """At least one code cell animates with particles.render and embeds it as HTML/JS."""
    sources = [cell.source for cell in nb.cells if cell.cell_type == "code"]
    assert any("render.animate(" in s and "to_html(" in s for s in sources)


def test_measures_each_rule_with_the_library(nb):
    """The lecture uses the flocking library and the three measurements, and times both neighbour searches."""
    code = "\n".join(cell.source for cell in nb.cells if cell.cell_type == "code")
    for name in ("Boids(", "Flock(", "polarization(", "spread(", "cell_pairs", "all_pairs"):
        assert name in code, name


def test_code_cells_are_short(nb):
    """Code cells stay short enough to read next to the prose (at most 15 lines)."""
    long = [k for k, cell in enumerate(nb.cells) if cell.cell_type == "code" and len(cell.source.splitlines()) > 15]
    assert long == []
