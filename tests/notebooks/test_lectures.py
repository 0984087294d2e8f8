"""Every lecture's committed notebook: clean, titled, closing with questions and its exercises.

These checks read the files only; ``tests/notebooks/test_notebooks.py`` executes every
lecture in a fresh kernel (and checks its animation player) and
``tests/notebooks/test_lecture_claims.py`` checks the numbers it prints. ``COVERS``
below says what each lecture must cover: the topics of its section titles and
the library names its code uses (so that a lecture teaches with the library
rather than beside it).
"""

import re
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[2]
LECTURES = sorted((ROOT / "lectures").glob("[0-9][0-9]_*.ipynb"))

# the exercises each lecture's closing cell must link (the matching exercise, or the nearest one)
EXERCISES = {
    "01": ["01_integrator_order"],
    "02": ["02_stiffness"],
    "03": ["07_contact", "01_integrator_order"],
    "04": ["00_warmup"],
    "05": ["00_warmup"],
    "06": ["03_provot"],
    "07": ["02_stiffness", "06_implicit_step", "03_provot", "04_discretization"],
    "08": ["05_xpbd", "03_provot"],
    "09": ["03_provot"],
}
MAX_CODE_LINES = 20

# per lecture: words its section titles contain, and names its code cells use
COVERS = {
    "01": (("state vector", "euler", "midpoint", "order", "energy", "animation"),
           ("ParticleSystem(", "integrate(", "convergence_study(", "fit_order(", "harmonic_oscillator(")),
    "02": (("force", "gravity", "damping", "fields", "n-body", "lennard-jones", "buckets", "periodic"),
           ("Gravity(", "Damping(", "NBodyGravity(", "LennardJones.from_epsilon_sigma(", "cell_pairs(",
            "all_pairs(", "Langevin(", "block_average(")),
    "03": (("detecting", "normal", "response", "overshooting", "animation", "summary"),
           ('"project"', '"backtrack"', "bounce_study(", "0.8")),
    "04": (("births", "reeves", "initial", "stagger", "lifetimes", "motion blur", "systems of particle systems",
            "grass", "summary"),
           ("carry=False", "floor(rate * t", "rate_spread=", "Point(", "Disk(", "SphereSurface(", "Cone(",
            "ParticleEmitter(", "ColorRamp(", 'when="death"', "blur=")),
    "05": (("neighbours", "three rules", "bucket grid", "control forces", "crowds"),
           ("Boids(", "Flock(", "polarization(", "spread(", "cell_pairs", "all_pairs")),
    "06": (("string", "hair", "cloth", "pinned", "three kinds of forces"),
           ("Springs(", "Bending(", "string(", "hair(", "cloth(", "reaction_forces(", "relax(")),
    "07": (("stiffness", "provot", "implicit", "discretization", "sphere"),
           ("stability_study(", "provot_study(", "BaraffWitkin", "Prefactored", "discretization_study(",
            "Collider(")),
    "08": (("rigid constraints", "position-based", "xpbd", "substeps", "stiff cloth"),
           ("xpbd_project(", "small_steps_study(", "stiffness_study(", "pendulum_period(", "Prefactored")),
    "09": (("surface", "particle self-collision", "thickness", "roller", "cost", "step", "fold"),
           ("TriangleMesh", "intersections(", "orientation(", "box_pairs(", "ClothCollisions", "Cylinder(",
            "MovingSurface(")),
}


@pytest.fixture(params=LECTURES, ids=[p.name for p in LECTURES])
def lecture(request):
    return request.param, nbformat.read(request.param, as_version=4)


def test_the_series_is_complete():
    """The lectures are numbered 01, 02, ... without gaps, each with its exercise links and coverage listed."""
    numbers = [p.name[:2] for p in LECTURES]
    assert numbers == [f"{k:02d}" for k in range(1, len(LECTURES) + 1)]
    assert numbers == sorted(EXERCISES) == sorted(COVERS)


def test_sections_cover_the_topics(lecture):
    """The section titles ('## ...') name every topic of the lecture, and a summary or closing questions."""
    path, nb = lecture
    titles = " ".join(line.lower() for cell in nb.cells if cell.cell_type == "markdown"
                      for line in cell.source.splitlines() if line.startswith("## "))
    topics, _ = COVERS[path.name[:2]]
    missing = [topic for topic in topics if topic not in titles]
    assert missing == [], f"{path.name}: no section about {missing}"
    assert "questions to think about" in titles


def test_teaches_with_the_library(lecture):
    """The code cells use the library functions and options the lecture is about."""
    path, nb = lecture
    source = "\n".join(cell.source for cell in nb.cells if cell.cell_type == "code")
    _, names = COVERS[path.name[:2]]
    missing = [name for name in names if name not in source]
    assert missing == [], f"{path.name}: the code never uses {missing}"


def test_valid_and_committed_clean(lecture):
    """nbformat 4 for the python3 kernel; no outputs, no execution counts; unique cell ids."""
    path, nb = lecture
    nbformat.validate(nb)
    assert nb.nbformat == 4 and nb.metadata["kernelspec"]["name"] == "python3"
    code = [cell for cell in nb.cells if cell.cell_type == "code"]
    assert code, "a lecture computes what it claims"
    dirty = [k for k, cell in enumerate(nb.cells) if cell.cell_type == "code"
             and (cell.outputs or cell.execution_count is not None)]
    assert dirty == [], f"{path.name}: cells with outputs {dirty}"
    ids = [cell.get("id") for cell in nb.cells]
    assert all(ids) and len(set(ids)) == len(ids)


def test_opens_with_its_title_and_goals(lecture):
    """The first cell is '# Lecture N · Topic' and says what the reader will be able to do (a list)."""
    path, nb = lecture
    first = nb.cells[0]
    assert first.cell_type == "markdown"
    assert re.match(rf"# Lecture {int(path.name[:2])} · \S", first.source), first.source.splitlines()[0]
    head, _, goals = first.source.partition("you will be able to")
    assert goals, "the first cell says what the reader will be able to do"
    assert len(re.findall(r"^\s*(?:\d+\.|[*-]) ", goals, flags=re.M)) >= 3


def test_closes_with_questions_and_links_its_exercises(lecture):
    """The last cell is markdown with questions to think about and relative links to existing exercises."""
    path, nb = lecture
    last = nb.cells[-1]
    assert last.cell_type == "markdown" and "Questions to think about" in last.source
    links = re.findall(r"\]\((\.\./exercises/[^)]+\.ipynb)\)", last.source)
    for name in EXERCISES[path.name[:2]]:
        assert f"../exercises/{name}.ipynb" in links, f"{path.name} does not link {name}"
    for link in links:
        assert (path.parent / link).resolve().is_file(), f"{path.name}: {link} does not exist"


def test_code_cells_are_short(lecture):
    """Code cells stay short enough to read beside their prose."""
    path, nb = lecture
    long = [(k, len(cell.source.splitlines())) for k, cell in enumerate(nb.cells)
            if cell.cell_type == "code" and len(cell.source.splitlines()) > MAX_CODE_LINES]
    assert long == [], f"{path.name}: (cell, lines) {long}"
