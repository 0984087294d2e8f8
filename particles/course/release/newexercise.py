"""``particles new-exercise NN_topic``: a new exercise from a template that already passes.

It writes the two files an exercise is made of (see the README's "For
instructors"):

* ``solutions/NN_topic.ipynb``, a master: a title, a short statement, one
  function between ``### BEGIN SOLUTION`` / ``### END SOLUTION``, a cell
  that tries it, a written question whose answer sits between the same
  markers, an instructor-only check and the public check
  ``particles.check("NN_topic")`` as the last cell;
* ``tests/exercises/test_NN_topic.py``: ``EXERCISE``, ``FORBIDDEN``, one
  public and one hidden test with points, calling the function with
  ``student.call`` and judging it with ``expect_float`` against a reference
  computed in the grader (the hidden one with the ``rng`` fixture).

As written, the exercise asks for the kinetic energy of a particle system:
the master scores full marks, the stub that ``particles release`` makes of
it scores zero, so the instructor starts from a working pipeline and
replaces the statement, the function and the tests with the exercise's own.
Cell ids and texts depend on the name only: the output is reproducible.
"""

import re
from pathlib import Path

import nbformat

from ..paths import exercise_tests

__all__ = ["NAME", "new_exercise", "master_notebook", "tests_text"]

NAME = re.compile(r"(?P<number>\d{2})_(?P<topic>[a-z][a-z0-9]*(?:_[a-z0-9]+)*)")
"""What an exercise name looks like: two digits, an underscore, a lower-case topic (``05_damped_springs``)."""


def _title(name):
    match = NAME.fullmatch(name)
    return match["number"], match["topic"].replace("_", " ").capitalize()


_STATEMENT = """# Exercise {number} — {title}

The kinetic energy of $n$ particles with masses $m_i$ and velocities $\\mathbf v_i$ is

$$K = \\tfrac12 \\sum_{{i=1}}^{{n}} m_i\\, \\lVert \\mathbf v_i \\rVert^2 .$$

A state $X$ of shape `(n, 2, d)` holds the positions in `X[:, 0]` and the velocities in `X[:, 1]`.
Write `kinetic_energy(X, m)` with NumPy, without a loop over the particles, and without modifying `X`.

**How your work is graded.** The autograder runs the *definitions* of this notebook in a separate
process and calls your function on inputs of its own, some of them random. Run
`particles.check("{name}")` at the end to see the public tests."""

_INSTRUCTOR_NOTE = """### INSTRUCTOR ONLY
Written by `particles new-exercise {name}`. This template exercise passes its own tests: replace the
statement, the function and `tests/exercises/test_{name}.py` with your exercise, then run
`particles release` and `pytest tests/exercises/test_{name}.py` (the master must score full marks).
This cell is dropped from the student version."""

_IMPORTS = """import numpy as np

import particles"""

_FUNCTION = '''def kinetic_energy(X, m):
    """Total kinetic energy of n particles, in joules.

    Parameters
    ----------
    X : ndarray, shape (n, 2, d)
        State: X[:, 0] positions (m), X[:, 1] velocities (m/s). Not modified.
    m : ndarray, shape (n,)
        Masses, in kg.

    Returns
    -------
    float
        K = 1/2 sum_i m_i |v_i|^2.
    """
    ### BEGIN SOLUTION
    v = np.asarray(X, dtype=float)[:, 1]
    return 0.5 * float(np.sum(np.asarray(m, dtype=float) * np.sum(v**2, axis=1)))
    ### END SOLUTION'''

_TRY = """Try it: a particle of 2 kg at rest and one of 1 kg moving at (3, 4) m/s carry $K = 12.5$ J."""

_EXAMPLE = """X = np.zeros((2, 2, 2))
X[1, 1] = [3.0, 4.0]
kinetic_energy(X, np.array([2.0, 1.0]))"""

_QUESTION = """**Question 1.** Doubling every velocity multiplies $K$ by which factor?

### BEGIN SOLUTION
$K$ is quadratic in the velocities: doubling them multiplies it by 4.
### END SOLUTION

**Question 2.** And doubling every mass?

### BEGIN SOLUTION
$K$ is linear in the masses: doubling them multiplies it by 2.
### END SOLUTION"""

_MASTER_CHECK = """### INSTRUCTOR ONLY
# Sanity check of the master; dropped from the student version.
rng = np.random.default_rng(1)
X_r, m_r = rng.normal(size=(5, 2, 3)), rng.uniform(0.5, 2.0, 5)
assert np.isclose(kinetic_energy(X_r, m_r), 0.5 * sum(m_r[i] * X_r[i, 1] @ X_r[i, 1] for i in range(5)))
print("master agrees with the reference")"""

_CHECK_TEXT = """## Check your work

`particles.check` runs the public tests of this exercise on the code you have run in this notebook, in a
separate process, and says what is wrong. The autograder adds hidden tests with random parameters."""

_TESTS = '''"""Autograder tests of exercise {name}: {title}.

Written by ``particles new-exercise {name}`` as a starting point that passes: replace the tests with
the exercise's own. Public tests use inputs a student can check by hand; hidden tests draw theirs from
the grading seed (fixture ``rng``). Every expected value is computed here, in the grader, never in the
student's process. To show a curve in the feedback, attach its data before the check (fixture
``feedback``): ``feedback.curve(title, xlabel, ylabel, [{{"label": "yours", "x": x, "y": got}},
{{"label": "reference", "x": x, "y": expected}}])``.
"""

import numpy as np
import pytest

from particles.course.grading.expect import expect_float

EXERCISE = "{name}"
FORBIDDEN = {{
    "particles.system.ParticleSystem": "its kinetic_energy() is the sum you are asked to write",
}}


def _reference(X, m):
    """K = 1/2 sum_i m_i |v_i|^2, computed in the grader."""
    v = np.asarray(X, dtype=float)[:, 1]
    return 0.5 * float(np.sum(np.asarray(m) * np.sum(v**2, axis=1)))


@pytest.mark.points(1)
def test_kinetic_energy_two_particles(student):
    """kinetic_energy of 2 kg at rest and 1 kg at (3, 4) m/s is 12.5 J, X unchanged."""
    X = np.zeros((2, 2, 2))
    X[1, 1] = [3.0, 4.0]
    got = student.call("kinetic_energy", X, np.array([2.0, 1.0]), check_inputs=True)
    expect_float(got, 12.5, "kinetic_energy(X, m=[2, 1]) with v = [(0, 0), (3, 4)] m/s")


@pytest.mark.points(2)
@pytest.mark.hidden
def test_kinetic_energy_random(student, rng):
    """kinetic_energy matches the reference on random states in 2D and 3D."""
    for d in (2, 3):
        n = int(rng.integers(1, 30))
        X, m = rng.normal(size=(n, 2, d)), rng.uniform(0.1, 5.0, n)
        expect_float(student.call("kinetic_energy", X, m, check_inputs=True), _reference(X, m),
                     f"kinetic_energy(X of shape {{X.shape}}, m) on random particles", rtol=1e-10)
'''


def master_notebook(name):
    """The template master ``solutions/NN_topic.ipynb`` of exercise `name`, as a notebook.

    Raises
    ------
    ValueError
        When `name` is not of the form ``NN_topic`` (see :data:`NAME`).
    """
    _check_name(name)
    number, title = _title(name)
    fields = {"name": name, "number": number, "title": title}
    md, code = nbformat.v4.new_markdown_cell, nbformat.v4.new_code_cell
    cells = [md(_STATEMENT.format(**fields)), md(_INSTRUCTOR_NOTE.format(**fields)), code(_IMPORTS),
             code(_FUNCTION), md(_TRY), code(_EXAMPLE), md(_QUESTION), code(_MASTER_CHECK), md(_CHECK_TEXT),
             code(f'particles.check("{name}")')]
    for k, cell in enumerate(cells):
        cell["id"] = f"cell-{k}"
    notebook = nbformat.v4.new_notebook(cells=cells)
    notebook.metadata = {"kernelspec": {"name": "python3", "display_name": "Python 3", "language": "python"},
                         "language_info": {"name": "python"}}
    return notebook


def tests_text(name):
    """The text of the template's ``tests/exercises/test_NN_topic.py`` for exercise `name`.

    Raises
    ------
    ValueError
        When `name` is not of the form ``NN_topic``.
    """
    _check_name(name)
    return _TESTS.format(name=name, title=_title(name)[1])


def _check_name(name):
    if not isinstance(name, str) or not NAME.fullmatch(name):
        raise ValueError(f"exercise name {name!r} is malformed: expected NN_topic, two digits, an underscore and a "
                         "lower-case topic (letters, digits, underscores), e.g. 05_damped_springs")


def new_exercise(root, name):
    """Write the template master and test module of a new exercise into the course folder `root`.

    Parameters
    ----------
    root : path
        The course folder (``solutions/`` and ``tests/exercises/`` are made
        when missing).
    name : str
        ``NN_topic``: two digits and a lower-case topic.

    Returns
    -------
    list of Path
        ``solutions/NN_topic.ipynb`` and ``tests/exercises/test_NN_topic.py``.

    Raises
    ------
    ValueError
        When `name` is malformed, or its number ``NN`` belongs to another
        exercise already.
    FileExistsError
        When either file exists (nothing is written then), naming them.
    """
    _check_name(name)
    root = Path(root)
    master = root / "solutions" / f"{name}.ipynb"
    tests = root / "tests" / "exercises" / f"test_{name}.py"
    there = [str(p.relative_to(root)) for p in (master, tests) if p.exists()]
    if there:
        raise FileExistsError(f"exercise {name} exists already: {', '.join(there)}; edit it or choose another name")
    number = name[:2]
    taken = sorted({p.stem for p in (root / "solutions").glob(f"{number}_*.ipynb")}
                   | {e for e in exercise_tests(root) if e.startswith(f"{number}_")})
    if taken:
        raise ValueError(f"exercise number {number} is taken by {', '.join(taken)}; choose another number")
    master.parent.mkdir(parents=True, exist_ok=True)
    tests.parent.mkdir(parents=True, exist_ok=True)
    text = nbformat.writes(master_notebook(name))
    master.write_text(text if text.endswith("\n") else text + "\n", encoding="utf-8")
    tests.write_text(tests_text(name), encoding="utf-8")
    return [master, tests]
