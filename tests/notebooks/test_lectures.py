"""Every lecture's committed notebook: clean, titled, closing with questions and its exercises.

These checks read the files only; ``tests/notebooks/test_notebooks.py`` executes every
lecture in a fresh kernel (and checks its animation player) and
``tests/notebooks/test_lecture_claims.py`` checks the numbers it prints. ``COVERS``
below says what each lecture must cover: the topics of its section titles and
the library names its code uses (so that a lecture teaches with the library
rather than beside it).

Appendices (``lectures/A1_topic.ipynb``, ...) hold sections that go beyond a lecture
(a reference comparison, the memory traffic of a step, exact arithmetic). Each is
titled ``# Appendix A1 · Topic``, linked from the lecture it extends (``APPENDICES``)
and links back to it, covers what ``APPENDIX_COVERS`` lists and closes with
questions; the notebook tests execute it and the course site publishes it.
"""

import re
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[2]
LECTURES = sorted((ROOT / "lectures").glob("[0-9][0-9]_*.ipynb"))
APPENDIX_FILES = sorted((ROOT / "lectures").glob("A[0-9]_*.ipynb"))

# the lecture each appendix extends: the lecture links it, and it links the lecture back
APPENDICES = {
    "A1_lennard_jones_liquid": "02_forces",
    "A2_memory_traffic": "07_stiffness_provot_implicit",
    "A3_exact_predicates": "09_cloth_collisions",
}

# per appendix: words its section titles contain, and names its code cells use
APPENDIX_COVERS = {
    "A1": (("periodic", "thermostats", "tail corrections", "error bars"),
           ("LennardJones.from_epsilon_sigma(", "cell_pairs(", "Langevin(", "Berendsen(", "block_average(")),
    "A2": (("spring loop",), ("Springs(", "njit(", "cloth(")),
    "A3": (("exact signs",), ("orientation(",)),
}

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
    "01": (("state vector", "euler", "midpoint", "order", "energy", "stability", "animation"),
           ("ParticleSystem(", "integrate(", "convergence_study(", "fit_order(", "harmonic_oscillator(",
            "step_doubling(", '"implicit_euler"')),
    "02": (("force", "gravity", "damping", "fields", "n-body", "lennard-jones", "buckets"),
           ("Gravity(", "Damping(", "NBodyGravity(", "LennardJones.from_epsilon_sigma(", "cell_pairs(",
            "all_pairs(", '"implicit_euler"')),
    "03": (("detecting", "normal", "response", "overshooting", "animation", "summary"),
           ('"project"', '"backtrack"', "bounce_study(", "0.8", "BallContacts(", "rest_speed=")),
    "04": (("births", "reeves", "initial", "stagger", "lifetimes", "motion blur", "systems of particle systems",
            "grass", "summary"),
           ("carry=False", "floor(rate * t", "rate_spread=", "Point(", "Disk(", "SphereSurface(", "Cone(",
            "ParticleEmitter(", "ColorRamp(", 'when="death"', "blur=")),
    "05": (("neighbours", "three rules", "bucket grid", "control forces", "crowds"),
           ("Boids(", "Flock(", "polarization(", "spread(", "cell_pairs", "all_pairs")),
    "06": (("string", "hair", "cloth", "pinned", "three kinds of forces"),
           ("Springs(", "Bending(", "string(", "hair(", "cloth(", "reaction_forces(", "relax(", "SurfaceWind(")),
    "07": (("stiffness", "provot", "implicit", "discretization", "sphere"),
           ("stability_study(", "provot_study(", "BaraffWitkin", "Prefactored", "discretization_study(",
            "Collider(", "clamp=False")),
    "08": (("rigid constraints", "position-based", "xpbd", "substeps", "stiff cloth"),
           ("xpbd_project(", "small_steps_study(", "stiffness_study(", "pendulum_period(", "Prefactored",
            "corrected=True")),
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


@pytest.fixture(params=APPENDIX_FILES, ids=[p.name for p in APPENDIX_FILES])
def appendix(request):
    return request.param, nbformat.read(request.param, as_version=4)


def test_the_appendices_are_listed_and_numbered():
    """The appendices are A1, A2, ... without gaps, each listed with its lecture and its coverage."""
    assert [p.stem for p in APPENDIX_FILES] == sorted(APPENDICES)
    assert [p.name[:2] for p in APPENDIX_FILES] == [f"A{k}" for k in range(1, len(APPENDIX_FILES) + 1)]
    assert sorted(APPENDIX_COVERS) == [p.name[:2] for p in APPENDIX_FILES]
    assert set(APPENDICES.values()) <= {p.stem for p in LECTURES}


def test_an_appendix_opens_with_its_title_and_links_its_lecture_both_ways(appendix):
    """The first cell is '# Appendix An · Topic', says what the reader will be able to do, and links the lecture
    it extends; that lecture links the appendix, and the appendix's last cell links the lecture back."""
    path, nb = appendix
    lecture = APPENDICES[path.stem]
    first = nb.cells[0]
    assert first.cell_type == "markdown"
    assert re.match(rf"# Appendix {path.name[:2]} · \S", first.source), first.source.splitlines()[0]
    _, _, goals = first.source.partition("you will be able to")
    assert len(re.findall(r"^\s*(?:\d+\.|[*-]) ", goals, flags=re.M)) >= 3
    assert f"]({lecture}.ipynb)" in first.source and f"]({lecture}.ipynb)" in nb.cells[-1].source
    text = "".join(cell.source for cell in nbformat.read(ROOT / "lectures" / f"{lecture}.ipynb", as_version=4).cells
                   if cell.cell_type == "markdown")
    assert f"]({path.name})" in text, f"{lecture} does not link {path.name}"


def test_an_appendix_covers_its_topics_and_closes_with_questions(appendix):
    """Section titles name the appendix's topics and a summary; code uses its library names; the last cell asks
    questions; committed without outputs."""
    path, nb = appendix
    nbformat.validate(nb)
    titles = " ".join(line.lower() for cell in nb.cells if cell.cell_type == "markdown"
                      for line in cell.source.splitlines() if line.startswith("## "))
    topics, names = APPENDIX_COVERS[path.name[:2]]
    assert [t for t in topics if t not in titles] == [] and "summary" in titles
    source = "\n".join(cell.source for cell in nb.cells if cell.cell_type == "code")
    assert [n for n in names if n not in source] == []
    assert nb.cells[-1].cell_type == "markdown" and "Questions to think about" in nb.cells[-1].source
    assert all(not cell.outputs and cell.execution_count is None for cell in nb.cells if cell.cell_type == "code")
