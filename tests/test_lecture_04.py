"""Lecture 4 (emitters, lifetimes and rendering): what the notebook must cover, read from the file.

``tests/test_lectures.py`` checks the structure every lecture shares and
``tests/test_notebooks.py`` executes it.
"""

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
